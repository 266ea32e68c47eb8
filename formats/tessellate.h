// Tessellation of parametric primitives and NURBS patch sets at a chordal tolerance.
//
// Parametrics stay parametric in the scene; these functions exist for consumers that need
// triangles (PLY/OBJ export, ray-cast snapshots, reference renders) and for counting the
// "equivalent triangles" a scene represents. Output is in the geometry's local frame.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "scene.h"

namespace tw {

// The default chordal tolerance, in scene units (metres for generated plants): the largest
// distance between the true surface and its triangles. 2 mm keeps a 100 mm pipe at 16 segments.
constexpr float kDefaultChordalTolerance = 0.002f;

// Number of segments an arc of `radius` spanning `sweep_rad` needs so that the chord never
// deviates from the arc by more than `tolerance`. At least 3 for a full circle, 1 otherwise;
// capped at kMaxArcSegments so hostile input cannot demand unbounded work.
constexpr uint32_t kMaxArcSegments = 1024;
uint32_t arcSegments(float radius, float sweep_rad, float tolerance);

// Appends triangles (positions, normals, indices) to `out`. `out` may already hold geometry;
// indices are offset accordingly. Colours are left to the caller. Normals are appended when `out`
// is empty or has one normal per position; positions without normals stay without normals.
void tessellatePrimitive(const Primitive& primitive, float tolerance, TriangleMesh& out);
// tessellateNurbs tessellates each patch on its own (cracks where patches share a border);
// tessellate() takes NURBS sets through the conforming tessellation the preprocessor uses
// (nurbs_conforming.h), so exports and snapshots show the triangles the package holds.
void tessellateNurbs(const NurbsPatchSet& patches, float tolerance, TriangleMesh& out);
void tessellate(const Geometry& geometry, float tolerance, TriangleMesh& out);

// Whether the triangles tessellatePrimitive makes of an extrusion with this profile enclose its
// solid, every face wound counter-clockwise seen from outside, so that a renderer may cull their
// back faces from an eye outside the solid: the profile (consecutive repeats and a closing copy of
// the first point dropped) is a valid simple polygon, no two of its edges meeting except
// neighbours at their shared corner. A profile that crosses or touches itself is still
// triangulated, but its caps may overlap or leave gaps. Profiles of more than
// kMaxSolidCheckPoints points are not checked (false), so hostile input costs no quadratic work.
constexpr size_t kMaxSolidCheckPoints = 256;
bool extrusionEnclosesSolid(std::span<const glm::vec2> profile);

// Twice the signed area of a closed profile (its last point joins its first), in double:
// positive when it winds counter-clockwise.
double profileSignedArea2(std::span<const glm::vec2> profile);

// Exactly the number of triangles the functions above would append, computed without building
// them (cheap enough to call for every object of a 100M-triangle scene); triangleCount of a NURBS
// set is the conforming tessellation's, which it builds to count (nurbs_conforming.h).
uint64_t primitiveTriangleCount(const Primitive& primitive, float tolerance);
uint64_t nurbsTriangleCount(const NurbsPatchSet& patches, float tolerance);
uint64_t triangleCount(const Geometry& geometry, float tolerance);

}  // namespace tw
