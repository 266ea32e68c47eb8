// Run-time tessellation of parametric clusters by distance, cached in GL buffers. See
// parametric_meshes.h.
#include "parametric_meshes.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "gl_program.h"
#include "parametric_shaders.h"
#include "profile_simplifier.h"
#include "tessellate.h"

namespace tw {


uint32_t packNormal(const glm::vec3& n) {
  auto component = [](float v) {
    return uint32_t(int32_t(std::lround(std::clamp(v, -1.0f, 1.0f) * 511.0f))) & 0x3ffu;
  };
  return component(n.x) | (component(n.y) << 10) | (component(n.z) << 20);
}

glm::mat3 normalMatrix(const glm::mat3& linear) {
  const float handedness = glm::determinant(linear) < 0.0f ? -1.0f : 1.0f;
  return glm::mat3(handedness * glm::cross(linear[1], linear[2]),
                   handedness * glm::cross(linear[2], linear[0]),
                   handedness * glm::cross(linear[0], linear[1]));
}

glm::dvec3 clusterAnchor(const pkg::ClusterRecord& c) {
  return glm::dvec3(c.center[0], c.center[1], c.center[2]);
}

namespace {

// Replaces the profile of extrusion `e` (placed by `linear`) by one within `tolerance_m` metres
// of it, when that drops points and keeps the profile simple (if it was) and its winding.
void simplifyExtrusion(Extrusion& e, const glm::mat3& linear, float tolerance_m,
                       ProfileSimplifier& simplifier, std::vector<glm::vec2>& kept) {
  const float scale = std::max(glm::length(linear[0]), glm::length(linear[1]));
  if (!(scale > 0.0f) || e.profile.size() <= 3) return;
  simplifier.simplifyClosed(e.profile, tolerance_m / scale, kept);
  if (kept.size() < 3 || kept.size() >= e.profile.size()) return;
  if (extrusionEnclosesSolid(kept) != extrusionEnclosesSolid(e.profile)) return;
  if ((profileSignedArea2(kept) > 0.0) != (profileSignedArea2(e.profile) > 0.0)) return;
  e.profile.assign(kept.begin(), kept.end());
}

}  // namespace

void tessellateCluster(const PackageView& view, uint32_t cluster, float tolerance_m,
                       std::vector<ParametricVertex>& vertices, std::vector<uint32_t>& indices,
                       std::vector<uint32_t>* instance_offsets, bool simplify_profiles) {
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
  ProfileSimplifier simplifier;
  std::vector<glm::vec2> kept;
  if (instance_offsets) instance_offsets->assign(1, static_cast<uint32_t>(indices.size()));
  for (uint32_t i = c.instance_first; i < c.instance_first + c.instance_count; ++i) {
    const pkg::InstanceRecord& in = instances[i];
    mesh.positions.clear();
    mesh.normals.clear();
    mesh.indices.clear();
    const glm::mat3 linear = instanceLinear(in);
    Primitive primitive = primitiveOf(in, view.profilePoints());
    if (auto* extrusion = std::get_if<Extrusion>(&primitive); extrusion && simplify_profiles)
      simplifyExtrusion(*extrusion, linear, tolerance_m, simplifier, kept);
    tessellatePrimitive(primitive, tolerance_m, mesh);
    const glm::vec3 origin(glm::dvec3(in.origin[0], in.origin[1], in.origin[2]) - anchor);
    const glm::mat3 normals = normalMatrix(linear);
    const bool with_normals = mesh.normals.size() == mesh.positions.size();
    const uint32_t base = static_cast<uint32_t>(vertices.size());
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
      glm::vec3 n(0.0f);
      if (with_normals) {
        n = normals * mesh.normals[v];
        const float length = glm::length(n);
        n = length > 1e-20f ? n / length : glm::vec3(0.0f);
      }
      vertices.push_back({origin + linear * mesh.positions[v], in.object, packNormal(n)});
    }
    for (uint32_t index : mesh.indices) indices.push_back(base + index);
    if (instance_offsets) instance_offsets->push_back(static_cast<uint32_t>(indices.size()));
  }
}

namespace {

using Clock = std::chrono::steady_clock;

struct CachedMesh {
  GLuint vertex_buffer = 0, index_buffer = 0;
  uint32_t index_count = 0;
  std::vector<uint32_t> instance_offsets;  // first index of each instance, and the end
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
  // drawInstances scratch: (instance offset in the cluster, face culling) by bucket, the
  // multi-draw ranges by face culling.
  static constexpr size_t kCullKinds = 3;  // FaceCull's values
  std::array<std::vector<std::pair<uint32_t, FaceCull>>, kBucketCount> by_bucket;
  std::array<std::vector<GLsizei>, kCullKinds> counts;
  std::array<std::vector<const void*>, kCullKinds> offsets;

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
    CachedMesh mesh;
    tessellateCluster(*view, cluster, static_cast<float>(tolerance), vertices, indices,
                      &mesh.instance_offsets, options.fixed_tolerance_m <= 0.0);
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

  // The mesh of `cluster` at bucket `wanted`, built now unless build_ms_per_frame has passed since
  // `start` and another bucket is cached (never a hole).
  CachedMesh* meshFor(uint32_t cluster, int wanted, Clock::time_point start, ParametricMeshStats& stats) {
    if (auto it = cache.find(meshKey(cluster, wanted)); it != cache.end()) return &it->second;
    const bool over_budget =
        std::chrono::duration<double, std::milli>(Clock::now() - start).count() > options.build_ms_per_frame;
    if (over_budget)
      for (int b = 0; b < kBucketCount; ++b)
        if (auto it = cache.find(meshKey(cluster, b)); it != cache.end()) return &it->second;
    CachedMesh built = build(cluster, wanted);
    cached_bytes += built.bytes;
    ++stats.meshes_built;
    return &cache.emplace(meshKey(cluster, wanted), std::move(built)).first->second;
  }

  // The GL state both draw calls start from, and what they do after.
  void beginDraw(const glm::mat4& view_projection, uint32_t object_color_count) {
    glUseProgram(program);
    glProgramUniformMatrix4fv(program, gl::kViewProjectionLocation, 1, GL_FALSE,
                              &view_projection[0][0]);
    glProgramUniform1ui(program, gl::kObjectColorCountLocation, object_color_count);
    glBindVertexArray(vertex_array);
  }
  void endDraw(uint64_t frame, ParametricMeshStats& stats) {
    glBindVertexArray(0);
    glUseProgram(0);
    evict(frame);
    stats.meshes_cached = static_cast<uint32_t>(cache.size());
    stats.cached_bytes = cached_bytes;
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
                                   {GL_FRAGMENT_SHADER, gl::parametricSmoothFragmentShader()}},
                                  "ParametricMeshes: mesh");
  GLuint& vao = impl_->vertex_array;
  glCreateVertexArrays(1, &vao);
  glEnableVertexArrayAttrib(vao, 0);
  glVertexArrayAttribFormat(vao, 0, 3, GL_FLOAT, GL_FALSE, offsetof(ParametricVertex, position));
  glVertexArrayAttribBinding(vao, 0, 0);
  glEnableVertexArrayAttrib(vao, 1);
  glVertexArrayAttribIFormat(vao, 1, 1, GL_UNSIGNED_INT, offsetof(ParametricVertex, object));
  glVertexArrayAttribBinding(vao, 1, 0);
  glEnableVertexArrayAttrib(vao, 2);
  glVertexArrayAttribFormat(vao, 2, 4, GL_INT_2_10_10_10_REV, GL_TRUE, offsetof(ParametricVertex, normal));
  glVertexArrayAttribBinding(vao, 2, 0);
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
  s.beginDraw(view_projection, object_color_count);
  for (uint32_t cluster : clusters) {
    if (cluster >= s.view->clusters().size()) continue;
    const int wanted = s.options.fixed_tolerance_m > 0.0 ? 0 : bucketFor(cluster, eye, pixel_scale, near_m);
    CachedMesh* mesh = s.meshFor(cluster, wanted, start, stats);
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
    stats.two_sided_triangles += mesh->index_count / 3;
  }
  s.endDraw(frame, stats);
  return stats;
}

ParametricMeshStats ParametricMeshes::drawInstances(std::span<const ParametricMeshInstance> instances,
                                                    const glm::dvec3& eye,
                                                    const glm::mat4& view_projection,
                                                    double pixel_scale, double tolerance_px,
                                                    uint32_t object_color_count, uint64_t frame) {
  Impl& s = *impl_;
  ParametricMeshStats stats;
  if (instances.empty()) return stats;
  const auto start = Clock::now();
  s.beginDraw(view_projection, object_color_count);
  const auto records = s.view->clusters();
  auto& by_bucket = s.by_bucket;
  auto& counts = s.counts;
  auto& offsets = s.offsets;
  for (size_t k = 0; k < instances.size();) {
    const uint32_t cluster = instances[k].cluster;
    size_t end = k;
    while (end < instances.size() && instances[end].cluster == cluster) ++end;
    if (cluster >= records.size()) {
      k = end;
      continue;
    }
    const pkg::ClusterRecord& record = records[cluster];
    for (auto& list : by_bucket) list.clear();
    for (size_t j = k; j < end; ++j) {
      const uint32_t i = instances[j].instance;
      if (i < record.instance_first || i - record.instance_first >= record.instance_count) continue;
      int bucket = 0;
      if (s.options.fixed_tolerance_m <= 0.0) {
        const double allowed_m = tolerance_px * std::max(instances[j].distance_m, 1e-6) /
                                 std::max(pixel_scale, 1e-9);
        while (bucket + 1 < kBucketCount && bucketToleranceM(bucket + 1) <= allowed_m) ++bucket;
      }
      by_bucket[size_t(bucket)].push_back({i - record.instance_first, instances[j].cull});
    }
    const glm::vec3 anchor_eye(clusterAnchor(record) - eye);
    bool drawn = false;
    for (int bucket = 0; bucket < kBucketCount; ++bucket) {
      if (by_bucket[size_t(bucket)].empty()) continue;
      CachedMesh* mesh = s.meshFor(cluster, bucket, start, stats);
      mesh->last_used = frame;
      if (mesh->index_count == 0 || mesh->instance_offsets.size() != record.instance_count + 1u) continue;
      for (size_t kind = 0; kind < Impl::kCullKinds; ++kind) {
        counts[kind].clear();
        offsets[kind].clear();
      }
      for (const auto& [local, cull] : by_bucket[size_t(bucket)]) {
        const uint32_t first = mesh->instance_offsets[local], last = mesh->instance_offsets[local + 1];
        if (last <= first) continue;
        // Consecutive instances alike in face culling merge into one range.
        std::vector<GLsizei>& kind_counts = counts[size_t(cull)];
        std::vector<const void*>& kind_offsets = offsets[size_t(cull)];
        if (!kind_counts.empty() &&
            reinterpret_cast<uintptr_t>(kind_offsets.back()) + uintptr_t(kind_counts.back()) * sizeof(uint32_t) ==
                uintptr_t(first) * sizeof(uint32_t)) {
          kind_counts.back() += GLsizei(last - first);
        } else {
          kind_counts.push_back(GLsizei(last - first));
          kind_offsets.push_back(reinterpret_cast<const void*>(uintptr_t(first) * sizeof(uint32_t)));
        }
        stats.triangles_drawn += (last - first) / 3;
        if (cull == FaceCull::None) stats.two_sided_triangles += (last - first) / 3;
        ++stats.instances_drawn;
      }
      bool bound = false;
      for (size_t kind = 0; kind < Impl::kCullKinds; ++kind) {
        if (counts[kind].empty()) continue;
        if (!bound) {
          glProgramUniform3fv(s.program, gl::kParamMeshAnchorLocation, 1, &anchor_eye[0]);
          glVertexArrayVertexBuffer(s.vertex_array, 0, mesh->vertex_buffer, 0, sizeof(ParametricVertex));
          glVertexArrayElementBuffer(s.vertex_array, mesh->index_buffer);
          bound = true;
        }
        if (FaceCull(kind) == FaceCull::None) {
          glDisable(GL_CULL_FACE);
        } else {
          glEnable(GL_CULL_FACE);
          glCullFace(GL_BACK);
          glFrontFace(FaceCull(kind) == FaceCull::BackOfCw ? GL_CW : GL_CCW);
        }
        glMultiDrawElements(GL_TRIANGLES, counts[kind].data(), GL_UNSIGNED_INT,
                            offsets[kind].data(), GLsizei(counts[kind].size()));
        drawn = true;
      }
    }
    stats.clusters_drawn += drawn;
    k = end;
  }
  glDisable(GL_CULL_FACE);
  glFrontFace(GL_CCW);
  s.endDraw(frame, stats);
  return stats;
}

}  // namespace tw
