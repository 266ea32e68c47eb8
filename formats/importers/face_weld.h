// B-rep faces' triangulations (BRepMesh's) gathered into one triangle mesh, their nodes welded
// by exact position.
//
// BRepMesh puts the very same nodes on the edge two faces share, so welding by exact position
// joins the faces into one surface without guessing by distance. Both the STEP importer (per
// part) and the boolean cuts of the IFC importer mesh their shapes this way.
#pragma once

#include <cstdint>
#include <map>
#include <tuple>
#include <vector>

#include <Poly_Triangulation.hxx>
#include <gp_Trsf.hxx>
#include <glm/glm.hpp>

#include "scene.h"

namespace tw {

class FaceWeld {
 public:
  // Positions go into `mesh` relative to `center` (a part's box centre keeps float precision
  // far from the datum).
  explicit FaceWeld(TriangleMesh& mesh, const glm::dvec3& center = glm::dvec3(0.0))
      : mesh_(mesh), center_(center) {}

  // Welds the face's nodes (placed by `placement`) into the mesh; returns, per 1-based node
  // number, its vertex in the mesh (index 0 unused). Valid until the next call.
  const std::vector<uint32_t>& addNodes(const Poly_Triangulation& triangulation, const gp_Trsf& placement);

  // Appends the face's triangles through the last addNodes() map, wound the other way for a
  // reversed face; triangles with an invalid node or collapsed by the weld are left out.
  void addTriangles(const Poly_Triangulation& triangulation, bool reversed);

 private:
  TriangleMesh& mesh_;
  glm::dvec3 center_;
  std::map<std::tuple<double, double, double>, uint32_t> weld_;
  std::vector<uint32_t> node_index_;
};

}  // namespace tw
