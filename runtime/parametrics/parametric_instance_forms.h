// How each visible parametric instance is drawn in tessellated mode: what is read of it once
// (InstanceBounds), and the form it takes each frame (chooseForm: a unit mesh at a resolution, a
// ribbon, a box, a point, or nothing), with the tests that decide whether its back faces show.
//
// Why a file of its own: choosing a form is a decision made per instance from its bounds and the
// distance; expanding the chosen form into the frame's batch is ParametricInstanceMeshes'
// (parametric_instance_meshes.h), which uses this.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <span>

#include <glm/glm.hpp>

#include "package_format.h"
#include "tessellate.h"

namespace tw::instance_forms {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr uint32_t kTypes = 7;  // cylinder, cone, sphere, torus segment, box, extrusion, revolution

// Segment counts a unit mesh may have: steps of at most 1.25x, up to kMaxArcSegments.
constexpr std::array<uint32_t, 28> kLevels = {1,   2,   3,   4,   5,   6,   8,   10,  12,  16,
                                              20,  24,  32,  40,  48,  64,  80,  96,  128, 160,
                                              192, 256, 320, 384, 512, 640, 768, 1024};
static_assert(kLevels.back() == kMaxArcSegments);

// The index in kLevels of the first count >= `segments` (the last when there is none).
uint32_t levelIndex(uint32_t segments);

// The unit meshes. Surfaces are triangles; instances thin in every direction degrade to a point
// (their box centre, placed without a unit mesh).
// Ribbon: a tube or elbow thinner than a pixel, or a beam thinner than a pixel both ways across,
// drawn as its silhouette (a band facing the eye along the axis, centre circle or longest box
// axis, as wide as the instance seen from there), built each frame.
// Profile: an extrusion's or a revolution's surface, drawn from its cluster's mesh
// (ParametricMeshes::drawInstances), not here.
// Lathe: a revolution swept here from its own profile (simplified to the tolerance), not from a
// unit mesh. None: thinner than the smallest thin form worth drawing (InstanceLodView::min_thin_px).
enum class Shape : uint32_t { Tube, Sphere, Torus, Box, Ribbon, Point, Profile, Lathe, None };

// The surface an instance of primitive `type` is drawn with, when it is not thin.
Shape surfaceOf(uint32_t type);

// The per-frame batches: triangles by back-face culling, points, rows of boxes (vertices of
// their own: where along the row), and the thin beams' bands (vertices of their own: both
// faces' normals).
enum Batch : uint32_t { kTwoSided, kCullCcw, kCullCw, kPoints, kRows, kBeams, kBatchCount };

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
  // A box's faces that another box's face covers (covered_box_faces.h): bit f for face f of
  // -X, +X, -Y, +Y, -Z, +Z, the unit box's order. Left out of its surface.
  uint8_t covered_faces = 0;
  // Rows of boxes (box_rows.h): 0 for an instance on its own; kDrawnWithRow for a member drawn by
  // its row's first member; n >= 2 for the first member of a row of n, whose bounds these are
  // (the row's: one box n times as long).
  uint8_t row = 0;
};
constexpr uint8_t kDrawnWithRow = 1;

// An open tube's inside can only be seen through its end discs, so from an eye between the two
// end planes and outside the tube its back faces are hidden by its front faces. `eye` is
// relative to the anchor.
bool tubeInsideHidden(const InstanceBounds& b, const glm::vec3& eye, float margin);

// Whether `eye` (relative to the anchor) lies more than `margin` outside the instance's solid,
// which makes the back faces of its closed surface hidden by its front faces. The bounding sphere
// alone is too cautious for long or flat instances: standing under a deck or beside a 12 m pipe
// run, the eye is inside their spheres though far outside the solids, and drawing both faces
// doubled what llvmpipe rasterized of them (docs/parametrics.md, "Back faces"). So also the
// world-axis box (which holds every handled shape) and, for tubes, the capped cylinder: farther
// from the axis than the widest ring reaches, or beyond an end plane.
bool eyeOutsideSolid(const InstanceBounds& b, const glm::vec3& eye, float margin);

// What the per-frame choice reads of instance `in`, its positions relative to `anchor` (the
// cluster's); not kValid when its type or parameters cannot be drawn here.
InstanceBounds boundsOf(const pkg::InstanceRecord& in, std::span<const glm::vec2> profile_points,
                        const glm::dvec3& anchor);

// How one visible instance is drawn: its unit mesh (shape and level indices; a ribbon's segments
// along a torus's centre circle), end caps, and the batch (back-face culling, mirroring; points).
struct Form {
  Shape shape = Shape::Tube;
  uint32_t a = 0, b = 0;
  bool capped = false;
  bool box_frame = false;  // shape points span the canonical box (not the primitive's formula)
  Batch batch = kTwoSided;
  uint8_t long_axis = 0;   // a box-framed ribbon: the canonical box axis it runs along
  // A box thin along one axis (a plate), thinner there than the smallest thin form worth
  // drawing: its four rims, as narrow as it is thick, in the bits' order of
  // InstanceBounds::covered_faces, left out as a thin form that narrow would be.
  uint8_t thin_faces = 0;
};

// The form of one visible instance: each arc's chordal error within `tolerance` metres; a tube
// or elbow thinner than `thin` metres across a ribbon, a box, extrusion or revolution thin in two
// directions a ribbon along its longest axis, an instance thin in all three a point; any of these
// whose second largest size (a tube's diameter) is under `min_thin`, nothing; a box thin along
// one axis, under `min_thin` there, without its rims. Surfaces come two-sided: cullBackFaces
// decides.
Form chooseForm(const InstanceBounds& b, float tolerance, float thin, float min_thin);
// The scale from which an instance shows at all, in pixels per metre at its nearest point (the
// choice's pixel_scale / distance): below it the small-feature test (its bounding sphere below
// min_feature_px) or chooseForm (None: its thin form below min_thin_px) leaves it out, from it
// on they never do, as a thin form is as wide as the same size at every scale. A far view then
// visits only the instances that can show (InstanceScaleIndex). Infinite when never shown.
double shownFrom(const InstanceBounds& b, double thin_px, double min_thin_px,
                 double min_feature_px);

// Culls the back faces of surface form `f` where the front faces hide them. `eye_outside`: the
// eye is outside the solid (eyeOutsideSolid); `inside_hidden`: an open tube's or elbow's inside
// cannot be seen (tubeInsideHidden, or a member of a sealed run with the eye clear of every
// sealed run). Points and ribbons are left as they are: the caller need not ask those questions
// of the far view's many thin instances.
void cullBackFaces(Form& f, const InstanceBounds& b, bool eye_outside, bool inside_hidden);

}  // namespace tw::instance_forms
