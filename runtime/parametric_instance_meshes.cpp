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
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "camera.h"
#include "gl_program.h"
#include "parametric_meshes.h"
#include "parametric_shaders.h"
#include "parametric_unit_meshes.h"
#include "profile_simplifier.h"
#include "sealed_pipe_runs.h"
#include "tessellate.h"

namespace tw {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr uint32_t kTypes = 7;  // cylinder, cone, sphere, torus segment, box, extrusion, revolution

// Segment counts a unit mesh may have: steps of at most 1.25x, up to kMaxArcSegments.
constexpr std::array<uint32_t, 28> kLevels = {1,   2,   3,   4,   5,   6,   8,   10,  12,  16,
                                              20,  24,  32,  40,  48,  64,  80,  96,  128, 160,
                                              192, 256, 320, 384, 512, 640, 768, 1024};
static_assert(kLevels.back() == kMaxArcSegments);

const float kMaxRingSwell = ringSwell(3);

uint32_t levelIndex(uint32_t segments) {
  const auto it = std::lower_bound(kLevels.begin(), kLevels.end(), segments);
  return it == kLevels.end() ? uint32_t(kLevels.size() - 1) : uint32_t(it - kLevels.begin());
}

// The unit meshes. Surfaces are triangles; instances thin in every direction degrade to a point.
// Ribbon: a tube or elbow thinner than a pixel, drawn as its silhouette (a band facing the eye
// along the axis or centre circle, as wide as the tube seen from there), built here each frame.
// Profile: an extrusion's or a revolution's surface, drawn from its cluster's mesh
// (ParametricMeshes::drawInstances), not here.
// Lathe: a revolution swept here from its own profile (simplified to the tolerance), not from a
// unit mesh. None: thinner than the smallest thin form worth drawing (InstanceLodView::min_thin_px).
enum class Shape : uint32_t { Tube, Sphere, Torus, Box, Ribbon, Point, Profile, Lathe, None };

Shape surfaceOf(uint32_t type) {
  switch (static_cast<pkg::PrimitiveType>(type)) {
    case pkg::PrimitiveType::Sphere: return Shape::Sphere;
    case pkg::PrimitiveType::TorusSegment: return Shape::Torus;
    case pkg::PrimitiveType::Box: return Shape::Box;
    case pkg::PrimitiveType::Extrusion:
    case pkg::PrimitiveType::Revolution: return Shape::Profile;
    default: return Shape::Tube;
  }
}

// The per-frame batches: triangles by back-face culling, points.
enum Batch : uint32_t { kTwoSided, kCullCcw, kCullCw, kPoints, kBatchCount };

constexpr uint8_t kValid = 1, kCapped = 2, kMirrored = 4;
constexpr uint8_t kRectangleProfile = 8;  // an extrusion whose profile fills its box: a box
// The transform's columns are perpendicular (rotation, mirroring, scaling along the axes; no
// shear): a tube's cross-sections are then perpendicular to its axis, within its largest radius.
constexpr uint8_t kOrthogonalAxes = 16;
// Roles in a sealed pipe run (sealed_pipe_runs.h): an open part whose inside cannot be seen from
// outside the run, and a closed solid that closes one of its ends.
constexpr uint8_t kRunMember = 32, kRunCloser = 64;
// An extrusion whose triangles enclose its solid (extrusionEnclosesSolid): from outside, its back
// faces are hidden by its front faces.
constexpr uint8_t kClosedProfile = 128;

// What the per-frame choice reads of an instance, prepared once.
struct InstanceBounds {
  glm::vec3 centre{0.0f};  // bounding-sphere centre, relative to the cluster's anchor
  float radius = 0.0f;     // bounding-sphere radius, metres
  // By type, in metres: tube (largest radius, height, -), sphere (radius, -, -), torus (major + minor
  // radius, minor radius, sweep in radians), box, extrusion, revolution (the half extents of the
  // canonical box along its axes).
  std::array<float, 3> size{};
  glm::vec3 extent{0.0f};  // half sizes of the world-axis box about centre
  glm::vec3 origin{0.0f};  // the canonical frame's origin, relative to the anchor
  glm::vec3 axis{0.0f};    // tubes: from the base centre (origin) to the top centre
  uint8_t type = 0;
  uint8_t flags = 0;       // kValid, kCapped, kMirrored, kRectangleProfile, kOrthogonalAxes,
                           // kRunMember, kRunCloser, kClosedProfile
};

// An open tube's inside can only be seen through its end discs, so from an eye between the two
// end planes and outside the tube its back faces are hidden by its front faces. `eye` is
// relative to the anchor.
bool tubeInsideHidden(const InstanceBounds& b, const glm::vec3& eye, float margin) {
  if (!(b.flags & kOrthogonalAxes)) return false;
  const glm::vec3 to_eye = eye - b.origin;
  const float length2 = glm::dot(b.axis, b.axis);
  if (!(length2 > 0.0f)) return false;
  const float t = glm::dot(to_eye, b.axis) / length2;
  if (t < 0.0f || t > 1.0f) return false;
  return glm::length(to_eye - t * b.axis) > kMaxRingSwell * b.size[0] + margin;
}

// Whether `eye` (relative to the anchor) lies more than `margin` outside the instance's solid,
// which makes the back faces of its closed surface hidden by its front faces. The bounding sphere
// alone is too cautious for long or flat instances: standing under a deck or beside a 12 m pipe
// run, the eye is inside their spheres though far outside the solids, and drawing both faces
// doubled what llvmpipe rasterized of them (docs/parametrics.md, "Back faces"). So also the
// world-axis box (which holds every handled shape) and, for tubes, the capped cylinder: farther
// from the axis than the widest ring reaches, or beyond an end plane.
bool eyeOutsideSolid(const InstanceBounds& b, const glm::vec3& eye, float margin) {
  const glm::vec3 from_centre = eye - b.centre;
  if (glm::length(from_centre) > b.radius + margin) return true;
  const glm::vec3 d = glm::abs(from_centre) - b.extent;
  if (std::max({d.x, d.y, d.z}) > margin) return true;
  if (surfaceOf(b.type) != Shape::Tube || !(b.flags & kOrthogonalAxes)) return false;
  const float length = glm::length(b.axis);
  if (!(length > 0.0f)) return false;
  const glm::vec3 to_eye = eye - b.origin;
  const float along = glm::dot(to_eye, b.axis) / length;  // metres from the base plane
  if (along < -margin || along > length + margin) return true;
  return glm::length(to_eye - (along / length) * b.axis) > kMaxRingSwell * b.size[0] + margin;
}

InstanceBounds boundsOf(const pkg::InstanceRecord& in, std::span<const glm::vec2> profile_points,
                        const glm::dvec3& anchor) {
  InstanceBounds b;
  glm::vec3 lo, hi;
  if (!ParametricInstanceMeshes::handles(in.type) || !instanceLocalBox(in, profile_points, lo, hi)) return b;
  // Straddling rings reach out past the true circle: the bounds take in the most they may.
  const float* p = in.params;
  const float swell = kMaxRingSwell - 1.0f;
  glm::vec3 grow(0.0f);
  switch (static_cast<pkg::PrimitiveType>(in.type)) {
    case pkg::PrimitiveType::Cylinder: grow = {swell * p[0], swell * p[0], 0.0f}; break;
    case pkg::PrimitiveType::Cone:
      grow = {swell * std::max(p[0], p[1]), swell * std::max(p[0], p[1]), 0.0f};
      break;
    case pkg::PrimitiveType::TorusSegment: grow = glm::vec3(swell * p[1]); break;
    default: break;
  }
  lo -= grow;
  hi += grow;
  const glm::mat3 linear(in.linear[0], in.linear[1], in.linear[2], in.linear[3], in.linear[4],
                         in.linear[5], in.linear[6], in.linear[7], in.linear[8]);
  const glm::vec3 scale(glm::length(linear[0]), glm::length(linear[1]), glm::length(linear[2]));
  const float largest = std::max({scale.x, scale.y, scale.z});
  // Chordal error scales with the largest stretch of the circle's plane (all axes for spheres).
  const float cross = std::max(scale.x, scale.y);
  const glm::dvec3 origin(in.origin[0], in.origin[1], in.origin[2]);
  b.centre = glm::vec3(origin - anchor) + linear * (0.5f * (lo + hi));
  b.radius = glm::dot(scale, 0.5f * (hi - lo));  // conservative for any linear map
  const glm::vec3 half = 0.5f * (hi - lo);
  for (int axis = 0; axis < 3; ++axis)  // |linear| times the half sizes, row by row
    b.extent[axis] = std::abs(linear[0][axis]) * half.x + std::abs(linear[1][axis]) * half.y +
                     std::abs(linear[2][axis]) * half.z;
  switch (static_cast<pkg::PrimitiveType>(in.type)) {
    case pkg::PrimitiveType::Cylinder: b.size = {p[0] * cross, p[1] * scale.z, 0.0f}; break;
    case pkg::PrimitiveType::Cone: b.size = {std::max(p[0], p[1]) * cross, p[2] * scale.z, 0.0f}; break;
    case pkg::PrimitiveType::Sphere: b.size = {p[0] * largest, 0.0f, 0.0f}; break;
    case pkg::PrimitiveType::TorusSegment: b.size = {(p[0] + p[1]) * cross, p[1] * largest, p[2]}; break;
    case pkg::PrimitiveType::Box: b.size = {p[0] * scale.x, p[1] * scale.y, p[2] * scale.z}; break;
    default: {  // extrusion, revolution: their box
      const glm::vec3 world_half = half * scale;
      b.size = {world_half.x, world_half.y, world_half.z};
      break;
    }
  }
  const bool finite = std::isfinite(b.radius) && std::isfinite(b.centre.x) &&
                      std::isfinite(b.centre.y) && std::isfinite(b.centre.z);
  b.origin = glm::vec3(origin - anchor);
  if (in.type == static_cast<uint32_t>(pkg::PrimitiveType::Cylinder) ||
      in.type == static_cast<uint32_t>(pkg::PrimitiveType::Cone))
    b.axis = linear[2] * b.size[1] / std::max(scale.z, 1e-30f);
  b.type = static_cast<uint8_t>(in.type);
  b.flags = (finite ? kValid : 0) | ((in.flags & pkg::kInstanceCapped) ? kCapped : 0) |
            (glm::determinant(linear) < 0.0f ? kMirrored : 0);
  auto perpendicular = [](const glm::vec3& u, const glm::vec3& v) {
    return std::abs(glm::dot(u, v)) <= 1e-5f * glm::length(u) * glm::length(v);
  };
  if (perpendicular(linear[0], linear[1]) && perpendicular(linear[0], linear[2]) &&
      perpendicular(linear[1], linear[2]))
    b.flags |= kOrthogonalAxes;
  if (in.type == static_cast<uint32_t>(pkg::PrimitiveType::Extrusion)) {
    // Shoelace area against the box's: equal (to float rounding) for a rectangle.
    const auto profile = profile_points.subspan(in.profile_first, in.profile_count);
    const double area2 = profileSignedArea2(profile);
    const double box_area = double(hi.x - lo.x) * double(hi.y - lo.y);
    if (std::abs(0.5 * std::abs(area2) - box_area) <= 1e-5 * box_area) b.flags |= kRectangleProfile;
    if (extrusionEnclosesSolid(profile)) b.flags |= kClosedProfile;
  }
  return b;
}

// How one visible instance is drawn: its unit mesh (shape and level indices; a ribbon's segments
// along a torus's centre circle), end caps, and the batch (back-face culling, mirroring; points).
struct Form {
  Shape shape = Shape::Tube;
  uint32_t a = 0, b = 0;
  bool capped = false;
  bool box_frame = false;  // shape points span the canonical box (not the primitive's formula)
  Batch batch = kTwoSided;
  uint8_t long_axis = 0;   // a box-framed ribbon: the canonical box axis it runs along
};

// The form of one visible instance: each arc's chordal error within `tolerance` metres; a tube
// or elbow thinner than `thin` metres across a ribbon, a box thin in two directions its box, an
// instance thin in all three a point; any of these thinner than `min_thin`, nothing.
// `eye_outside`: the eye is outside the solid (eyeOutsideSolid); `inside_hidden`: an open tube's
// or elbow's inside cannot be seen (tubeInsideHidden, or a member of a sealed run with the eye
// clear of every sealed run).
Form chooseForm(const InstanceBounds& b, float tolerance, float thin, float min_thin,
                bool eye_outside, bool inside_hidden) {
  Form f;
  f.capped = (b.flags & kCapped) != 0;
  bool closed = true;
  float across = 0.0f;  // thin forms: the width the ribbon, box or point stands for
  // Cross-section rings (tubes, tori, spheres) at half the tolerance: a ring's error shows on
  // both sides of a pipe, so its width is what tau bounds (docs/parametrics.md, "Rings").
  const float ring_tolerance = 0.5f * tolerance;
  switch (surfaceOf(b.type)) {
    case Shape::Tube:
      if (2.0f * b.size[0] < thin) {
        f.shape = b.size[1] < thin ? Shape::Point : Shape::Ribbon;
        across = f.shape == Shape::Point ? std::max(2.0f * b.size[0], b.size[1]) : 2.0f * b.size[0];
        break;
      }
      f.shape = Shape::Tube;
      f.a = levelIndex(arcSegments(b.size[0], float(kTwoPi), ring_tolerance));
      closed = f.capped || inside_hidden;
      break;
    case Shape::Sphere:
      if (2.0f * b.size[0] < thin) {
        f.shape = Shape::Point;
        across = 2.0f * b.size[0];
        break;
      }
      f.shape = Shape::Sphere;
      f.a = levelIndex(arcSegments(b.size[0], float(kTwoPi), ring_tolerance));
      f.b = levelIndex(std::max(2u, arcSegments(b.size[0], float(std::numbers::pi), ring_tolerance)));
      break;
    case Shape::Torus: {
      f.a = levelIndex(arcSegments(b.size[0], std::min(b.size[2], float(kTwoPi)), tolerance));
      if (2.0f * b.size[1] < thin) {
        // The ribbon is narrower than its chords' sag could be at the tolerance: a quarter of it,
        // and straddling chords (ribbon()), keep it within an eighth of the true centre circle.
        f.shape = Shape::Ribbon;
        f.a = levelIndex(arcSegments(b.size[0], std::min(b.size[2], float(kTwoPi)), 0.25f * tolerance));
        across = 2.0f * b.size[1];
        break;
      }
      f.shape = Shape::Torus;
      f.b = levelIndex(arcSegments(b.size[1], float(kTwoPi), ring_tolerance));
      closed = inside_hidden || b.size[2] >= float(kTwoPi);  // a full torus has no open ends
      break;
    }
    default: {  // box and profiles: thin in two directions, the box; in all three, a point
      int thin_axes = 0, longest = 0;
      for (int axis = 0; axis < 3; ++axis) {
        thin_axes += 2.0f * b.size[axis] < thin;
        if (b.size[axis] > b.size[longest]) longest = axis;
      }
      f.shape = thin_axes == 3 ? Shape::Point : surfaceOf(b.type);
      if (thin_axes == 2) {
        // A beam thinner than a pixel both ways across: a ribbon along its longest axis, as
        // wide as its cross-section seen from the eye (beamRibbon), the silhouette its box
        // would show, in two triangles instead of six to twelve.
        for (int axis = 0; axis < 3; ++axis)
          if (axis != longest) across = std::max(across, 2.0f * b.size[axis]);
        f.shape = Shape::Ribbon;
        f.box_frame = true;
        f.long_axis = static_cast<uint8_t>(longest);
      } else if (f.shape == Shape::Point) {
        across = 2.0f * b.size[longest];
      }
      // An extrusion is drawn as its box when the profile lies within `tolerance` of the box's
      // sides (at most half its smaller width away), or is the box.
      if (f.shape == Shape::Profile && b.type == static_cast<uint8_t>(pkg::PrimitiveType::Extrusion) &&
          ((b.flags & kRectangleProfile) || std::min(b.size[0], b.size[1]) <= tolerance)) {
        f.shape = Shape::Box;
        f.box_frame = true;
      }
      // A revolution: half the tolerance for the angle, half for the profile (lathe()).
      if (f.shape == Shape::Profile && b.type == static_cast<uint8_t>(pkg::PrimitiveType::Revolution)) {
        f.shape = Shape::Lathe;
        f.a = levelIndex(arcSegments(std::max(b.size[0], b.size[1]), float(kTwoPi), 0.5f * tolerance));
      }
      break;
    }
  }
  if (across > 0.0f && across < min_thin) f.shape = Shape::None;
  if (f.shape == Shape::Point) f.box_frame = true;
  if (f.shape != Shape::Tube) f.capped = false;
  if (f.shape == Shape::Point)
    f.batch = kPoints;
  else if (f.shape == Shape::Ribbon)
    f.batch = kTwoSided;  // it faces the eye
  else if (closed && (eye_outside || inside_hidden))  // back faces hidden by the front faces
    f.batch = (b.flags & kMirrored) ? kCullCw : kCullCcw;
  return f;
}

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
  std::array<std::vector<uint32_t>, kBatchCount> indices;
  // Drawn (both passes), hidden last frame (first pass), to test (second pass): cluster, instance.
  std::vector<std::pair<uint32_t, uint32_t>> drawn, deferred, to_test;
  std::vector<ParametricMeshInstance> profiles;
  InstanceLodStats stats;
  std::vector<glm::vec2> kept, ring;  // lathe scratch
  ProfileSimplifier simplifier;

  void clear() {
    vertices.clear();
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
    vertices.insert(vertices.end(), part.vertices.begin(), part.vertices.end());
    for (uint32_t batch = 0; batch < kBatchCount; ++batch)
      for (uint32_t index : part.indices[batch]) indices[batch].push_back(base + index);
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
  GLuint program = 0, vertex_array = 0, vertex_buffer = 0, index_buffer = 0;
  // Unit meshes by (shape, a, b), published once made (unitMesh); `made` owns them.
  static constexpr size_t kUnitSlots = size_t(Shape::None) * kLevels.size() * kLevels.size();
  std::array<std::atomic<const OwnedUnitMesh*>, kUnitSlots> unit_slots{};
  std::mutex unit_mutex;
  std::vector<std::unique_ptr<OwnedUnitMesh>> made;
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

  ~Impl() {
    glDeleteProgram(program);
    glDeleteBuffers(1, &vertex_buffer);
    glDeleteBuffers(1, &index_buffer);
    glDeleteVertexArrays(1, &vertex_array);
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
      case Shape::Point: m = builder.point(); break;
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
  // `axis` facing the eye, as wide as the box's cross-section seen from there, cut where the two
  // long faces the eye sees meet, each part shaded with its face's normal. Four triangles show
  // what the box's six to twelve would, but for its end faces.
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
    std::vector<SmoothVertex>& vertices = part.vertices;
    // One cross-section: across `side`, the face at +u spans the edges u - w and u + w, the face
    // at +w the edges u + w and w - u; the outer edges are the silhouette.
    auto section = [&](const glm::vec3& at) {
      const glm::vec3 to_eye = -at / std::max(glm::length(at), 1e-30f);
      glm::vec3 side = glm::cross(tangent, to_eye);
      if (glm::length(side) < 1e-6f)  // seen along its axis: any side will do
        side = glm::cross(tangent, std::abs(tangent.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0));
      side = glm::normalize(side);
      const float shared = glm::dot(u + w, side);
      const float u_outer = glm::dot(u - w, side), w_outer = glm::dot(w - u, side);
      vertices.push_back({at + u_outer * side, in.object, packed_u});
      vertices.push_back({at + shared * side, in.object, packed_u});
      vertices.push_back({at + shared * side, in.object, packed_w});
      vertices.push_back({at + w_outer * side, in.object, packed_w});
    };
    const auto base = static_cast<uint32_t>(vertices.size());
    section(centre - along);
    section(centre + along);
    std::vector<uint32_t>& out = part.indices[kTwoSided];
    for (uint32_t face = 0; face < 2; ++face) {
      const uint32_t a = base + 2 * face, c = a + 4;  // this face's pair at each end
      out.insert(out.end(), {a, a + 1, c + 1, a, c + 1, c});
    }
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
                                                   uint32_t clusters_per_run)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.view = &view;
  s.clusters_per_run = clusters_per_run;
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
  glCreateBuffers(1, &s.vertex_buffer);
  glCreateBuffers(1, &s.index_buffer);
  glVertexArrayVertexBuffer(s.vertex_array, 0, s.vertex_buffer, 0, sizeof(SmoothVertex));
  glVertexArrayElementBuffer(s.vertex_array, s.index_buffer);
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
  const auto records = s.view->clusters();
  // The frustum's side planes, eye-relative (rows of the projection: w +- x, w +- y), each
  // scaled to a unit normal so a sphere's radius compares directly.
  const glm::mat4& m = view.view_projection;
  const glm::vec4 row_x(m[0][0], m[1][0], m[2][0], m[3][0]), row_y(m[0][1], m[1][1], m[2][1], m[3][1]),
      row_w(m[0][3], m[1][3], m[2][3], m[3][3]);
  std::array<glm::vec4, 4> planes = {row_w + row_x, row_w - row_x, row_w + row_y, row_w - row_y};
  for (glm::vec4& plane : planes) plane /= std::max(glm::length(glm::vec3(plane)), 1e-30f);
  const double pixel_scale = std::max(view.pixel_scale, 1e-9);
  const double near_m = std::max(view.near_m, 1e-6);
  // How far from the eye the near plane reaches (its corners): an eye closer than that to a
  // surface may see it clipped open, so back faces are kept there.
  // The rows' lengths are the reciprocals of the frustum's half extents at unit distance.
  const float near_reach = static_cast<float>(
      nearPlaneReach(near_m, 1.0 / std::max(double(glm::length(glm::vec3(row_x))), 1e-6),
                     1.0 / std::max(double(glm::length(glm::vec3(row_y))), 1e-6)));

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
  const bool test = view.pass == InstancePass::Second && view.box_hidden;
  // The distance of instance `b` (its centre at `centre`, eye-relative) for its level of detail.
  auto distanceOf = [&](const InstanceBounds& b, const glm::vec3& centre) {
    return std::max(double(glm::length(centre)) - b.radius, near_m);
  };
  // Draws one visible instance of cluster `c` (anchor_eye: its anchor relative to the eye) into
  // `part`. Called from several threads at once, each with its own part.
  auto place = [&](ExpandedPart& part, uint32_t c, const glm::vec3& anchor_eye, uint32_t i) {
    InstanceLodStats& stats = part.stats;
    const InstanceBounds& b = s.bounds[i];
    const double distance = distanceOf(b, anchor_eye + b.centre);
    const double px_per_m = pixel_scale / distance;
    const float metres_per_px = static_cast<float>(1.0 / px_per_m);
    const Form form =
        chooseForm(b, static_cast<float>(std::max(view.tolerance_px, 1e-3)) * metres_per_px,
                   static_cast<float>(view.thin_px) * metres_per_px,
                   static_cast<float>(view.min_thin_px) * metres_per_px,
                   eyeOutsideSolid(b, -anchor_eye, near_reach),
                   ((b.flags & kRunMember) && s.eye_clear_of_runs) ||
                       (!(b.flags & kCapped) && tubeInsideHidden(b, -anchor_eye, near_reach)));
    if (form.shape == Shape::None) {
      ++stats.instances_culled;
      return;
    }
    if (view.pass != InstancePass::All) part.drawn.push_back({c, i});
    ++stats.instances_drawn;
    if (form.shape == Shape::Profile) {
      FaceCull cull = FaceCull::None;
      if ((b.flags & kClosedProfile) && eyeOutsideSolid(b, -anchor_eye, near_reach))
        cull = (b.flags & kMirrored) ? FaceCull::BackOfCw : FaceCull::BackOfCcw;
      part.profiles.push_back({c, i, distance, cull});
      return;
    }
    stats.thin_instances += form.shape == Shape::Ribbon || form.shape == Shape::Point;
    if (form.shape == Shape::Ribbon) {
      if (form.box_frame)
        s.beamRibbon(part, i, b, anchor_eye, form.long_axis);
      else
        s.ribbon(part, i, b, anchor_eye, kLevels[form.a]);
      return;
    }
    if (form.shape == Shape::Lathe) {
      s.lathe(part, i, b, anchor_eye, kLevels[form.a],
              0.5f * static_cast<float>(std::max(view.tolerance_px, 1e-3)) * metres_per_px);
      return;
    }
    s.expand(part, i, b, anchor_eye, form);
  };
  // One instance of cluster `c`: culled, deferred, left for the pyramid's test, or placed.
  auto consider = [&](ExpandedPart& part, uint32_t c, const glm::vec3& anchor_eye, uint32_t i) {
    InstanceLodStats& stats = part.stats;
    const InstanceBounds& b = s.bounds[i];
    if (!(b.flags & kValid)) return;
    const glm::vec3 centre = anchor_eye + b.centre;
    const double px_per_m = pixel_scale / distanceOf(b, centre);
    bool outside = 2.0 * b.radius * px_per_m < view.min_feature_px;
    for (const glm::vec4& plane : planes)
      outside = outside || glm::dot(glm::vec3(plane), centre) + plane.w < -b.radius;
    if (outside) {
      ++stats.instances_culled;
      return;
    }
    if (view.pass == InstancePass::First && s.hidden_last[i]) {
      part.deferred.push_back({c, i});  // hidden last frame: the second pass tests it
      return;
    }
    if (test) {
      part.to_test.push_back({c, i});
      return;
    }
    place(part, c, anchor_eye, i);
  };
  // The clusters in runs, one part each, expanded on TBB (the GL thread waits for this batch);
  // a run's part is its instances in cluster order, and the parts are appended in run order.
  auto expandClusters = [&](ExpandedPart& part, size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) {
      const uint32_t c = clusters[k];
      if (c >= records.size() ||
          records[c].kind != static_cast<uint8_t>(pkg::ClusterKind::Parametric))
        continue;
      const pkg::ClusterRecord& record = records[c];
      if (record.instance_first > s.bounds.size() ||
          record.instance_count > s.bounds.size() - record.instance_first)
        continue;
      const glm::vec3 anchor_eye(clusterAnchor(record) - view.eye);
      for (uint32_t i = record.instance_first; i < record.instance_first + record.instance_count; ++i)
        consider(part, c, anchor_eye, i);
    }
  };
  const size_t runs =
      s.clusters_per_run == 0
          ? 1
          : std::clamp<size_t>(clusters.size() / s.clusters_per_run, 1,
                               size_t(tbb::this_task_arena::max_concurrency()) * 4);
  if (runs == 1) {
    expandClusters(s.frame, 0, clusters.size());
  } else {
    if (s.parts.size() < runs) s.parts.resize(runs);
    tbb::parallel_for(size_t(0), runs, [&](size_t r) {
      s.parts[r].clear();
      expandClusters(s.parts[r], clusters.size() * r / runs, clusters.size() * (r + 1) / runs);
    });
    for (size_t r = 0; r < runs; ++r) s.frame.append(s.parts[r]);
  }
  if (view.pass == InstancePass::Second) {
    for (const auto& [c, i] : s.deferred)
      consider(s.frame, c, glm::vec3(clusterAnchor(records[c]) - view.eye), i);
    s.deferred.clear();
  }
  std::vector<std::pair<uint32_t, uint32_t>> to_test;
  to_test.swap(s.frame.to_test);
  if (!to_test.empty()) {
    s.testAll(to_test, view.eye, view.box_hidden);
    // Placed in the order considered, as without the test.
    for (size_t k = 0; k < to_test.size(); ++k) {
      const auto [c, i] = to_test[k];
      if (s.test_hidden[k]) {
        s.hidden_last[i] = 1;
        ++s.frame.stats.instances_occluded;
      } else {
        place(s.frame, c, glm::vec3(clusterAnchor(records[c]) - view.eye), i);
      }
    }
  }
  s.drawn.insert(s.drawn.end(), s.frame.drawn.begin(), s.frame.drawn.end());
  s.deferred.insert(s.deferred.end(), s.frame.deferred.begin(), s.frame.deferred.end());
  profiles.assign(s.frame.profiles.begin(), s.frame.profiles.end());
  InstanceLodStats result = s.frame.stats;
  result.instances_drawn -= profiles.size();  // counted by whoever draws them
  {
    std::lock_guard lock(s.unit_mutex);
    result.unit_meshes = static_cast<uint32_t>(s.made.size());
  }
  return result;
}
void ParametricInstanceMeshes::submit(const glm::mat4& view_projection, uint32_t object_color_count,
                                      InstanceLodStats& stats) {
  Impl& s = *impl_;
  ExpandedPart& frame = s.frame;
  if (frame.vertices.empty()) return;
  // One upload of every batch, then one draw per batch.
  s.all_indices.clear();
  std::array<size_t, kBatchCount + 1> first{};
  for (uint32_t batch = 0; batch < kBatchCount; ++batch) {
    first[batch] = s.all_indices.size();
    s.all_indices.insert(s.all_indices.end(), frame.indices[batch].begin(), frame.indices[batch].end());
  }
  first[kBatchCount] = s.all_indices.size();
  glNamedBufferData(s.vertex_buffer, GLsizeiptr(frame.vertices.size() * sizeof(SmoothVertex)),
                    frame.vertices.data(), GL_STREAM_DRAW);
  glNamedBufferData(s.index_buffer, GLsizeiptr(s.all_indices.size() * sizeof(uint32_t)),
                    s.all_indices.data(), GL_STREAM_DRAW);
  glUseProgram(s.program);
  glProgramUniformMatrix4fv(s.program, gl::kViewProjectionLocation, 1, GL_FALSE,
                            &view_projection[0][0]);
  glProgramUniform1ui(s.program, gl::kObjectColorCountLocation, object_color_count);
  glBindVertexArray(s.vertex_array);
  for (uint32_t batch = 0; batch < kBatchCount; ++batch) {
    const size_t count = first[batch + 1] - first[batch];
    if (count == 0) continue;
    if (batch == kCullCcw || batch == kCullCw) {
      glEnable(GL_CULL_FACE);
      glCullFace(GL_BACK);
      glFrontFace(batch == kCullCw ? GL_CW : GL_CCW);
    } else {
      glDisable(GL_CULL_FACE);
    }
    const GLenum mode = batch == kPoints ? GL_POINTS : GL_TRIANGLES;
    glDrawElements(mode, GLsizei(count), GL_UNSIGNED_INT,
                   reinterpret_cast<const void*>(first[batch] * sizeof(uint32_t)));
    ++stats.draw_calls;
    if (mode == GL_TRIANGLES) stats.triangles_drawn += count / 3;
    if (batch == kTwoSided) stats.two_sided_triangles += count / 3;
  }
  glDisable(GL_CULL_FACE);
  glFrontFace(GL_CCW);
  glBindVertexArray(0);
  glUseProgram(0);
  // Drawn once: a second submit without a prepare draws nothing.
  frame.vertices.clear();
  for (auto& list : frame.indices) list.clear();
}

}  // namespace tw
