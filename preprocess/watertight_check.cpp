// Watertightness check through OpenMesh: weld by position, count what the half-edge structure
// refuses and the boundary it ends up with. OpenMesh stays confined to this file.
#include "watertight_check.h"

#include <array>
#include <vector>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include "exact_weld.h"
#include "quiet_openmesh.h"

namespace tw {
namespace {

using HalfEdgeMesh = OpenMesh::TriMesh_ArrayKernelT<>;

}  // namespace

MeshTopologyReport checkWatertight(const TriangleMesh& mesh) {
  MeshTopologyReport report;
  // Weld (exact_weld.h): one half-edge vertex per distinct position used by a face.
  const WeldedTriangles welded = weldExactly(mesh);
  const std::vector<glm::vec3>& points = welded.points;
  const std::vector<std::array<uint32_t, 3>>& triangles = welded.triangles;
  report.degenerate_faces = welded.skipped;
  report.vertices = points.size();

  // Non-manifold edges from directed-edge uses: a closed oriented manifold uses every edge once
  // in each direction.
  for (const auto& [key, use] : countEdgeUses(triangles))
    if (use.forward + use.backward > 2 || use.forward > 1 || use.backward > 1) ++report.non_manifold_edges;

  // The half-edge mesh: OpenMesh refuses faces that would make an edge or vertex non-manifold.
  QuietOpenMesh quiet;
  HalfEdgeMesh he;
  he.reserve(points.size(), points.size() + triangles.size(), triangles.size());
  std::vector<HalfEdgeMesh::VertexHandle> handles;
  handles.reserve(points.size());
  for (const glm::vec3& p : points) handles.push_back(he.add_vertex(HalfEdgeMesh::Point(p.x, p.y, p.z)));
  for (const auto& tri : triangles) {
    const auto f = he.add_face(handles[tri[0]], handles[tri[1]], handles[tri[2]]);
    if (f.is_valid())
      ++report.faces;
    else
      ++report.rejected_faces;
  }
  for (const auto& eh : he.edges())
    if (he.is_boundary(eh)) ++report.boundary_edges;
  return report;
}

}  // namespace tw
