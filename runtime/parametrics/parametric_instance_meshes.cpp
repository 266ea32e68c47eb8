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
#include <stdexcept>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include "box_rows.h"
#include "camera.h"
#include "gl_program.h"
#include "parametric_instance_expansion.h"
#include "parametric_instance_forms.h"
#include "parametric_instance_scales.h"
#include "parametric_meshes.h"
#include "parametric_shaders.h"
#include "sealed_pipe_runs.h"
#include "tessellate.h"

namespace tw {

using namespace instance_forms;

// What expanding a run of clusters produces: prepare() splits the frame's clusters into runs
// expanded on TBB, each into a part of its own, and appends the parts in cluster order, so the
// batch is the one a single thread makes.
struct ExpandedPart {
  InstanceBatch batch;
  // Drawn (both passes), hidden last frame (first pass), to test (second pass): cluster, instance.
  std::vector<std::pair<uint32_t, uint32_t>> drawn, deferred, to_test;
  std::vector<ParametricMeshInstance> profiles;
  InstanceLodStats stats;
  LatheScratch lathe;
  std::vector<uint32_t> selected;  // a cluster's instances that may show (InstanceScaleIndex)

  void clear() {
    batch.clear();
    drawn.clear();
    deferred.clear();
    to_test.clear();
    profiles.clear();
    stats = {};
  }
  // Appends `part` after this one's contents.
  void append(const ExpandedPart& part) {
    batch.append(part.batch);
    drawn.insert(drawn.end(), part.drawn.begin(), part.drawn.end());
    deferred.insert(deferred.end(), part.deferred.begin(), part.deferred.end());
    to_test.insert(to_test.end(), part.to_test.begin(), part.to_test.end());
    profiles.insert(profiles.end(), part.profiles.begin(), part.profiles.end());
    stats.instances_drawn += part.stats.instances_drawn;
    stats.instances_culled += part.stats.instances_culled;
    stats.thin_instances += part.stats.thin_instances;
    stats.instances_occluded += part.stats.instances_occluded;
    stats.instances_tested += part.stats.instances_tested;
  }
};

struct ParametricInstanceMeshes::Impl {
  const PackageView* view = nullptr;
  std::vector<InstanceBounds> bounds;  // by instance index; a row's first member: the row's
  // Rows of boxes, by first member, and that member's own bounds (drawn on its own when the row
  // is thin or nothing as a whole).
  std::vector<BoxRow> rows;
  std::vector<InstanceBounds> row_first_bounds;
  // The other members, each with its row's cluster, by instance: a member is left to its row
  // when the row's cluster is among the frame's, and draws itself otherwise.
  std::vector<std::pair<uint32_t, uint32_t>> row_member_clusters;
  std::vector<uint8_t> cluster_in_frame;      // by cluster: this frame's passes so far
  std::vector<uint32_t> clusters_in_frame;    // the clusters set there, to clear
  bool leftToItsRow(uint32_t i) const {
    const auto at = std::lower_bound(row_member_clusters.begin(), row_member_clusters.end(),
                                     std::pair<uint32_t, uint32_t>(i, 0));
    return at != row_member_clusters.end() && at->first == i && cluster_in_frame[at->second];
  }
  // The lists of instances drawn, deferred and left for the test hold entries: an instance
  // index, with kAlone set for a row's member considered on its own (considerMembers), not as
  // its row (a row's first member then has row_first_bounds, not the row's bounds).
  static constexpr uint32_t kAlone = 1u << 31;
  const InstanceBounds& entryBounds(uint32_t entry) const {
    const uint32_t i = entry & ~kAlone;
    if ((entry & kAlone) && bounds[i].row >= 2) return row_first_bounds[rowOf(i)];
    return bounds[i];
  }
  // The row whose first member is instance `i`.
  size_t rowOf(uint32_t i) const {
    return size_t(std::lower_bound(rows.begin(), rows.end(), i,
                                   [](const BoxRow& row, uint32_t at) {
                                     return row.instances.front() < at;
                                   }) -
                  rows.begin());
  }
  // The scales at which each instance shows: built with the bounds for InstanceLodView's
  // default thresholds, and again by prepare() for a frame whose thresholds differ.
  bool use_scale_index = true;
  InstanceScaleIndex scales;
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
  GLuint point_program = 0;  // the points' batch: shaded per vertex
  GLuint row_program = 0, row_vertex_array = 0;  // rows of boxes: the member per fragment
  // The GL buffers of each part drawn in a frame (set 0 for a batch drawn whole): a part's are
  // filled while llvmpipe may still read the previous part's.
  struct BufferSet {
    GLuint vertices = 0, beam_vertices = 0, row_vertices = 0, indices = 0;
  };
  std::vector<BufferSet> buffer_sets;
  BufferSet& bufferSet(size_t k) {
    while (buffer_sets.size() <= k) {
      BufferSet set;
      glCreateBuffers(1, &set.vertices);
      glCreateBuffers(1, &set.beam_vertices);
      glCreateBuffers(1, &set.row_vertices);
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
  // instances left for the second pass, and every instance drawn (cluster, entry; kAlone).
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
                          const InstanceBounds& b = entryBounds(i);
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
    glDeleteProgram(point_program);
    glDeleteProgram(row_program);
    for (const BufferSet& set : buffer_sets) {
      glDeleteBuffers(1, &set.vertices);
      glDeleteBuffers(1, &set.beam_vertices);
      glDeleteBuffers(1, &set.row_vertices);
      glDeleteBuffers(1, &set.indices);
    }
    glDeleteVertexArrays(1, &vertex_array);
    glDeleteVertexArrays(1, &beam_vertex_array);
    glDeleteVertexArrays(1, &row_vertex_array);
  }

  // The distance of instance `b` (its centre at `centre`, eye-relative) for its level of detail.
  double distanceOf(const InstanceBounds& b, const glm::vec3& centre) const {
    return std::max(double(glm::length(centre)) - b.radius, choice.near_m);
  }

  // Draws one visible instance of cluster `c` (anchor_eye: its anchor relative to the eye) into
  // `part`. Called from several threads at once, each with its own part.
  void place(ExpandedPart& part, uint32_t c, const glm::vec3& anchor_eye, uint32_t entry) {
    const uint32_t i = entry & ~kAlone;
    if (!(entry & kAlone) && bounds[i].row >= 2) {
      double distance = 0.0;
      float metres_per_px = 0.0f;
      placeRow(part, c, anchor_eye, i, formOf(bounds[i], anchor_eye, distance, metres_per_px));
      return;
    }
    placeOne(part, c, anchor_eye, i, entryBounds(entry), view->instances()[i], entry);
  }

  // The form of an instance with bounds `b` at its distance (set, with the metres a pixel spans
  // there).
  Form formOf(const InstanceBounds& b, const glm::vec3& anchor_eye, double& distance,
              float& metres_per_px) const {
    distance = distanceOf(b, anchor_eye + b.centre);
    const double px_per_m = choice.pixel_scale / distance;
    metres_per_px = static_cast<float>(1.0 / px_per_m);
    return chooseForm(b, static_cast<float>(std::max(choice.view.tolerance_px, 1e-3)) * metres_per_px,
                      static_cast<float>(choice.view.thin_px) * metres_per_px,
                      static_cast<float>(choice.view.min_thin_px) * metres_per_px);
  }

  // Whether the row with bounds `b` and form `form` at its distance is drawn whole: one box, one
  // band, or nothing. Otherwise its members are drawn one by one, and culled one by one too.
  static bool drawnWhole(const Form& form, const InstanceBounds& b, const BoxRow& row) {
    return form.shape == Shape::None ||
           (form.shape == Shape::Box && b.type == uint8_t(pkg::PrimitiveType::Box)) ||
           (form.shape == Shape::Ribbon && form.box_frame && form.long_axis == row.axis);
  }

  // A row whose first member is `i` (bounds[i] are the row's), drawn whole in `form` (one that
  // drawnWhole accepts): nothing, one box when the row of boxes is a box at its distance, or one
  // band when the row is thin across its own axis (appendBeamRibbon). consider() sends every
  // other row member by member, and a row's form is the same in both passes of a frame.
  // Recorded drawn as the row: the pyramid's tests take its box.
  void placeRow(ExpandedPart& part, uint32_t c, const glm::vec3& anchor_eye, uint32_t i,
                Form form) {
    InstanceLodStats& stats = part.stats;
    const InstanceBounds& b = bounds[i];
    const BoxRow& row = rows[rowOf(i)];
    const uint32_t members = uint32_t(row.instances.size());
    if (form.shape == Shape::None) {
      stats.instances_culled += members;
      return;
    }
    if (choice.view.pass != InstancePass::All) part.drawn.push_back({c, i});
    stats.instances_drawn += members;
    if (form.shape == Shape::Box) {
      if (!choice.view.keep_back_faces)
        cullBackFaces(form, b, eyeOutsideSolid(b, -anchor_eye, choice.near_reach), false);
      appendBoxRow(part.batch, row.record, b, anchor_eye, form, unitMesh(form.shape, form.a, form.b),
                   members, row.axis);
      return;
    }
    stats.thin_instances += members;
    appendBeamRibbon(part.batch, row.record, b, anchor_eye, row.axis, members);
  }

  // Instance `i` of cluster `c`, bounds `b`, record `in`; listed drawn as `entry`.
  void placeOne(ExpandedPart& part, uint32_t c, const glm::vec3& anchor_eye, uint32_t i,
                const InstanceBounds& b, const pkg::InstanceRecord& in, uint32_t entry) {
    InstanceLodStats& stats = part.stats;
    double distance = 0.0;
    float metres_per_px = 0.0f;
    Form form = formOf(b, anchor_eye, distance, metres_per_px);
    if (form.shape == Shape::None) {
      ++stats.instances_culled;
      return;
    }
    if (form.shape != Shape::Point && form.shape != Shape::Ribbon && !choice.view.keep_back_faces)
      cullBackFaces(form, b, eyeOutsideSolid(b, -anchor_eye, choice.near_reach),
                    ((b.flags & kRunMember) && eye_clear_of_runs) ||
                        (!(b.flags & kCapped) && tubeInsideHidden(b, -anchor_eye, choice.near_reach)));
    if (choice.view.pass != InstancePass::All) part.drawn.push_back({c, entry});
    ++stats.instances_drawn;
    if (form.shape == Shape::Profile) {
      FaceCull cull = FaceCull::None;
      if ((b.flags & kClosedProfile) && !choice.view.keep_back_faces &&
          eyeOutsideSolid(b, -anchor_eye, choice.near_reach))
        cull = (b.flags & kMirrored) ? FaceCull::BackOfCw : FaceCull::BackOfCcw;
      part.profiles.push_back({c, i, distance, cull});
      return;
    }
    stats.thin_instances += form.shape == Shape::Ribbon || form.shape == Shape::Point;
    if (form.shape == Shape::Ribbon) {
      if (form.box_frame)
        appendBeamRibbon(part.batch, in, b, anchor_eye, form.long_axis);
      else
        appendTubeRibbon(part.batch, in, b, anchor_eye, kLevels[form.a]);
      return;
    }
    if (form.shape == Shape::Point) {
      // A point is its instance's box centre, which the bounds hold: placed without a unit mesh,
      // the instance's box or its transform (some 18,000 of the 50M orbit's 47,000 instances a
      // frame are points).
      appendPoint(part.batch, in.object, anchor_eye + b.centre);
      return;
    }
    if (form.shape == Shape::Lathe) {
      appendLathe(part.batch, part.lathe, in, view->profilePoints(), b, anchor_eye, kLevels[form.a],
                  0.5f * static_cast<float>(std::max(choice.view.tolerance_px, 1e-3)) * metres_per_px);
      return;
    }
    appendSurface(part.batch, in, view->profilePoints(), b, anchor_eye, form,
                  unitMesh(form.shape, form.a, form.b));
  }

  // Whether bounds `b` (anchor at `anchor_eye`) lie outside the frustum or under the smallest
  // feature.
  bool outsideView(const InstanceBounds& b, const glm::vec3& anchor_eye) const {
    const glm::vec3 centre = anchor_eye + b.centre;
    const double px_per_m = choice.pixel_scale / distanceOf(b, centre);
    bool outside = 2.0 * b.radius * px_per_m < choice.view.min_feature_px;
    for (const glm::vec4& plane : choice.planes)
      outside = outside || glm::dot(glm::vec3(plane), centre) + plane.w < -b.radius;
    return outside;
  }

  // One instance of cluster `c` (an entry: kAlone set for a row's first member on its own):
  // culled, deferred, left for the pyramid's test, or placed. A row not drawn whole at its
  // distance goes member by member (considerMembers).
  void consider(ExpandedPart& part, uint32_t c, const glm::vec3& anchor_eye, uint32_t entry) {
    InstanceLodStats& stats = part.stats;
    const uint32_t i = entry & ~kAlone;
    const InstanceBounds& b = entryBounds(entry);
    if (!(b.flags & kValid) || (!(entry & kAlone) && b.row == kDrawnWithRow && leftToItsRow(i)))
      return;
    if (outsideView(b, anchor_eye)) {
      ++stats.instances_tested;
      ++stats.instances_culled;
      return;
    }
    const bool row_head = !(entry & kAlone) && b.row >= 2;
    // An instance this pass skips (hidden, or ghosted in the opaque pass) costs nothing; a row
    // drawn whole still goes, and its fragments leave out the skipped members
    // (parametric_shaders.h).
    if (!row_head && choice.view.objects &&
        !drawnIn(choice.view.objects->flags(view->instances()[i].object), choice.view.surface))
      return;
    Form row_form;
    if (row_head) {
      double distance = 0.0;
      float metres_per_px = 0.0f;
      const BoxRow& row = rows[rowOf(i)];
      row_form = formOf(b, anchor_eye, distance, metres_per_px);
      if (!drawnWhole(row_form, b, row)) {
        considerMembers(part, c, anchor_eye, row);
        return;
      }
    }
    ++stats.instances_tested;
    if (choice.view.pass == InstancePass::First && hidden_last[i]) {
      part.deferred.push_back({c, entry});  // hidden last frame: the second pass tests it
      return;
    }
    if (choice.test) {
      part.to_test.push_back({c, entry});
      return;
    }
    if (row_head)
      placeRow(part, c, anchor_eye, i, row_form);
    else
      placeOne(part, c, anchor_eye, i, b, view->instances()[i], entry);
  }

  // The members of `row` (first member's cluster `c`, its anchor at `anchor_eye`), each
  // considered on its own, with its own bounds and cluster: a long row of beams seen close by
  // is culled beam by beam, by the frustum and by the pyramid, as its beams are without rows.
  void considerMembers(ExpandedPart& part, uint32_t c, const glm::vec3& anchor_eye,
                       const BoxRow& row) {
    const auto records = view->clusters();
    for (size_t k = 0; k < row.instances.size(); ++k) {
      const uint32_t m = row.instances[k], cluster = row.member_clusters[k];
      const glm::vec3 member_anchor_eye =
          cluster == c ? anchor_eye : glm::vec3(clusterAnchor(records[cluster]) - choice.view.eye);
      consider(part, cluster, member_anchor_eye, m | kAlone);
    }
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
      uint32_t skipped = 0;
      if (use_scale_index && scales.select(c, anchor_eye, choice.pixel_scale, choice.near_m,
                                           part.selected, skipped)) {
        part.stats.instances_culled += skipped;  // as consider() would count them
        for (uint32_t i : part.selected) consider(part, c, anchor_eye, i);
        continue;
      }
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
    run_done[r].notify_all();
    return true;
  }

  // Uploads `part` into buffer set `set` and draws its batches, adding to `stats`. A far view's
  // primitives go in draws of at most primitives_per_flush, each flushed once that many have
  // gone since the last flush (`unflushed` carries the count from part to part): llvmpipe's
  // rasterizer threads start on a scene only when it is flushed, and until then the submitting
  // thread shades and bins every vertex alone (docs/runtime.md, "Overlap"). A near view's
  // (four or more primitives an instance) goes whole: every extra scene then reloads and stores
  // the many tiles its large triangles cover, and on the walked decks parts were 5 % slower.
  void drawPart(InstanceBatch& part, size_t set_index, uint64_t part_instances, size_t& unflushed,
                InstanceLodStats& stats) {
    if (part.vertices.empty() && part.beam_vertices.empty() && part.row_vertices.empty()) return;
    all_indices.clear();
    std::array<size_t, kBatchCount + 1> first{};
    for (uint32_t batch = 0; batch < kBatchCount; ++batch) {
      first[batch] = all_indices.size();
      all_indices.insert(all_indices.end(), part.indices[batch].begin(), part.indices[batch].end());
    }
    first[kBatchCount] = all_indices.size();
    const size_t primitives = part.primitives();
    const bool in_parts =
        primitives_per_flush != 0 && primitives < 4 * std::max<uint64_t>(part_instances, 1);
    const BufferSet& set = bufferSet(set_index);
    glNamedBufferData(set.vertices, GLsizeiptr(part.vertices.size() * sizeof(SmoothVertex)),
                      part.vertices.data(), GL_STREAM_DRAW);
    glNamedBufferData(set.beam_vertices, GLsizeiptr(part.beam_vertices.size() * sizeof(BeamVertex)),
                      part.beam_vertices.data(), GL_STREAM_DRAW);
    glNamedBufferData(set.row_vertices, GLsizeiptr(part.row_vertices.size() * sizeof(RowVertex)),
                      part.row_vertices.data(), GL_STREAM_DRAW);
    glNamedBufferData(set.indices, GLsizeiptr(all_indices.size() * sizeof(uint32_t)),
                      all_indices.data(), GL_STREAM_DRAW);
    glVertexArrayVertexBuffer(vertex_array, 0, set.vertices, 0, sizeof(SmoothVertex));
    glVertexArrayElementBuffer(vertex_array, set.indices);
    glVertexArrayVertexBuffer(beam_vertex_array, 0, set.beam_vertices, 0, sizeof(BeamVertex));
    glVertexArrayElementBuffer(beam_vertex_array, set.indices);
    glVertexArrayVertexBuffer(row_vertex_array, 0, set.row_vertices, 0, sizeof(RowVertex));
    glVertexArrayElementBuffer(row_vertex_array, set.indices);
    glUseProgram(program);
    glBindVertexArray(vertex_array);
    for (uint32_t batch = 0; batch < kBatchCount; ++batch) {
      const size_t count = first[batch + 1] - first[batch];
      if (count == 0) continue;
      if (batch == kPoints) glUseProgram(point_program);
      if (batch == kRows) {  // vertices and a program of their own; back faces left out already
        glUseProgram(row_program);
        glBindVertexArray(row_vertex_array);
      }
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
      // batch went in flushed parts (commit 080f873); near views' batches go whole
      // (docs/design-notes.md, "Every batch in flushed parts").
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
    part.clear();
  }

  // Safe to call from several threads at once: a mesh is made once, under the mutex, and read
  // without it once published.
  const OwnedUnitMesh& unitMesh(Shape shape, uint32_t a, uint32_t b) {
    std::atomic<const OwnedUnitMesh*>& slot =
        unit_slots[(size_t(shape) * kLevels.size() + a) * kLevels.size() + b];
    if (const OwnedUnitMesh* mesh = slot.load(std::memory_order_acquire)) return *mesh;
    std::lock_guard lock(unit_mutex);
    if (const OwnedUnitMesh* mesh = slot.load(std::memory_order_relaxed)) return *mesh;
    auto owned = std::make_unique<OwnedUnitMesh>(makeUnitMesh(shape, a, b));
    made.push_back(std::move(owned));
    made_count.store(static_cast<uint32_t>(made.size()), std::memory_order_relaxed);
    slot.store(made.back().get(), std::memory_order_release);
    return *made.back();
  }
};

void ParametricInstanceMeshes::recordVisible(
    const std::function<bool(const glm::vec3&, const glm::vec3&)>& box_hidden) {
  Impl& s = *impl_;
  if (box_hidden) {
    s.testAll(s.drawn, s.eye, box_hidden);
    for (size_t k = 0; k < s.drawn.size(); ++k)
      s.hidden_last[s.drawn[k].second & ~Impl::kAlone] = s.test_hidden[k];
  } else {
    for (const auto& [c, i] : s.drawn) s.hidden_last[i & ~Impl::kAlone] = 0;
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
  s.use_scale_index = options.scale_index;
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
  // Rows of boxes: only where the preprocessor marked covered faces (the faces between members),
  // and the instance indices leave Impl::kAlone free.
  if (options.box_rows && (view.header().flags & pkg::kHeaderCoveredFacesMarked) &&
      instances.size() < Impl::kAlone) {
    s.rows = findBoxRows(instances, clusters, view.profilePoints());
    s.row_first_bounds.reserve(s.rows.size());
    for (const BoxRow& row : s.rows) {
      const uint32_t first = row.instances.front();
      s.row_first_bounds.push_back(s.bounds[first]);
      InstanceBounds whole = boundsOf(row.record, view.profilePoints(), clusterAnchor(clusters[row.cluster]));
      if (!(whole.flags & kValid)) continue;  // drawn one by one
      whole.row = static_cast<uint8_t>(row.instances.size());
      s.bounds[first] = whole;
      for (size_t k = 1; k < row.instances.size(); ++k) {
        s.bounds[row.instances[k]].row = kDrawnWithRow;
        s.row_member_clusters.push_back({row.instances[k], row.cluster});
      }
    }
    std::sort(s.row_member_clusters.begin(), s.row_member_clusters.end());
  }
  s.cluster_in_frame.assign(clusters.size(), 0);
  if (s.use_scale_index) {
    const InstanceLodView defaults;
    s.scales.build(clusters, s.bounds,
                   {defaults.thin_px, defaults.min_thin_px, defaults.min_feature_px});
  }
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
  s.point_program = buildGlProgram({{GL_VERTEX_SHADER, gl::parametricPointVertexShader()},
                                    {GL_FRAGMENT_SHADER, gl::parametricPointFragmentShader()}},
                                   "ParametricInstanceMeshes (points)");
  s.row_program = buildGlProgram({{GL_VERTEX_SHADER, gl::parametricRowVertexShader()},
                                  {GL_FRAGMENT_SHADER, gl::parametricRowFragmentShader()}},
                                 "ParametricInstanceMeshes (rows)");
  glCreateVertexArrays(1, &s.row_vertex_array);
  const GLuint rows = s.row_vertex_array;
  glEnableVertexArrayAttrib(rows, 0);
  glVertexArrayAttribFormat(rows, 0, 3, GL_FLOAT, GL_FALSE, offsetof(RowVertex, position));
  glEnableVertexArrayAttrib(rows, 1);
  glVertexArrayAttribIFormat(rows, 1, 1, GL_UNSIGNED_INT, offsetof(RowVertex, object));
  glEnableVertexArrayAttrib(rows, 2);
  glVertexArrayAttribFormat(rows, 2, 1, GL_FLOAT, GL_FALSE, offsetof(RowVertex, along));
  glEnableVertexArrayAttrib(rows, 3);
  glVertexArrayAttribIFormat(rows, 3, 1, GL_UNSIGNED_INT, offsetof(RowVertex, last));
  for (GLuint attribute = 0; attribute < 4; ++attribute)
    glVertexArrayAttribBinding(rows, attribute, 0);
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
  glEnableVertexArrayAttrib(beams, 5);
  glVertexArrayAttribFormat(beams, 5, 1, GL_FLOAT, GL_FALSE, offsetof(BeamVertex, along));
  glEnableVertexArrayAttrib(beams, 6);
  glVertexArrayAttribIFormat(beams, 6, 1, GL_UNSIGNED_INT, offsetof(BeamVertex, last));
  for (GLuint attribute = 0; attribute < 7; ++attribute)
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
  const InstanceScaleIndex::Thresholds thresholds{view.thin_px, view.min_thin_px,
                                                  view.min_feature_px};
  if (s.use_scale_index && !s.scales.builtFor(thresholds))
    s.scales.build(records, s.bounds, thresholds);
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
  // The clusters of the frame's passes so far: a row whose cluster is among them draws its
  // members (Impl::leftToItsRow).
  if (view.pass != InstancePass::Second) {
    for (uint32_t c : s.clusters_in_frame) s.cluster_in_frame[c] = 0;
    s.clusters_in_frame.clear();
  }
  for (uint32_t c : clusters)
    if (c < s.cluster_in_frame.size() && !s.cluster_in_frame[c]) {
      s.cluster_in_frame[c] = 1;
      s.clusters_in_frame.push_back(c);
    }
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
        s.hidden_last[i & ~Impl::kAlone] = 1;
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
  for (GLuint program : {s.program, s.beam_program, s.point_program, s.row_program}) {
    glProgramUniformMatrix4fv(program, gl::kViewProjectionLocation, 1, GL_FALSE,
                              &view_projection[0][0]);
    glProgramUniform1ui(program, gl::kObjectColorCountLocation, object_color_count);
  }
  size_t unflushed = 0;
  if (s.streaming) {
    // Each run's part as soon as it is done, in run order; waiting for one, expand another.
    std::vector<ParametricMeshInstance>& profiles = *s.stream_profiles;
    for (size_t r = 0; r < s.stream_runs; ++r) {
      // Nothing left to claim: sleep until the run's worker is done, leaving the core to
      // llvmpipe's rasterizer threads (a spin with yield kept it).
      while (!s.run_done[r].load(std::memory_order_acquire))
        if (!s.claimAndExpand()) s.run_done[r].wait(0, std::memory_order_acquire);
      ExpandedPart& part = s.parts[r];
      s.drawPart(part.batch, r, part.stats.instances_drawn - part.profiles.size(), unflushed, stats);
      s.drawn.insert(s.drawn.end(), part.drawn.begin(), part.drawn.end());
      s.deferred.insert(s.deferred.end(), part.deferred.begin(), part.deferred.end());
      profiles.insert(profiles.end(), part.profiles.begin(), part.profiles.end());
      stats.instances_drawn += part.stats.instances_drawn - part.profiles.size();
      stats.instances_culled += part.stats.instances_culled;
      stats.thin_instances += part.stats.thin_instances;
      stats.instances_occluded += part.stats.instances_occluded;
      stats.instances_tested += part.stats.instances_tested;
    }
    s.expansion.wait();
    s.streaming = false;
    stats.unit_meshes = s.made_count.load(std::memory_order_relaxed);
  } else {
    s.drawPart(s.frame.batch, 0, s.batch_instances, unflushed, stats);
  }
  if (unflushed != 0) glFlush();
  glDisable(GL_CULL_FACE);
  glFrontFace(GL_CCW);
  glBindVertexArray(0);
  glUseProgram(0);
}

}  // namespace tw
