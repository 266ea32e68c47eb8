// Expanding one visible parametric instance, in the form chosen for it this frame
// (parametric_instance_forms.h), into eye-relative vertices and indices: a surface from its unit
// mesh, a revolution swept from its own profile, a thin tube's or beam's band facing the eye, or
// a point.
//
// Why a file of its own: what an instance looks like in each form is geometry, independent of
// how the frame's instances are chosen, split into runs on TBB and handed to GL, which is
// ParametricInstanceMeshes' (parametric_instance_meshes.h). Every function here writes only the
// batch it is given, so threads expand instances side by side, each into a batch of its own.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "package_format.h"
#include "parametric_instance_forms.h"
#include "parametric_unit_meshes.h"
#include "profile_simplifier.h"

namespace tw::instance_forms {

// One vertex of a batch: 20 bytes.
struct SmoothVertex {
  glm::vec3 position;  // metres from the eye
  uint32_t object;     // object index
  uint32_t normal;     // packNormal
};

// One vertex of a thin beam's band (appendBeamRibbon): 36 bytes. A band may stand for a row of
// beams end to end (box_rows.h): a fragment's object is `object` plus the whole part of `along`,
// at most `last`.
struct BeamVertex {
  glm::vec3 position;  // metres from the eye
  uint32_t object;     // object index (a row's first member's)
  uint32_t normal_u;   // packNormal: the first long face's
  uint32_t normal_w;   // and the second's
  float across;        // signed metres from the edge where the faces meet (< 0: first face)
  float along;         // members from the band's start: 0 there, the member count at its end
  uint32_t last;       // the member count less one (0: one beam)
};

// One vertex of a row of boxes (appendBoxRow): 24 bytes. A fragment's object is `object` plus
// the whole part of `along`, at most `last`.
struct RowVertex {
  glm::vec3 position;  // metres from the eye
  uint32_t object;     // the first member's object index
  float along;         // members from the row's start face: 0 there, the member count at its end
  uint32_t last;       // the member count less one
};

// A unit mesh with arrays of its own (base_vertex and first_index 0), so that threads expanding
// instances read it while another thread makes a mesh they have not met yet.
struct OwnedUnitMesh {
  UnitMesh mesh;
  std::vector<glm::vec4> shapes;
  std::vector<uint32_t> indices;
};

// The unit mesh of `shape` at levels kLevels[a] (and kLevels[b] across, for spheres and tori).
// Shapes never expanded from a unit mesh (points, profiles, lathes, ribbons) get an empty one.
OwnedUnitMesh makeUnitMesh(Shape shape, uint32_t a, uint32_t b);

// Expanded instances: vertices relative to the eye, and indices into them by Batch (kBeams into
// beam_vertices, kRows into row_vertices, the others into vertices).
struct InstanceBatch {
  std::vector<SmoothVertex> vertices;
  std::vector<BeamVertex> beam_vertices;
  std::vector<RowVertex> row_vertices;
  std::array<std::vector<uint32_t>, kBatchCount> indices;

  void clear();
  // Appends `other` after this batch's contents, its indices offset to match.
  void append(const InstanceBatch& other);
  // Points plus triangles.
  size_t primitives() const;
};

// What sweeping revolutions reuses from one to the next.
struct LatheScratch {
  std::vector<glm::vec2> kept, ring;
  ProfileSimplifier simplifier;
};

// In each function, `in` is the instance, `b` its bounds, `anchor_eye` its cluster's anchor
// relative to the eye, and `profile_points` the package's profile table.

// Appends instance `in` as the surface of form `f` (unit mesh `unit`, made for f's shape and
// levels). Closed surfaces in a culling batch leave out the triangles whose back the eye sees.
void appendSurface(InstanceBatch& batch, const pkg::InstanceRecord& in,
                   std::span<const glm::vec2> profile_points, const InstanceBounds& b,
                   const glm::vec3& anchor_eye, const Form& f, const OwnedUnitMesh& unit);

// Appends row `row` (box_rows.h: the row as one box record, its bounds `b`) of `members` boxes
// along canonical axis `axis` as the surface of form `f` (a box), into kRows whatever f's batch:
// back faces, covered faces and thin rims are left out here as appendSurface leaves them out,
// and each fragment tells the member it falls on.
void appendBoxRow(InstanceBatch& batch, const pkg::InstanceRecord& row, const InstanceBounds& b,
                  const glm::vec3& anchor_eye, const Form& f, const OwnedUnitMesh& unit,
                  uint32_t members, int axis);

// Appends revolution `in` swept over `segments` steps (a full turn's count; a partial sweep gets
// its share, at least one), its profile simplified to `profile_tolerance` metres: flat bands
// between the kept profile points, two-sided (no normals: faceted like the reference).
void appendLathe(InstanceBatch& batch, LatheScratch& scratch, const pkg::InstanceRecord& in,
                 std::span<const glm::vec2> profile_points, const InstanceBounds& b,
                 const glm::vec3& anchor_eye, uint32_t segments, float profile_tolerance);

// Appends tube or elbow `in`, thinner than a pixel, as its silhouette: a band along the axis
// (the centre circle in `segments` steps over its sweep) facing the eye, as wide as the tube's
// cross-section seen from there, shaded with the normal of the tube's line nearest the eye.
void appendTubeRibbon(InstanceBatch& batch, const pkg::InstanceRecord& in, const InstanceBounds& b,
                      const glm::vec3& anchor_eye, uint32_t segments);

// Appends box-framed instance `in` (a box, or an extrusion or revolution by its box), thinner
// than a pixel across its two shorter axes, as a band along its longest axis `axis` facing the
// eye, as wide as its cross-section seen from there, each side of the edge where the two long
// faces the eye sees meet shaded with its own face's normal. The box's half sizes are the
// bounds' (`b.size`), so the profile is not read again. `members` > 1: `in` and `b` are a row of
// that many equal beams end to end along `axis` (box_rows.h), objects `in.object` onward.
void appendBeamRibbon(InstanceBatch& batch, const pkg::InstanceRecord& in, const InstanceBounds& b,
                      const glm::vec3& anchor_eye, int axis, uint32_t members = 1);

// Appends a point at `at` (eye-relative) for object `object`.
void appendPoint(InstanceBatch& batch, uint32_t object, const glm::vec3& at);

}  // namespace tw::instance_forms
