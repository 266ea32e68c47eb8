// Per-instance level of detail for tessellated parametrics: unit meshes made on first use, each
// visible instance expanded from one into a per-frame batch, a few draws per frame. See
// parametric_instance_meshes.h.
#include "parametric_instance_meshes.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <atomic>
#include <future>
#include <memory>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include "camera.h"
#include "gl_program.h"
#include "parametric_instance_forms.h"
#include "parametric_meshes.h"
#include "parametric_shaders.h"
#include "parametric_unit_meshes.h"
#include "profile_simplifier.h"
#include "sealed_pipe_runs.h"
#include "tessellate.h"

namespace tw {

using namespace instance_forms;

namespace {

// A unit-mesh point `q` of a primitive with parameters `p`, in its canonical frame (scene.h).
glm::vec3 shapedPoint(pkg::PrimitiveType type, const float* p, const glm::vec4& q) {
  const float rim = std::min(q.w, 1.0f);  // tubes: 0 at a cap centre
  switch (type) {
    case pkg::PrimitiveType::Cylinder: return {rim * p[0] * q.x, rim * p[0] * q.y, q.z * p[1]};
    case pkg::PrimitiveType::Cone: {
      const float r = rim * (p[0] + (p[1] - p[0]) * q.z);
      return {r * q.x, r * q.y, q.z * p[2]};
    }
    case pkg::PrimitiveType::Sphere: return p[0] * glm::vec3(q.z * q.x, q.z * q.y, q.w);
    case pkg::PrimitiveType::TorusSegment: {
      const float a = q.x * p[2], rho = p[0] + p[1] * q.y;
      return {rho * std::cos(a), rho * std::sin(a), p[1] * q.z};
    }
    case pkg::PrimitiveType::Box: return glm::vec3(q) * glm::vec3(p[0], p[1], p[2]);
    default: return glm::vec3(0.0f);  // profiles are drawn in the box frame only
  }
}

// The surface normal at unit-mesh point `q` in the canonical frame (not normalized for cones);
// zero where the surface is flat there (caps, boxes) or for lines and points.
glm::vec3 shapedNormal(pkg::PrimitiveType type, Shape shape, const float* p, const glm::vec4& q) {
  switch (shape) {
    case Shape::Tube:
      if (q.w != 1.0f) return glm::vec3(0.0f);
      if (type == pkg::PrimitiveType::Cone) {
        const glm::vec2 c = glm::vec2(q) / std::max(glm::length(glm::vec2(q)), 1e-30f);
        return {p[2] * c.x, p[2] * c.y, p[0] - p[1]};
      }
      return {q.x, q.y, 0.0f};
    case Shape::Sphere: return {q.z * q.x, q.z * q.y, q.w};
    case Shape::Torus: {
      const float a = q.x * p[2];
      return {q.y * std::cos(a), q.y * std::sin(a), q.z};
    }
    default: return glm::vec3(0.0f);
  }
}

}  // namespace

// One vertex of the per-frame batch: 20 bytes.
struct SmoothVertex {
  glm::vec3 position;  // metres from the eye
  uint32_t object;     // object index
  uint32_t normal;     // packNormal
};

// One vertex of a thin beam's band (beamRibbon): 28 bytes.
struct BeamVertex {
  glm::vec3 position;  // metres from the eye
  uint32_t object;     // object index
  uint32_t normal_u;   // packNormal: the first long face's
  uint32_t normal_w;   // and the second's
  float across;        // signed metres from the edge where the faces meet (< 0: first face)
};

// A unit mesh with arrays of its own (base_vertex and first_index 0), so that threads expanding
// instances read it while another thread makes a mesh they have not met yet.
struct OwnedUnitMesh {
  UnitMesh mesh;
  std::vector<glm::vec4> shapes;
  std::vector<uint32_t> indices;
};

// What expanding a run of clusters produces: prepare() splits the frame's clusters into runs
// expanded on TBB, each into a part of its own, and appends the parts in cluster order, so the
// batch is the one a single thread makes.
struct ExpandedPart {
  std::vector<SmoothVertex> vertices;
  std::vector<BeamVertex> beam_vertices;  // indexed by indices[kBeams]
  std::array<std::vector<uint32_t>, kBatchCount> indices;
  // Drawn (both passes), hidden last frame (first pass), to test (second pass): cluster, instance.
  std::vector<std::pair<uint32_t, uint32_t>> drawn, deferred, to_test;
  std::vector<ParametricMeshInstance> profiles;
  InstanceLodStats stats;
  std::vector<glm::vec2> kept, ring;  // lathe scratch
  ProfileSimplifier simplifier;

  void clear() {
    vertices.clear();
    beam_vertices.clear();
    for (auto& list : indices) list.clear();
    drawn.clear();
    deferred.clear();
    to_test.clear();
    profiles.clear();
    stats = {};
  }
  // Appends `part` after this one's contents.
  void append(const ExpandedPart& part) {
    const auto base = static_cast<uint32_t>(vertices.size());
    const auto beam_base = static_cast<uint32_t>(beam_vertices.size());
    vertices.insert(vertices.end(), part.vertices.begin(), part.vertices.end());
    beam_vertices.insert(beam_vertices.end(), part.beam_vertices.begin(), part.beam_vertices.end());
    for (uint32_t batch = 0; batch < kBatchCount; ++batch) {
      const uint32_t offset = batch == kBeams ? beam_base : base;
      for (uint32_t index : part.indices[batch]) indices[batch].push_back(offset + index);
    }
    drawn.insert(drawn.end(), part.drawn.begin(), part.drawn.end());
    deferred.insert(deferred.end(), part.deferred.begin(), part.deferred.end());
    to_test.insert(to_test.end(), part.to_test.begin(), part.to_test.end());
    profiles.insert(profiles.end(), part.profiles.begin(), part.profiles.end());
    stats.instances_drawn += part.stats.instances_drawn;
    stats.instances_culled += part.stats.instances_culled;
    stats.thin_instances += part.stats.thin_instances;
    stats.instances_occluded += part.stats.instances_occluded;
  }
};

struct ParametricInstanceMeshes::Impl {
  const PackageView* view = nullptr;
  std::vector<InstanceBounds> bounds;  // by instance index
  // Parametric clusters holding members or closers of sealed runs, with the box (package frame)
  // of those instances; and whether this frame's eye is clear of all of them.
  struct RunCluster {
    uint32_t cluster;
    glm::dvec3 lo, hi;
  };
  std::future<std::vector<uint8_t>> runs_found;  // roles by instance; valid until the first draw
  std::vector<RunCluster> run_clusters;
  bool eye_clear_of_runs = false;

  // Marks the members and closers of the runs found, and lists their clusters.
  void takeSealedRuns() {
    const std::vector<uint8_t> roles = runs_found.get();
    const auto clusters = view->clusters();
    for (uint32_t c = 0; c < clusters.size(); ++c) {
      const pkg::ClusterRecord& r = clusters[c];
      if (r.kind != static_cast<uint8_t>(pkg::ClusterKind::Parametric) ||
          r.instance_first > bounds.size() || r.instance_count > bounds.size() - r.instance_first)
        continue;
      const glm::dvec3 anchor = clusterAnchor(r);
      RunCluster run{c, glm::dvec3(INFINITY), glm::dvec3(-INFINITY)};
      for (uint32_t i = r.instance_first; i < r.instance_first + r.instance_count; ++i) {
        InstanceBounds& b = bounds[i];
        if (!(b.flags & kValid) || roles[i] == 0) continue;
        b.flags |= ((roles[i] & kSealedRunMember) ? kRunMember : 0) |
                   ((roles[i] & kSealedRunCloser) ? kRunCloser : 0);
        run.lo = glm::min(run.lo, anchor + glm::dvec3(b.centre - b.extent));
        run.hi = glm::max(run.hi, anchor + glm::dvec3(b.centre + b.extent));
      }
      if (run.lo.x <= run.hi.x) run_clusters.push_back(run);
    }
  }
  GLuint program = 0, vertex_array = 0, beam_program = 0, beam_vertex_array = 0;
  // The GL buffers of each part drawn in a frame (set 0 for a batch drawn whole): a part's are
  // filled while llvmpipe may still read the previous part's.
  struct BufferSet {
    GLuint vertices = 0, beam_vertices = 0, indices = 0;
  };
  std::vector<BufferSet> buffer_sets;
  BufferSet& bufferSet(size_t k) {
    while (buffer_sets.size() <= k) {
      BufferSet set;
      glCreateBuffers(1, &set.vertices);
      glCreateBuffers(1, &set.beam_vertices);
      glCreateBuffers(1, &set.indices);
      buffer_sets.push_back(set);
    }
    return buffer_sets[k];
  }
  // Unit meshes by (shape, a, b), published once made (unitMesh); `made` owns them.
  static constexpr size_t kUnitSlots = size_t(Shape::None) * kLevels.size() * kLevels.size();
  std::array<std::atomic<const OwnedUnitMesh*>, kUnitSlots> unit_slots{};
  std::mutex unit_mutex;
  std::vector<std::unique_ptr<OwnedUnitMesh>> made;
  std::atomic<uint32_t> made_count{0};  // made.size(), for the stats without the mutex
  // The frame's batch (parts appended in order), and the parts expanded beside it.
  ExpandedPart frame;
  std::vector<ExpandedPart> parts;
  // Occlusion: per instance, hidden by last frame's final depth; this frame's first-pass
  // instances left for the second pass, and every instance drawn (cluster, instance).
  std::vector<uint8_t> hidden_last;
  std::vector<std::pair<uint32_t, uint32_t>> deferred, drawn;
  // Which of the instances last tested (testAll) the pyramid hides.
  std::vector<uint8_t> test_hidden;

  // Tests every (cluster, instance) of `list` with `box_hidden`, eye at `eye_at`, into
  // test_hidden. On TBB: the rasterizer threads are idle then, waiting for the draws these tests
  // decide (the second pass) or done with the frame (the visibility record).
  void testAll(const std::vector<std::pair<uint32_t, uint32_t>>& list, const glm::dvec3& eye_at,
               const std::function<bool(const glm::vec3&, const glm::vec3&)>& box_hidden) {
    test_hidden.assign(list.size(), 0);
    const auto records = view->clusters();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, list.size(), 256),
                      [&](const tbb::blocked_range<size_t>& range) {
                        for (size_t k = range.begin(); k != range.end(); ++k) {
                          const auto [c, i] = list[k];
                          const InstanceBounds& b = bounds[i];
                          const glm::vec3 centre =
                              glm::vec3(clusterAnchor(records[c]) - eye_at) + b.centre;
                          test_hidden[k] = box_hidden(centre - b.extent, centre + b.extent) ? 1 : 0;
                        }
                      });
  }
  glm::dvec3 eye{0.0};  // of the frame's passes
  std::vector<uint32_t> all_indices;
  uint32_t clusters_per_run = 32;  // 0: one run
  uint32_t primitives_per_flush = 8192;  // 0: each batch in one draw
  uint64_t batch_instances = 0;          // expanded into the prepared batch

  // The frame's choice, fixed by prepare() for the expansion, which may run on after it returns.
  struct FrameChoice {
    InstanceLodView view;
    std::array<glm::vec4, 4> planes{};  // the frustum's side planes, eye-relative, unit normals
    double pixel_scale = 1.0, near_m = 1e-6;
    float near_reach = 0.0f;  // how far from the eye the near plane reaches (its corners)
    bool test = false;        // second pass: instances are left for the pyramid's test
  };
  FrameChoice choice;
  std::vector<uint32_t> frame_clusters;  // prepare()'s
  // Streaming: prepare() of a first or only pass in several runs hands the runs to a worker,
  // which expands them in order, each into parts[r]; submit() draws each part as soon as it is
  // done and, while it waits for one, expands the next run nobody has claimed. So the GL
  // thread's share of llvmpipe's work (it shades and bins every vertex of a draw) overlaps the
  // expansion instead of following it (docs/parametrics.md, "Streamed").
  bool streaming = false;
  size_t stream_runs = 0;
  std::atomic<size_t> next_run{0};
  std::unique_ptr<std::atomic<uint8_t>[]> run_done;
  size_t run_done_capacity = 0;
  std::vector<ParametricMeshInstance>* stream_profiles = nullptr;
  tbb::task_group expansion;

  ~Impl() {
    expansion.wait();
    glDeleteProgram(program);
    glDeleteProgram(beam_program);
    for (const BufferSet& set : buffer_sets) {
      glDeleteBuffers(1, &set.vertices);
      glDeleteBuffers(1, &set.beam_vertices);
      glDeleteBuffers(1, &set.indices);
    }
    glDeleteVertexArrays(1, &vertex_array);
    glDeleteVertexArrays(1, &beam_vertex_array);
  }

  // The distance of instance `b` (its centre at `centre`, eye-relative) for its level of detail.
  double distanceOf(const InstanceBounds& b, const glm::vec3& centre) const {
    return std::max(double(glm::length(centre)) - b.radius, choice.near_m);
  }

  // Draws one visible instance of cluster `c` (anchor_eye: its anchor relative to the eye) into
  // `part`. Called from several threads at once, each with its own part.
  void place(ExpandedPart& part, uint32_t c, const glm::vec3& anchor_eye, uint32_t i) {
    InstanceLodStats& stats = part.stats;
    const InstanceBounds& b = bounds[i];
    const double distance = distanceOf(b, anchor_eye + b.centre);
    const double px_per_m = choice.pixel_scale / distance;
    const float metres_per_px = static_cast<float>(1.0 / px_per_m);
    Form form =
        chooseForm(b, static_cast<float>(std::max(choice.view.tolerance_px, 1e-3)) * metres_per_px,
                   static_cast<float>(choice.view.thin_px) * metres_per_px,
                   static_cast<float>(choice.view.min_thin_px) * metres_per_px);
    if (form.shape == Shape::None) {
      ++stats.instances_culled;
      return;
    }
    if (form.shape != Shape::Point && form.shape != Shape::Ribbon)
      cullBackFaces(form, b, eyeOutsideSolid(b, -anchor_eye, choice.near_reach),
                    ((b.flags & kRunMember) && eye_clear_of_runs) ||
                        (!(b.flags & kCapped) && tubeInsideHidden(b, -anchor_eye, choice.near_reach)));
    if (choice.view.pass != InstancePass::All) part.drawn.push_back({c, i});
    ++stats.instances_drawn;
    if (form.shape == Shape::Profile) {
      FaceCull cull = FaceCull::None;
      if ((b.flags & kClosedProfile) && eyeOutsideSolid(b, -anchor_eye, choice.near_reach))
        cull = (b.flags & kMirrored) ? FaceCull::BackOfCw : FaceCull::BackOfCcw;
      part.profiles.push_back({c, i, distance, cull});
      return;
    }
    stats.thin_instances += form.shape == Shape::Ribbon || form.shape == Shape::Point;
    if (form.shape == Shape::Ribbon) {
      if (form.box_frame)
        beamRibbon(part, i, b, anchor_eye, form.long_axis);
      else
        ribbon(part, i, b, anchor_eye, kLevels[form.a]);
      return;
    }
    if (form.shape == Shape::Point) {
      // A point is its instance's box centre, which the bounds hold: placed without a unit mesh,
      // the instance's box or its transform (some 18,000 of the 50M orbit's 47,000 instances a
      // frame are points).
      part.indices[kPoints].push_back(static_cast<uint32_t>(part.vertices.size()));
      part.vertices.push_back({anchor_eye + b.centre, view->instances()[i].object, 0u});
      return;
    }
    if (form.shape == Shape::Lathe) {
      lathe(part, i, b, anchor_eye, kLevels[form.a],
            0.5f * static_cast<float>(std::max(choice.view.tolerance_px, 1e-3)) * metres_per_px);
      return;
    }
    expand(part, i, b, anchor_eye, form);
  }

  // One instance of cluster `c`: culled, deferred, left for the pyramid's test, or placed.
  void consider(ExpandedPart& part, uint32_t c, const glm::vec3& anchor_eye, uint32_t i) {
    InstanceLodStats& stats = part.stats;
    const InstanceBounds& b = bounds[i];
    if (!(b.flags & kValid)) return;
    const glm::vec3 centre = anchor_eye + b.centre;
    const double px_per_m = choice.pixel_scale / distanceOf(b, centre);
    bool outside = 2.0 * b.radius * px_per_m < choice.view.min_feature_px;
    for (const glm::vec4& plane : choice.planes)
      outside = outside || glm::dot(glm::vec3(plane), centre) + plane.w < -b.radius;
    if (outside) {
      ++stats.instances_culled;
      return;
    }
    if (choice.view.pass == InstancePass::First && hidden_last[i]) {
      part.deferred.push_back({c, i});  // hidden last frame: the second pass tests it
      return;
    }
    if (choice.test) {
      part.to_test.push_back({c, i});
      return;
    }
    place(part, c, anchor_eye, i);
  }

  // Considers every instance of frame_clusters[begin, end) into `part`, in cluster order.
  void expandClusters(ExpandedPart& part, size_t begin, size_t end) {
    const auto records = view->clusters();
    for (size_t k = begin; k < end; ++k) {
      const uint32_t c = frame_clusters[k];
      if (c >= records.size() ||
          records[c].kind != static_cast<uint8_t>(pkg::ClusterKind::Parametric))
        continue;
      const pkg::ClusterRecord& record = records[c];
      if (record.instance_first > bounds.size() ||
          record.instance_count > bounds.size() - record.instance_first)
        continue;
      const glm::vec3 anchor_eye(clusterAnchor(record) - choice.view.eye);
      for (uint32_t i = record.instance_first; i < record.instance_first + record.instance_count; ++i)
        consider(part, c, anchor_eye, i);
    }
  }
  // Run r of `runs` over frame_clusters, into parts[r].
  void expandRun(size_t r, size_t runs) {
    parts[r].clear();
    const size_t n = frame_clusters.size();
    expandClusters(parts[r], n * r / runs, n * (r + 1) / runs);
  }
  // Streaming: expands the next run nobody has claimed; false when none is left.
  bool claimAndExpand() {
    const size_t r = next_run.fetch_add(1, std::memory_order_relaxed);
    if (r >= stream_runs) return false;
    expandRun(r, stream_runs);
    run_done[r].store(1, std::memory_order_release);
    return true;
  }

  // Uploads `part` into buffer set `set` and draws its batches, adding to `stats`. A far view's
  // primitives go in draws of at most primitives_per_flush, each flushed once that many have
  // gone since the last flush (`unflushed` carries the count from part to part): llvmpipe's
  // rasterizer threads start on a scene only when it is flushed, and until then the submitting
  // thread shades and bins every vertex alone (docs/runtime.md, "Overlap"). A near view's
  // (four or more primitives an instance) goes whole: every extra scene then reloads and stores
  // the many tiles its large triangles cover, and on the walked decks parts were 5 % slower.
  void drawPart(ExpandedPart& part, size_t set_index, uint64_t part_instances, size_t& unflushed,
                InstanceLodStats& stats) {
    if (part.vertices.empty() && part.beam_vertices.empty()) return;
    all_indices.clear();
    std::array<size_t, kBatchCount + 1> first{};
    for (uint32_t batch = 0; batch < kBatchCount; ++batch) {
      first[batch] = all_indices.size();
      all_indices.insert(all_indices.end(), part.indices[batch].begin(), part.indices[batch].end());
    }
    first[kBatchCount] = all_indices.size();
    const size_t primitives = part.indices[kPoints].size() +
                              (all_indices.size() - part.indices[kPoints].size()) / 3;
    const bool in_parts =
        primitives_per_flush != 0 && primitives < 4 * std::max<uint64_t>(part_instances, 1);
    const BufferSet& set = bufferSet(set_index);
    glNamedBufferData(set.vertices, GLsizeiptr(part.vertices.size() * sizeof(SmoothVertex)),
                      part.vertices.data(), GL_STREAM_DRAW);
    glNamedBufferData(set.beam_vertices, GLsizeiptr(part.beam_vertices.size() * sizeof(BeamVertex)),
                      part.beam_vertices.data(), GL_STREAM_DRAW);
    glNamedBufferData(set.indices, GLsizeiptr(all_indices.size() * sizeof(uint32_t)),
                      all_indices.data(), GL_STREAM_DRAW);
    glVertexArrayVertexBuffer(vertex_array, 0, set.vertices, 0, sizeof(SmoothVertex));
    glVertexArrayElementBuffer(vertex_array, set.indices);
    glVertexArrayVertexBuffer(beam_vertex_array, 0, set.beam_vertices, 0, sizeof(BeamVertex));
    glVertexArrayElementBuffer(beam_vertex_array, set.indices);
    glUseProgram(program);
    glBindVertexArray(vertex_array);
    for (uint32_t batch = 0; batch < kBatchCount; ++batch) {
      const size_t count = first[batch + 1] - first[batch];
      if (count == 0) continue;
      if (batch == kBeams) {  // the last batch: vertices and a program of their own
        glUseProgram(beam_program);
        glBindVertexArray(beam_vertex_array);
      }
      if (batch == kCullCcw || batch == kCullCw) {
        glEnable(GL_CULL_FACE);
        glCullFace(GL_BACK);
        glFrontFace(batch == kCullCw ? GL_CW : GL_CCW);
      } else {
        glDisable(GL_CULL_FACE);
      }
      const GLenum mode = batch == kPoints ? GL_POINTS : GL_TRIANGLES;
      // The 50M plant's orbit (121,516 triangles a frame) fell from 47.6 to 39.5 ms when its
      // batch went in flushed parts (docs/benchmarks.md, "A far view's parametric batch in
      // flushed parts").
      const size_t vertices_per_primitive = mode == GL_TRIANGLES ? 3 : 1;
      const size_t most = in_parts ? size_t(primitives_per_flush) * vertices_per_primitive : count;
      for (size_t at = 0; at < count; at += most) {
        const size_t n = std::min(most, count - at);
        glDrawElements(mode, GLsizei(n), GL_UNSIGNED_INT,
                       reinterpret_cast<const void*>((first[batch] + at) * sizeof(uint32_t)));
        ++stats.draw_calls;
        if (in_parts) {
          unflushed += n / vertices_per_primitive;
          if (unflushed >= primitives_per_flush) {
            glFlush();
            unflushed = 0;
          }
        }
      }
      if (mode == GL_TRIANGLES) stats.triangles_drawn += count / 3;
      if (batch == kTwoSided || batch == kBeams) stats.two_sided_triangles += count / 3;
    }
    part.vertices.clear();
    part.beam_vertices.clear();
    for (auto& list : part.indices) list.clear();
  }

  // Safe to call from several threads at once: a mesh is made once, under the mutex, and read
  // without it once published.
  const OwnedUnitMesh& unitMesh(Shape shape, uint32_t a, uint32_t b) {
    std::atomic<const OwnedUnitMesh*>& slot =
        unit_slots[(size_t(shape) * kLevels.size() + a) * kLevels.size() + b];
    if (const OwnedUnitMesh* mesh = slot.load(std::memory_order_acquire)) return *mesh;
    std::lock_guard lock(unit_mutex);
    if (const OwnedUnitMesh* mesh = slot.load(std::memory_order_relaxed)) return *mesh;
    UnitMeshBuilder builder;
    UnitMesh m;
    switch (shape) {
      case Shape::Tube: m = builder.tube(kLevels[a]); break;
      case Shape::Sphere: m = builder.sphere(kLevels[a], kLevels[b]); break;
      case Shape::Torus: m = builder.torus(kLevels[a], kLevels[b]); break;
      case Shape::Box: m = builder.box(); break;
      case Shape::Point:  // the box centre, placed from the bounds (prepare)
      case Shape::Profile:
      case Shape::Lathe:
      case Shape::Ribbon:
      case Shape::None: break;  // never expanded from a unit mesh
    }
    m.vertex_count = static_cast<uint32_t>(builder.shapes.size()) - m.base_vertex;
    auto owned = std::make_unique<OwnedUnitMesh>();
    owned->mesh = m;
    owned->shapes = std::move(builder.shapes);
    owned->indices = std::move(builder.indices);
    made.push_back(std::move(owned));
    made_count.store(static_cast<uint32_t>(made.size()), std::memory_order_relaxed);
    slot.store(made.back().get(), std::memory_order_release);
    return *made.back();
  }

  // Appends revolution `i` swept over `segments` steps (a full turn's count; a partial sweep gets
  // its share, at least one), its profile simplified to `profile_tolerance` metres: flat bands
  // between the kept profile points, two-sided (no normals: faceted like the reference).
  void lathe(ExpandedPart& part, uint32_t i, const InstanceBounds& b, const glm::vec3& anchor_eye,
             uint32_t segments, float profile_tolerance) {
    std::vector<SmoothVertex>& vertices = part.vertices;
    std::vector<glm::vec2>& kept = part.kept;
    std::vector<glm::vec2>& ring = part.ring;
    const pkg::InstanceRecord& in = view->instances()[i];
    const auto all_points = view->profilePoints();
    if (in.profile_count < 2 || in.profile_first > all_points.size() ||
        in.profile_count > all_points.size() - in.profile_first)
      return;
    const auto profile = all_points.subspan(in.profile_first, in.profile_count);
    const glm::mat3 linear(in.linear[0], in.linear[1], in.linear[2], in.linear[3], in.linear[4],
                           in.linear[5], in.linear[6], in.linear[7], in.linear[8]);
    const float scale = std::max({glm::length(linear[0]), glm::length(linear[1]), glm::length(linear[2])});
    part.simplifier.simplify(profile, profile_tolerance / std::max(scale, 1e-30f), kept);
    const float sweep = in.params[0];
    const bool full = !(sweep < float(kTwoPi) * (1.0f - 1e-5f));
    const uint32_t steps =
        full ? segments
             : std::max(1u, uint32_t(std::ceil(double(segments) * double(sweep) / kTwoPi)));
    const uint32_t columns = full ? steps : steps + 1;
    ring.resize(columns);
    for (uint32_t c = 0; c < columns; ++c) {
      const double a = (full ? kTwoPi : double(sweep)) * c / steps;
      ring[c] = {static_cast<float>(std::cos(a)), static_cast<float>(std::sin(a))};
    }
    const glm::vec3 origin = anchor_eye + b.origin;
    std::vector<uint32_t>& out = part.indices[kTwoSided];
    uint32_t previous_first = 0;
    bool previous_on_axis = false;
    for (size_t j = 0; j < kept.size(); ++j) {
      const glm::vec2 q = kept[j];
      const bool on_axis = q.x == 0.0f;
      const uint32_t first = static_cast<uint32_t>(vertices.size());
      if (on_axis) {
        vertices.push_back({origin + linear * glm::vec3(0.0f, 0.0f, q.y), in.object, 0u});
      } else {
        for (const glm::vec2& cs : ring)
          vertices.push_back({origin + linear * glm::vec3(q.x * cs.x, q.x * cs.y, q.y), in.object, 0u});
      }
      if (j > 0 && !(previous_on_axis && on_axis)) {
        for (uint32_t c = 0; c < steps; ++c) {
          const uint32_t c1 = full ? (c + 1) % columns : c + 1;
          const uint32_t a = previous_first + (previous_on_axis ? 0 : c);
          const uint32_t b1 = previous_first + (previous_on_axis ? 0 : c1);
          const uint32_t c2 = first + (on_axis ? 0 : c1), d = first + (on_axis ? 0 : c);
          if (!previous_on_axis) out.insert(out.end(), {a, b1, c2});
          if (!on_axis) out.insert(out.end(), {a, c2, d});
        }
      }
      previous_first = first;
      previous_on_axis = on_axis;
    }
  }

  // Appends tube or elbow `i`, thinner than a pixel, as its silhouette: a band along the axis
  // (the centre circle in `segments` steps over its sweep) facing the eye, as wide as the tube's
  // cross-section seen from there, shaded with the normal of the tube's line nearest the eye.
  // Its two triangles cover the pixel centres the full-resolution tube would, where a one-pixel
  // line covered a whole pixel row along a tube a fifth of a pixel thick.
  void ribbon(ExpandedPart& part, uint32_t i, const InstanceBounds& b, const glm::vec3& anchor_eye,
              uint32_t segments) {
    std::vector<SmoothVertex>& vertices = part.vertices;
    const pkg::InstanceRecord& in = view->instances()[i];
    const glm::mat3 linear(in.linear[0], in.linear[1], in.linear[2], in.linear[3], in.linear[4],
                           in.linear[5], in.linear[6], in.linear[7], in.linear[8]);
    const glm::vec3 origin = anchor_eye + b.origin;
    const float* p = in.params;
    const auto type = static_cast<pkg::PrimitiveType>(in.type);
    // One cross-section: its centre, the axis direction there and the circle's two radii
    // (canonical frame).
    auto section = [&](const glm::vec3& centre, const glm::vec3& along, const glm::vec3& u,
                       const glm::vec3& w, float radius) {
      const glm::vec3 at = origin + linear * centre;
      const glm::vec3 tangent = glm::normalize(linear * along);
      const glm::vec3 to_eye = -at / std::max(glm::length(at), 1e-30f);
      glm::vec3 side = glm::cross(tangent, to_eye);
      if (glm::length(side) < 1e-6f)  // seen along its axis: a dot, any side will do
        side = glm::cross(tangent, std::abs(tangent.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0));
      side = glm::normalize(side);
      // The circle radius * (cos t * u + sin t * w), mapped, reaches this far along `side`.
      const float half = radius * std::hypot(glm::dot(linear * u, side), glm::dot(linear * w, side));
      const glm::vec3 facing = to_eye - glm::dot(to_eye, tangent) * tangent;
      const float facing_length = glm::length(facing);
      const uint32_t normal = packNormal(facing_length > 1e-6f ? facing / facing_length : to_eye);
      vertices.push_back({at - half * side, in.object, normal});
      vertices.push_back({at + half * side, in.object, normal});
    };
    const uint32_t base = static_cast<uint32_t>(vertices.size());
    uint32_t steps = 1;
    if (type == pkg::PrimitiveType::TorusSegment) {
      // Centre circle of radius p[0] in the canonical xy plane, swept p[2] radians in `segments`
      // chords that straddle the circle, as the rings do.
      const float sweep = p[2];
      steps = std::max(segments, 1u);
      const float centre_radius = p[0] * 2.0f / (1.0f + std::cos(0.5f * sweep / float(steps)));
      for (uint32_t k = 0; k <= steps; ++k) {
        const float a = sweep * float(k) / float(steps);
        const glm::vec3 radial(std::cos(a), std::sin(a), 0.0f);
        section(centre_radius * radial, {-radial.y, radial.x, 0.0f}, radial, {0.0f, 0.0f, 1.0f}, p[1]);
      }
    } else {  // cylinder (radius p[0], height p[1]) or cone (radii p[0], p[1], height p[2])
      const bool cone = type == pkg::PrimitiveType::Cone;
      const float height = cone ? p[2] : p[1];
      section({0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f}, {1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, p[0]);
      section({0.0f, 0.0f, height}, {0.0f, 0.0f, 1.0f}, {1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f},
              cone ? p[1] : p[0]);
    }
    std::vector<uint32_t>& out = part.indices[kTwoSided];
    for (uint32_t k = 0; k < steps; ++k) {
      const uint32_t a = base + 2 * k;
      out.insert(out.end(), {a, a + 1, a + 3, a, a + 3, a + 2});
    }
  }

  // Appends box-framed instance `i` (a box, or an extrusion or revolution by its box) thinner
  // than a pixel across its two shorter axes as its silhouette: a band along the longest axis
  // `axis` facing the eye, as wide as the box's cross-section seen from there, each side of the
  // line where the two long faces the eye sees meet shaded with its face's normal (the
  // fragments choose, parametricBeamFragmentShader). Two triangles show what the box's six to
  // twelve would, but for its end faces; two bands of two, one a face, made the 50M plant's
  // orbit 20 % slower (docs/benchmarks.md, "Thin beams in one band").
  void beamRibbon(ExpandedPart& part, uint32_t i, const InstanceBounds& b,
                  const glm::vec3& anchor_eye, int axis) {
    const pkg::InstanceRecord& in = view->instances()[i];
    glm::vec3 lo, hi;
    if (!instanceLocalBox(in, view->profilePoints(), lo, hi)) return;
    const glm::mat3 linear(in.linear[0], in.linear[1], in.linear[2], in.linear[3], in.linear[4],
                           in.linear[5], in.linear[6], in.linear[7], in.linear[8]);
    const glm::vec3 half = 0.5f * (hi - lo);
    const glm::vec3 axes[3] = {linear[0] * half.x, linear[1] * half.y, linear[2] * half.z};
    const glm::vec3 along = axes[axis];
    glm::vec3 u = axes[(axis + 1) % 3], w = axes[(axis + 2) % 3];
    const float along_length = glm::length(along);
    if (!(along_length > 0.0f)) return;
    const glm::vec3 tangent = along / along_length;
    const glm::vec3 centre = anchor_eye + b.centre;
    // Outward unit normals of the long faces at +u and at +w (the axes need not be orthogonal);
    // then u and w turned toward the eye, so the faces at +u and +w are the ones it sees.
    auto outward = [](const glm::vec3& n, const glm::vec3& toward) {
      const float length = glm::length(n);
      if (!(length > 0.0f)) return glm::vec3(0.0f);
      return (glm::dot(n, toward) < 0.0f ? -n : n) / length;
    };
    glm::vec3 n_u = outward(glm::cross(along, w), u), n_w = outward(glm::cross(along, u), w);
    if (glm::dot(n_u, -centre) < 0.0f) {
      u = -u;
      n_u = -n_u;
    }
    if (glm::dot(n_w, -centre) < 0.0f) {
      w = -w;
      n_w = -n_w;
    }
    const uint32_t packed_u = packNormal(n_u), packed_w = packNormal(n_w);
    std::vector<BeamVertex>& vertices = part.beam_vertices;
    // One cross-section: across `side`, the face at +u spans the edges u - w and u + w, the face
    // at +w the edges u + w and w - u; the outer edges are the silhouette, and `across` is zero
    // at the shared edge u + w.
    auto section = [&](const glm::vec3& at) {
      const glm::vec3 to_eye = -at / std::max(glm::length(at), 1e-30f);
      glm::vec3 side = glm::cross(tangent, to_eye);
      if (glm::length(side) < 1e-6f)  // seen along its axis: any side will do
        side = glm::cross(tangent, std::abs(tangent.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0));
      side = glm::normalize(side);
      const float shared = glm::dot(u + w, side);
      const float u_outer = glm::dot(u - w, side), w_outer = glm::dot(w - u, side);
      vertices.push_back({at + u_outer * side, in.object, packed_u, packed_w, -std::abs(shared - u_outer)});
      vertices.push_back({at + w_outer * side, in.object, packed_u, packed_w, std::abs(w_outer - shared)});
    };
    const auto base = static_cast<uint32_t>(vertices.size());
    section(centre - along);
    section(centre + along);
    // Outer edge of the first face at each end (base, base + 2), of the second (base + 1, + 3).
    part.indices[kBeams].insert(part.indices[kBeams].end(),
                                {base, base + 1, base + 3, base, base + 3, base + 2});
  }

  // Appends instance `i` in form `f` to its batch, positions relative to the eye.
  void expand(ExpandedPart& part, uint32_t i, const InstanceBounds& b, const glm::vec3& anchor_eye,
              const Form& f) {
    std::vector<SmoothVertex>& vertices = part.vertices;
    const pkg::InstanceRecord& in = view->instances()[i];
    const OwnedUnitMesh& owned = unitMesh(f.shape, f.a, f.b);
    const UnitMesh& mesh = owned.mesh;
    const glm::mat3 linear(in.linear[0], in.linear[1], in.linear[2], in.linear[3], in.linear[4],
                           in.linear[5], in.linear[6], in.linear[7], in.linear[8]);
    const uint32_t base = static_cast<uint32_t>(vertices.size());
    const uint32_t vertex_count = mesh.vertex_count;
    if (f.box_frame) {
      glm::vec3 lo, hi;
      if (!instanceLocalBox(in, view->profilePoints(), lo, hi)) return;
      const glm::vec3 centre = anchor_eye + b.centre, half = 0.5f * (hi - lo);
      const glm::mat3 half_axes(linear[0] * half.x, linear[1] * half.y, linear[2] * half.z);
      for (uint32_t v = 0; v < vertex_count; ++v)
        vertices.push_back(
            {centre + half_axes * glm::vec3(owned.shapes[mesh.base_vertex + v]), in.object, 0u});
    } else {
      const glm::vec3 origin = anchor_eye + b.origin;
      const auto type = static_cast<pkg::PrimitiveType>(in.type);
      const glm::mat3 normal_matrix = normalMatrix(linear);  // scale normalized away below
      for (uint32_t v = 0; v < vertex_count; ++v) {
        const glm::vec4& q = owned.shapes[mesh.base_vertex + v];
        const glm::vec3 n = normal_matrix * shapedNormal(type, f.shape, in.params, q);
        const float length = glm::length(n);
        vertices.push_back({origin + linear * shapedPoint(type, in.params, q), in.object,
                            packNormal(length > 1e-20f ? n / length : glm::vec3(0.0f))});
      }
    }
    const uint32_t count = f.capped ? mesh.all_indices : mesh.side_indices;
    std::vector<uint32_t>& out = part.indices[f.batch];
    const uint32_t* unit = owned.indices.data() + mesh.first_index;
    if (f.batch == kTwoSided || f.batch == kPoints) {
      for (uint32_t k = 0; k < count; ++k) out.push_back(base + unit[k]);
      return;
    }
    // A closed surface seen from outside: its back faces are left out here, where the eye-relative
    // positions make the test one dot product, instead of being shaded, set up and then culled
    // by llvmpipe on the render thread. The plane test is the rasterizer's own (the eye behind
    // the triangle's plane); edge-on triangles are kept.
    const float front = f.batch == kCullCw ? -1.0f : 1.0f;
    for (uint32_t k = 0; k + 2 < count; k += 3) {
      const glm::vec3& a = vertices[base + unit[k]].position;
      const glm::vec3& b1 = vertices[base + unit[k + 1]].position;
      const glm::vec3& c1 = vertices[base + unit[k + 2]].position;
      if (front * glm::dot(glm::cross(b1 - a, c1 - a), a) > 0.0f) continue;  // eye behind it
      out.insert(out.end(), {base + unit[k], base + unit[k + 1], base + unit[k + 2]});
    }
  }
};

void ParametricInstanceMeshes::recordVisible(
    const std::function<bool(const glm::vec3&, const glm::vec3&)>& box_hidden) {
  Impl& s = *impl_;
  if (box_hidden) {
    s.testAll(s.drawn, s.eye, box_hidden);
    for (size_t k = 0; k < s.drawn.size(); ++k) s.hidden_last[s.drawn[k].second] = s.test_hidden[k];
  } else {
    for (const auto& [c, i] : s.drawn) s.hidden_last[i] = 0;
  }
  s.drawn.clear();
}

uint32_t ParametricInstanceMeshes::roundedSegments(uint32_t segments) {
  return kLevels[levelIndex(segments)];
}

bool ParametricInstanceMeshes::handles(uint32_t type) { return type < kTypes; }

ParametricInstanceMeshes::ParametricInstanceMeshes(const PackageView& view,
                                                   const ParametricMeshOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.view = &view;
  s.clusters_per_run = options.clusters_per_run;
  s.primitives_per_flush = options.primitives_per_flush;
  const auto instances = view.instances();
  if (view.header().flags & pkg::kHeaderSealedRunsMarked) {
    // The preprocessor searched: the roles are the instances' flags.
    std::vector<uint8_t> roles(instances.size());
    for (size_t i = 0; i < instances.size(); ++i) roles[i] = sealedRunRole(instances[i].flags);
    std::promise<std::vector<uint8_t>> marked;
    marked.set_value(std::move(roles));
    s.runs_found = marked.get_future();
  } else {
    // Runs are found beside the bounds, the start-up's page loads and the first cut, and taken
    // by the first draw.
    s.runs_found = std::async(std::launch::async, [instances] { return findSealedRuns(instances); });
  }
  s.bounds.resize(instances.size());
  s.hidden_last.assign(instances.size(), 0);
  const auto clusters = view.clusters();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, clusters.size(), 64),
                    [&](const tbb::blocked_range<size_t>& range) {
                      for (size_t k = range.begin(); k != range.end(); ++k) {
                        const pkg::ClusterRecord& c = clusters[k];
                        if (c.kind != static_cast<uint8_t>(pkg::ClusterKind::Parametric)) continue;
                        if (c.instance_first > instances.size() ||
                            c.instance_count > instances.size() - c.instance_first)
                          continue;  // the view rejects such packages; never read past the table
                        const glm::dvec3 anchor = clusterAnchor(c);
                        for (uint32_t i = c.instance_first; i < c.instance_first + c.instance_count; ++i)
                          s.bounds[i] = boundsOf(instances[i], view.profilePoints(), anchor);
                      }
                    });
  while (glGetError() != GL_NO_ERROR) {
  }
  s.program = buildGlProgram({{GL_VERTEX_SHADER, gl::parametricSmoothVertexShader()},
                              {GL_FRAGMENT_SHADER, gl::parametricSmoothFragmentShader()}},
                             "ParametricInstanceMeshes");
  glCreateVertexArrays(1, &s.vertex_array);
  glEnableVertexArrayAttrib(s.vertex_array, 0);
  glVertexArrayAttribFormat(s.vertex_array, 0, 3, GL_FLOAT, GL_FALSE, offsetof(SmoothVertex, position));
  glVertexArrayAttribBinding(s.vertex_array, 0, 0);
  glEnableVertexArrayAttrib(s.vertex_array, 1);
  glVertexArrayAttribIFormat(s.vertex_array, 1, 1, GL_UNSIGNED_INT, offsetof(SmoothVertex, object));
  glVertexArrayAttribBinding(s.vertex_array, 1, 0);
  glEnableVertexArrayAttrib(s.vertex_array, 2);
  glVertexArrayAttribFormat(s.vertex_array, 2, 4, GL_INT_2_10_10_10_REV, GL_TRUE, offsetof(SmoothVertex, normal));
  glVertexArrayAttribBinding(s.vertex_array, 2, 0);
  s.bufferSet(0);  // the parts' buffers are bound to the vertex arrays as each is drawn
  s.beam_program = buildGlProgram({{GL_VERTEX_SHADER, gl::parametricBeamVertexShader()},
                                   {GL_FRAGMENT_SHADER, gl::parametricBeamFragmentShader()}},
                                  "ParametricInstanceMeshes (beams)");
  glCreateVertexArrays(1, &s.beam_vertex_array);
  const GLuint beams = s.beam_vertex_array;
  glEnableVertexArrayAttrib(beams, 0);
  glVertexArrayAttribFormat(beams, 0, 3, GL_FLOAT, GL_FALSE, offsetof(BeamVertex, position));
  glEnableVertexArrayAttrib(beams, 1);
  glVertexArrayAttribIFormat(beams, 1, 1, GL_UNSIGNED_INT, offsetof(BeamVertex, object));
  glEnableVertexArrayAttrib(beams, 2);
  glVertexArrayAttribFormat(beams, 2, 4, GL_INT_2_10_10_10_REV, GL_TRUE, offsetof(BeamVertex, normal_u));
  glEnableVertexArrayAttrib(beams, 3);
  glVertexArrayAttribFormat(beams, 3, 4, GL_INT_2_10_10_10_REV, GL_TRUE, offsetof(BeamVertex, normal_w));
  glEnableVertexArrayAttrib(beams, 4);
  glVertexArrayAttribFormat(beams, 4, 1, GL_FLOAT, GL_FALSE, offsetof(BeamVertex, across));
  for (GLuint attribute = 0; attribute < 5; ++attribute)
    glVertexArrayAttribBinding(beams, attribute, 0);
  if (GLenum error = glGetError(); error != GL_NO_ERROR) {
    char message[96];
    std::snprintf(message, sizeof message, "ParametricInstanceMeshes: set-up failed (GL error 0x%04x)",
                  error);
    throw std::runtime_error(message);
  }
}

ParametricInstanceMeshes::~ParametricInstanceMeshes() = default;

InstanceLodStats ParametricInstanceMeshes::draw(std::span<const uint32_t> clusters,
                                                const InstanceLodView& view,
                                                uint32_t object_color_count,
                                                std::vector<ParametricMeshInstance>& profiles) {
  InstanceLodStats stats = prepare(clusters, view, profiles);
  submit(view.view_projection, object_color_count, stats);
  return stats;
}

InstanceLodStats ParametricInstanceMeshes::prepare(std::span<const uint32_t> clusters,
                                                   const InstanceLodView& view,
                                                   std::vector<ParametricMeshInstance>& profiles) {
  Impl& s = *impl_;
  // A prepare() that was never submitted: its expansion ends before this one starts.
  s.expansion.wait();
  s.streaming = false;
  const auto records = s.view->clusters();
  Impl::FrameChoice& choice = s.choice;
  choice.view = view;
  // The frustum's side planes, eye-relative (rows of the projection: w +- x, w +- y), each
  // scaled to a unit normal so a sphere's radius compares directly.
  const glm::mat4& m = view.view_projection;
  const glm::vec4 row_x(m[0][0], m[1][0], m[2][0], m[3][0]), row_y(m[0][1], m[1][1], m[2][1], m[3][1]),
      row_w(m[0][3], m[1][3], m[2][3], m[3][3]);
  choice.planes = {row_w + row_x, row_w - row_x, row_w + row_y, row_w - row_y};
  for (glm::vec4& plane : choice.planes) plane /= std::max(glm::length(glm::vec3(plane)), 1e-30f);
  choice.pixel_scale = std::max(view.pixel_scale, 1e-9);
  choice.near_m = std::max(view.near_m, 1e-6);
  // An eye closer to a surface than the near plane reaches may see it clipped open, so back
  // faces are kept there. The rows' lengths are the reciprocals of the frustum's half extents
  // at unit distance.
  choice.near_reach = static_cast<float>(
      nearPlaneReach(choice.near_m, 1.0 / std::max(double(glm::length(glm::vec3(row_x))), 1e-6),
                     1.0 / std::max(double(glm::length(glm::vec3(row_y))), 1e-6)));
  choice.test = view.pass == InstancePass::Second && view.box_hidden;
  const float near_reach = choice.near_reach;

  s.frame.clear();
  if (view.pass == InstancePass::First) {
    s.deferred.clear();
    s.drawn.clear();
  }
  s.eye = view.eye;
  // Sealed runs hide their insides only while the eye, and the near plane around it, is outside
  // every member and closer of every sealed run (sealed_pipe_runs.h); decided once a frame.
  if (s.runs_found.valid()) s.takeSealedRuns();
  if (view.pass != InstancePass::Second) {
    s.eye_clear_of_runs = true;
    for (const Impl::RunCluster& run : s.run_clusters) {
      if (glm::any(glm::lessThan(view.eye, run.lo - double(near_reach))) ||
          glm::any(glm::greaterThan(view.eye, run.hi + double(near_reach))))
        continue;
      const pkg::ClusterRecord& r = records[run.cluster];
      const glm::vec3 eye_local(view.eye - clusterAnchor(r));
      for (uint32_t i = r.instance_first; i < r.instance_first + r.instance_count; ++i)
        if ((s.bounds[i].flags & (kRunMember | kRunCloser)) &&
            !eyeOutsideSolid(s.bounds[i], eye_local, near_reach))
          s.eye_clear_of_runs = false;
      if (!s.eye_clear_of_runs) break;
    }
  }
  s.frame_clusters.assign(clusters.begin(), clusters.end());
  // The clusters in runs, one part each; a run's part is its instances in cluster order.
  const size_t concurrency = size_t(tbb::this_task_arena::max_concurrency());
  if (view.pass != InstancePass::Second && s.clusters_per_run != 0 &&
      clusters.size() >= 2 * size_t(s.clusters_per_run)) {
    // Streamed: the runs are drawn one by one as they are done (Impl::streaming). More runs
    // than threads, so the first is drawn early and the last is short.
    const size_t runs = std::clamp<size_t>(clusters.size() / s.clusters_per_run, 2, concurrency * 8);
    if (s.parts.size() < runs) s.parts.resize(runs);
    if (s.run_done_capacity < runs) {
      s.run_done = std::make_unique<std::atomic<uint8_t>[]>(runs);
      s.run_done_capacity = runs;
    }
    for (size_t r = 0; r < runs; ++r) s.run_done[r].store(0, std::memory_order_relaxed);
    s.stream_runs = runs;
    s.next_run.store(0, std::memory_order_relaxed);
    s.stream_profiles = &profiles;
    profiles.clear();
    s.streaming = true;
    s.expansion.run([&s] {
      while (s.claimAndExpand()) {
      }
    });
    InstanceLodStats result;  // the counts come with submit()
    result.unit_meshes = s.made_count.load(std::memory_order_relaxed);
    return result;
  }
  // Whole: expanded here, on TBB (the GL thread waits for this batch), the parts appended in
  // run order so the batch is the one a single thread makes.
  const size_t runs = s.clusters_per_run == 0
                          ? 1
                          : std::clamp<size_t>(clusters.size() / s.clusters_per_run, 1, concurrency * 4);
  if (runs == 1) {
    s.expandClusters(s.frame, 0, clusters.size());
  } else {
    if (s.parts.size() < runs) s.parts.resize(runs);
    tbb::parallel_for(size_t(0), runs, [&](size_t r) { s.expandRun(r, runs); });
    for (size_t r = 0; r < runs; ++r) s.frame.append(s.parts[r]);
  }
  if (view.pass == InstancePass::Second) {
    for (const auto& [c, i] : s.deferred)
      s.consider(s.frame, c, glm::vec3(clusterAnchor(records[c]) - view.eye), i);
    s.deferred.clear();
  }
  // Read in place: place() adds to the part's batch and lists, never to to_test.
  const std::vector<std::pair<uint32_t, uint32_t>>& to_test = s.frame.to_test;
  if (!to_test.empty()) {
    s.testAll(to_test, view.eye, view.box_hidden);
    // Placed in the order considered, as without the test.
    for (size_t k = 0; k < to_test.size(); ++k) {
      const auto [c, i] = to_test[k];
      if (s.test_hidden[k]) {
        s.hidden_last[i] = 1;
        ++s.frame.stats.instances_occluded;
      } else {
        s.place(s.frame, c, glm::vec3(clusterAnchor(records[c]) - view.eye), i);
      }
    }
    s.frame.to_test.clear();
  }
  s.drawn.insert(s.drawn.end(), s.frame.drawn.begin(), s.frame.drawn.end());
  s.deferred.insert(s.deferred.end(), s.frame.deferred.begin(), s.frame.deferred.end());
  profiles.assign(s.frame.profiles.begin(), s.frame.profiles.end());
  InstanceLodStats result = s.frame.stats;
  result.instances_drawn -= profiles.size();  // counted by whoever draws them
  s.batch_instances = result.instances_drawn;
  result.unit_meshes = s.made_count.load(std::memory_order_relaxed);
  return result;
}

void ParametricInstanceMeshes::submit(const glm::mat4& view_projection, uint32_t object_color_count,
                                      InstanceLodStats& stats) {
  Impl& s = *impl_;
  for (GLuint program : {s.program, s.beam_program}) {
    glProgramUniformMatrix4fv(program, gl::kViewProjectionLocation, 1, GL_FALSE,
                              &view_projection[0][0]);
    glProgramUniform1ui(program, gl::kObjectColorCountLocation, object_color_count);
  }
  size_t unflushed = 0;
  if (s.streaming) {
    // Each run's part as soon as it is done, in run order; waiting for one, expand another.
    std::vector<ParametricMeshInstance>& profiles = *s.stream_profiles;
    for (size_t r = 0; r < s.stream_runs; ++r) {
      while (!s.run_done[r].load(std::memory_order_acquire))
        if (!s.claimAndExpand()) std::this_thread::yield();
      ExpandedPart& part = s.parts[r];
      s.drawPart(part, r, part.stats.instances_drawn - part.profiles.size(), unflushed, stats);
      s.drawn.insert(s.drawn.end(), part.drawn.begin(), part.drawn.end());
      s.deferred.insert(s.deferred.end(), part.deferred.begin(), part.deferred.end());
      profiles.insert(profiles.end(), part.profiles.begin(), part.profiles.end());
      stats.instances_drawn += part.stats.instances_drawn - part.profiles.size();
      stats.instances_culled += part.stats.instances_culled;
      stats.thin_instances += part.stats.thin_instances;
      stats.instances_occluded += part.stats.instances_occluded;
    }
    s.expansion.wait();
    s.streaming = false;
    stats.unit_meshes = s.made_count.load(std::memory_order_relaxed);
  } else {
    s.drawPart(s.frame, 0, s.batch_instances, unflushed, stats);
  }
  if (unflushed != 0) glFlush();
  glDisable(GL_CULL_FACE);
  glFrontFace(GL_CCW);
  glBindVertexArray(0);
  glUseProgram(0);
}

}  // namespace tw
