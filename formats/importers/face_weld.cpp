// B-rep face triangulations welded into one mesh. See face_weld.h.
#include "face_weld.h"

namespace tw {

const std::vector<uint32_t>& FaceWeld::addNodes(const Poly_Triangulation& triangulation,
                                                const gp_Trsf& placement) {
  const int nodes = triangulation.NbNodes();
  node_index_.assign(size_t(nodes) + 1, 0);
  for (int n = 1; n <= nodes; ++n) {
    const gp_Pnt p = triangulation.Node(n).Transformed(placement);
    auto [it, inserted] = weld_.emplace(std::make_tuple(p.X(), p.Y(), p.Z()), uint32_t(mesh_.positions.size()));
    if (inserted) mesh_.positions.push_back(glm::vec3(glm::dvec3(p.X(), p.Y(), p.Z()) - center_));
    node_index_[size_t(n)] = it->second;
  }
  return node_index_;
}

void FaceWeld::addTriangles(const Poly_Triangulation& triangulation, bool reversed) {
  const int nodes = int(node_index_.size()) - 1;
  for (int t = 1; t <= triangulation.NbTriangles(); ++t) {
    int a, b, c;
    triangulation.Triangle(t).Get(a, b, c);
    if (a < 1 || b < 1 || c < 1 || a > nodes || b > nodes || c > nodes) continue;
    const uint32_t ia = node_index_[size_t(a)], ib = node_index_[size_t(b)], ic = node_index_[size_t(c)];
    if (ia == ib || ib == ic || ia == ic) continue;  // collapsed by the weld
    if (reversed) mesh_.indices.insert(mesh_.indices.end(), {ia, ic, ib});
    else mesh_.indices.insert(mesh_.indices.end(), {ia, ib, ic});
  }
}

}  // namespace tw
