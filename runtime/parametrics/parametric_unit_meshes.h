// The unit meshes of tessellated parametrics: one mesh per (shape, resolution), in the shape's
// own coordinates, that ParametricInstanceMeshes (parametric_instance_meshes.h) expands into each
// visible instance of that shape.
//
// Why a file of its own: what the unit meshes are (rows, columns, rings that straddle the circle,
// winding) is one decision, made once per resolution; choosing a resolution per instance and
// expanding it every frame is another.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

// How far out a straddling ring of n segments puts its vertices (UnitMeshBuilder::
// straddlingCircle), as a factor of the radius: 2 / (1 + cos(pi / n)); 4/3 at the fewest, 3.
float ringSwell(uint32_t n);

// A unit mesh in the builder's arrays: its vertices start at base_vertex, its indices (relative to
// base_vertex) at first_index; the first side_indices are the surface without end caps.
struct UnitMesh {
  uint32_t base_vertex = 0, vertex_count = 0, first_index = 0, side_indices = 0, all_indices = 0;
};

// Builds the unit meshes: points of a shape (shapedPoint, in parametric_instance_expansion.cpp, gives
// them the instance's parameters).
// Rows and columns follow formats/primitive_tessellation.cpp, and every triangle is
// counter-clockwise seen from outside.
//   tube (cylinder, cone): (cos a, sin a, z in [0, 1], 1 on the side's rim, 2 on a cap's rim,
//                          0 at a cap centre)
//   sphere:                (cos a, sin a, cos latitude, sin latitude)
//   torus:                 (fraction of the sweep, cos b, sin b, -) with b around the tube
//   box:                   (+-1, +-1, +-1, -)
// In the box frame (thin forms, extrusions as boxes) xyz in [-1, 1] spans the instance's
// canonical box.
class UnitMeshBuilder {
 public:
  std::vector<glm::vec4> shapes;
  std::vector<uint32_t> indices;

  UnitMesh tube(uint32_t n);

  // n columns around, m rows pole to pole.
  UnitMesh sphere(uint32_t n, uint32_t m);

  // nu steps along the sweep (nu + 1 columns), nv rows around the tube.
  UnitMesh torus(uint32_t nu, uint32_t nv);

  UnitMesh box();

 private:
  UnitMesh begin() const;
  uint32_t count(const UnitMesh& m) const { return static_cast<uint32_t>(indices.size()) - m.first_index; }
  void triangle(uint32_t a, uint32_t b, uint32_t c) { indices.insert(indices.end(), {a, b, c}); }
  void quad(uint32_t a, uint32_t b, uint32_t c, uint32_t d);
  static std::vector<glm::vec2> circle(uint32_t n);
  // A ring whose chords cross the true circle: vertices pushed out so the polygon's largest
  // distance inside (at chord middles) equals its largest outside (at vertices), each half the
  // inscribed polygon's sagitta. A pipe then keeps its width on average, seen from any side,
  // instead of always looking thinner; in a rack of pipes, the gaps between them stay closed.
  static std::vector<glm::vec2> straddlingCircle(uint32_t n);
};

}  // namespace tw
