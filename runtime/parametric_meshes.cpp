// Run-time tessellation of parametric clusters by distance, cached in GL buffers. See
// parametric_meshes.h.
#include "parametric_meshes.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "gl_program.h"
#include "parametric_shaders.h"
#include "tessellate.h"

namespace tw {

Primitive primitiveOf(const pkg::InstanceRecord& in, std::span<const glm::vec2> profile_points) {
  const float* p = in.params;
  const bool capped = (in.flags & pkg::kInstanceCapped) != 0;
  auto profile = [&] {
    std::vector<glm::vec2> points;
    if (in.profile_first <= profile_points.size() &&
        in.profile_count <= profile_points.size() - in.profile_first)
      points.assign(profile_points.begin() + in.profile_first,
                    profile_points.begin() + in.profile_first + in.profile_count);
    return points;
  };
  switch (static_cast<pkg::PrimitiveType>(in.type)) {
    case pkg::PrimitiveType::Cylinder: return Cylinder{p[0], p[1], capped};
    case pkg::PrimitiveType::Cone: return Cone{p[0], p[1], p[2], capped};
    case pkg::PrimitiveType::Sphere: return Sphere{p[0]};
    case pkg::PrimitiveType::TorusSegment: return TorusSegment{p[0], p[1], p[2]};
    case pkg::PrimitiveType::Box: return Box{glm::vec3(p[0], p[1], p[2])};
    case pkg::PrimitiveType::Extrusion: return Extrusion{profile(), p[0]};
    case pkg::PrimitiveType::Revolution: return Revolution{profile(), p[0]};
  }
  return Sphere{0.0f};  // unknown type (the view rejects it): tessellates to nothing
}

glm::dvec3 clusterAnchor(const pkg::ClusterRecord& c) {
  return glm::dvec3(c.center[0], c.center[1], c.center[2]);
}

void tessellateCluster(const PackageView& view, uint32_t cluster, float tolerance_m,
                       std::vector<ParametricVertex>& vertices, std::vector<uint32_t>& indices) {
  if (cluster >= view.clusters().size() ||
      view.clusters()[cluster].kind != static_cast<uint8_t>(pkg::ClusterKind::Parametric))
    throw std::out_of_range("tessellateCluster: cluster " + std::to_string(cluster) +
                            " is not a parametric cluster");
  const pkg::ClusterRecord& c = view.clusters()[cluster];
  const auto instances = view.instances();
  if (c.instance_first > instances.size() || c.instance_count > instances.size() - c.instance_first)
    throw std::out_of_range("tessellateCluster: cluster " + std::to_string(cluster) +
                            " instance range is outside the table");
  const glm::dvec3 anchor = clusterAnchor(c);
  TriangleMesh mesh;
  for (uint32_t i = c.instance_first; i < c.instance_first + c.instance_count; ++i) {
    const pkg::InstanceRecord& in = instances[i];
    mesh.positions.clear();
    mesh.normals.clear();
    mesh.indices.clear();
    tessellatePrimitive(primitiveOf(in, view.profilePoints()), tolerance_m, mesh);
    const glm::mat3 linear(in.linear[0], in.linear[1], in.linear[2], in.linear[3], in.linear[4],
                           in.linear[5], in.linear[6], in.linear[7], in.linear[8]);
    const glm::vec3 origin(glm::dvec3(in.origin[0], in.origin[1], in.origin[2]) - anchor);
    const uint32_t base = static_cast<uint32_t>(vertices.size());
    for (const glm::vec3& q : mesh.positions) vertices.push_back({origin + linear * q, in.object});
    for (uint32_t index : mesh.indices) indices.push_back(base + index);
  }
}

namespace {

using Clock = std::chrono::steady_clock;

struct CachedMesh {
  GLuint vertex_buffer = 0, index_buffer = 0;
  uint32_t index_count = 0;
  uint64_t bytes = 0;
  uint64_t last_used = 0;
};

uint64_t meshKey(uint32_t cluster, int bucket) { return uint64_t(cluster) * 8 + uint64_t(bucket); }

}  // namespace

struct ParametricMeshes::Impl {
  const PackageView* view = nullptr;
  ParametricMeshOptions options;
  GLuint program = 0, vertex_array = 0;
  std::unordered_map<uint64_t, CachedMesh> cache;
  uint64_t cached_bytes = 0;
  std::vector<ParametricVertex> vertices;  // build scratch
  std::vector<uint32_t> indices;

  ~Impl() {
    for (auto& [key, mesh] : cache) release(mesh);
    glDeleteVertexArrays(1, &vertex_array);
    glDeleteProgram(program);
  }
  void release(CachedMesh& mesh) {
    glDeleteBuffers(1, &mesh.vertex_buffer);
    glDeleteBuffers(1, &mesh.index_buffer);
    mesh.vertex_buffer = mesh.index_buffer = 0;
  }

  CachedMesh build(uint32_t cluster, int bucket) {
    vertices.clear();
    indices.clear();
    const double tolerance = options.fixed_tolerance_m > 0.0 ? options.fixed_tolerance_m
                                                             : bucketToleranceM(bucket);
    tessellateCluster(*view, cluster, static_cast<float>(tolerance), vertices, indices);
    CachedMesh mesh;
    mesh.index_count = static_cast<uint32_t>(indices.size());
    if (indices.empty()) return mesh;
    glCreateBuffers(1, &mesh.vertex_buffer);
    glNamedBufferStorage(mesh.vertex_buffer, GLsizeiptr(vertices.size() * sizeof(vertices[0])),
                         vertices.data(), 0);
    glCreateBuffers(1, &mesh.index_buffer);
    glNamedBufferStorage(mesh.index_buffer, GLsizeiptr(indices.size() * sizeof(indices[0])),
                         indices.data(), 0);
    mesh.bytes = vertices.size() * sizeof(vertices[0]) + indices.size() * sizeof(indices[0]);
    return mesh;
  }

  // Drops the least recently used meshes not used in `frame` until the cache fits its budget.
  void evict(uint64_t frame) {
    if (cached_bytes <= options.budget_bytes) return;
    std::vector<std::pair<uint64_t, uint64_t>> by_age;  // (last_used, key)
    for (const auto& [key, mesh] : cache)
      if (mesh.last_used < frame) by_age.push_back({mesh.last_used, key});
    std::sort(by_age.begin(), by_age.end());
    for (const auto& [used, key] : by_age) {
      if (cached_bytes <= options.budget_bytes) break;
      auto it = cache.find(key);
      cached_bytes -= it->second.bytes;
      release(it->second);
      cache.erase(it);
    }
  }
};

ParametricMeshes::ParametricMeshes(const PackageView& view, const ParametricMeshOptions& options)
    : impl_(std::make_unique<Impl>()) {
  impl_->view = &view;
  impl_->options = options;
  impl_->program = buildGlProgram({{GL_VERTEX_SHADER, gl::parametricMeshVertexShader()},
                                   {GL_FRAGMENT_SHADER, gl::parametricMeshFragmentShader()}},
                                  "ParametricMeshes: mesh");
  GLuint& vao = impl_->vertex_array;
  glCreateVertexArrays(1, &vao);
  glEnableVertexArrayAttrib(vao, 0);
  glVertexArrayAttribFormat(vao, 0, 3, GL_FLOAT, GL_FALSE, offsetof(ParametricVertex, position));
  glVertexArrayAttribBinding(vao, 0, 0);
  glEnableVertexArrayAttrib(vao, 1);
  glVertexArrayAttribIFormat(vao, 1, 1, GL_UNSIGNED_INT, offsetof(ParametricVertex, object));
  glVertexArrayAttribBinding(vao, 1, 0);
}

ParametricMeshes::~ParametricMeshes() = default;

double ParametricMeshes::bucketToleranceM(int bucket) {
  return kBaseToleranceM * std::pow(4.0, std::clamp(bucket, 0, kBucketCount - 1));
}

int ParametricMeshes::bucketFor(uint32_t cluster, const glm::dvec3& eye, double pixel_scale,
                                double near_m) const {
  const pkg::ClusterRecord& c = impl_->view->clusters()[cluster];
  const double distance =
      std::max(glm::length(clusterAnchor(c) - eye) - double(c.radius), std::max(near_m, 1e-6));
  // Metres one pixel spans at the cluster's nearest point, times the allowed error in pixels.
  const double allowed_m = impl_->options.tolerance_px * distance / std::max(pixel_scale, 1e-9);
  int bucket = 0;
  while (bucket + 1 < kBucketCount && bucketToleranceM(bucket + 1) <= allowed_m) ++bucket;
  return bucket;
}

ParametricMeshStats ParametricMeshes::draw(std::span<const uint32_t> clusters,
                                           const glm::dvec3& eye, const glm::mat4& view_projection,
                                           double pixel_scale, double near_m,
                                           uint32_t object_color_count, uint64_t frame) {
  Impl& s = *impl_;
  ParametricMeshStats stats;
  const auto start = Clock::now();
  glUseProgram(s.program);
  glProgramUniformMatrix4fv(s.program, gl::kViewProjectionLocation, 1, GL_FALSE,
                            &view_projection[0][0]);
  glProgramUniform1ui(s.program, gl::kObjectColorCountLocation, object_color_count);
  glBindVertexArray(s.vertex_array);
  for (uint32_t cluster : clusters) {
    if (cluster >= s.view->clusters().size()) continue;
    const int wanted = s.options.fixed_tolerance_m > 0.0 ? 0 : bucketFor(cluster, eye, pixel_scale, near_m);
    CachedMesh* mesh = nullptr;
    if (auto it = s.cache.find(meshKey(cluster, wanted)); it != s.cache.end()) mesh = &it->second;
    const bool over_budget =
        std::chrono::duration<double, std::milli>(Clock::now() - start).count() >
        s.options.build_ms_per_frame;
    if (!mesh && over_budget) {  // any other bucket already built stands in
      for (int b = 0; b < kBucketCount && !mesh; ++b)
        if (auto it = s.cache.find(meshKey(cluster, b)); it != s.cache.end()) mesh = &it->second;
    }
    if (!mesh) {
      CachedMesh built = s.build(cluster, wanted);
      s.cached_bytes += built.bytes;
      mesh = &s.cache.emplace(meshKey(cluster, wanted), built).first->second;
      ++stats.meshes_built;
    }
    mesh->last_used = frame;
    if (mesh->index_count == 0) continue;
    const glm::vec3 anchor_eye(clusterAnchor(s.view->clusters()[cluster]) - eye);
    glProgramUniform3fv(s.program, gl::kParamMeshAnchorLocation, 1, &anchor_eye[0]);
    glVertexArrayVertexBuffer(s.vertex_array, 0, mesh->vertex_buffer, 0, sizeof(ParametricVertex));
    glVertexArrayElementBuffer(s.vertex_array, mesh->index_buffer);
    glDrawElements(GL_TRIANGLES, GLsizei(mesh->index_count), GL_UNSIGNED_INT, nullptr);
    ++stats.clusters_drawn;
    stats.instances_drawn += s.view->clusters()[cluster].instance_count;
    stats.triangles_drawn += mesh->index_count / 3;
  }
  glBindVertexArray(0);
  glUseProgram(0);
  s.evict(frame);
  stats.meshes_cached = static_cast<uint32_t>(s.cache.size());
  stats.cached_bytes = s.cached_bytes;
  return stats;
}

}  // namespace tw
