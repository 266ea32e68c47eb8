// The scene model shared by every reader, writer, the generator and the preprocessor.
//
// A scene is a list of layers and a stream of objects. Each object keeps its id, name, layer and
// database key from input to package so that review tools can find it again. Geometry stays in
// its most compact exact form: parametric primitives and NURBS are not tessellated here.
#pragma once

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

// Placement of an object's local frame in the world. The origin is double precision so that plant
// coordinates (kilometres from the datum) keep millimetre accuracy; the linear part is float
// because local geometry is small.
struct Transform {
  glm::dvec3 origin{0.0};
  glm::mat3 linear{1.0f};  // rotation and scale, column-major

  glm::dvec3 apply(const glm::vec3& local) const { return origin + glm::dvec3(linear * local); }
  bool isIdentity() const { return origin == glm::dvec3(0.0) && linear == glm::mat3(1.0f); }
};

// Indexed triangles in the object's local frame.
struct TriangleMesh {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;   // empty, or one per position
  std::vector<uint32_t> colors;     // empty, or one RGBA8 (0xAABBGGRR) per position
  std::vector<uint32_t> indices;    // three per triangle, each < positions.size()

  uint64_t triangleCount() const { return indices.size() / 3; }
};

// Parametric primitives. Each lives in a canonical local frame with its axis along +Z; the
// object's Transform places it. Lengths are in scene units (metres for generated plants).
struct Cylinder {
  float radius = 1.0f;
  float height = 1.0f;  // from z = 0 to z = height
  bool capped = true;   // closed with discs at both ends
};
struct Cone {  // also a frustum when both radii are non-zero
  float radius_bottom = 1.0f;  // at z = 0
  float radius_top = 0.0f;     // at z = height
  float height = 1.0f;
  bool capped = true;
};
struct Sphere {
  float radius = 1.0f;  // centred on the local origin
};
// A pipe elbow: the tube of radius minor_radius swept along an arc of radius major_radius in the
// XY plane, starting on +X and turning counter-clockwise about +Z by sweep_rad.
struct TorusSegment {
  float major_radius = 1.0f;
  float minor_radius = 0.25f;
  float sweep_rad = 1.5707964f;
};
struct Box {
  glm::vec3 half_extents{0.5f};  // centred on the local origin
};
// A closed simple polygon in the XY plane (counter-clockwise), swept along +Z and capped.
struct Extrusion {
  std::vector<glm::vec2> profile;
  float height = 1.0f;
};
// A polyline in the XZ half-plane, given as (radius >= 0, z) pairs, revolved about +Z by
// sweep_rad starting from +X. A full turn (2*pi) gives a closed solid of revolution when the
// profile starts and ends on the axis.
struct Revolution {
  std::vector<glm::vec2> profile;
  float sweep_rad = 6.2831855f;
};
using Primitive = std::variant<Cylinder, Cone, Sphere, TorusSegment, Box, Extrusion, Revolution>;

// One untrimmed rational B-spline patch. Control points are (x, y, z, w) with x, y, z not
// premultiplied by w; the grid is row-major with u varying fastest. Knot vectors are clamped or
// not, non-decreasing, with count + degree + 1 entries.
struct NurbsPatch {
  uint32_t degree_u = 3;
  uint32_t degree_v = 3;
  uint32_t count_u = 4;
  uint32_t count_v = 4;
  std::vector<float> knots_u;
  std::vector<float> knots_v;
  std::vector<glm::vec4> control_points;  // count_u * count_v
};
// Patches that belong together. Adjacent patches share a border: the same control points along
// the common edge, so a crack-free tessellation is possible.
struct NurbsPatchSet {
  std::vector<NurbsPatch> patches;
};

using Geometry = std::variant<TriangleMesh, Primitive, NurbsPatchSet>;
enum class GeometryKind : uint8_t { Mesh = 0, Parametric = 1, Nurbs = 2 };
inline GeometryKind kindOf(const Geometry& g) { return static_cast<GeometryKind>(g.index()); }

struct Layer {
  std::string name;
  uint32_t color_rgba = 0xffb0b0b0u;  // 0xAABBGGRR
};

// Identity and placement of an object. color_rgba == 0 means "use the layer's colour".
struct ObjectInfo {
  uint32_t id = 0;        // unique within a scene
  std::string name;
  uint32_t layer = 0;     // index into the scene's layer list
  std::string db_key;     // key of the object's record in the project database; may be empty
  uint32_t color_rgba = 0;
  Transform transform;
};

struct SceneObject {
  ObjectInfo info;
  Geometry geometry;
};

}  // namespace tw
