// Watertightness check through OpenMesh: weld by position, count what the half-edge structure
// refuses and the boundary it ends up with. OpenMesh stays confined to this file.
#include "watertight_check.h"

#include <array>
#include <bit>
#include <unordered_map>
#include <vector>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include "position_key.h"
#include "quiet_openmesh.h"

namespace tw {
namespace {

using HalfEdgeMesh = OpenMesh::TriMesh_ArrayKernelT<>;

}  // namespace

MeshTopologyReport checkWatertight(const TriangleMesh& mesh) {
  MeshTopologyReport report;
  const size_t vertex_count = mesh.positions.size();

  // Weld: one half-edge vertex per distinct position, created when a face first uses it.
  std::unordered_map<PositionKey, uint32_t, PositionHash> welded;
  welded.reserve(vertex_count);
  std::vector<uint32_t> remap(vertex_count, UINT32_MAX);
  std::vector<glm::vec3> points;
  auto weld = [&](uint32_t index) {
    if (remap[index] == UINT32_MAX) {
      const auto [it, inserted] = welded.try_emplace(positionKeyOf(mesh.positions[index]), static_cast<uint32_t>(points.size()));
      if (inserted) points.push_back(mesh.positions[index]);
      remap[index] = it->second;
    }
    return remap[index];
  };

  std::vector<std::array<uint32_t, 3>> triangles;
  triangles.reserve(mesh.indices.size() / 3);
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const uint32_t i0 = mesh.indices[t], i1 = mesh.indices[t + 1], i2 = mesh.indices[t + 2];
    if (i0 >= vertex_count || i1 >= vertex_count || i2 >= vertex_count) {
      ++report.degenerate_faces;
      continue;
    }
    const uint32_t a = weld(i0), b = weld(i1), c = weld(i2);
    if (a == b || b == c || c == a) {
      ++report.degenerate_faces;
      continue;
    }
    triangles.push_back({a, b, c});
  }
  report.vertices = points.size();

  // Non-manifold edges from directed-edge uses: a closed oriented manifold uses every edge once
  // in each direction.
  struct EdgeUse {
    uint32_t forward = 0, backward = 0;
  };
  std::unordered_map<uint64_t, EdgeUse> edges;
  edges.reserve(triangles.size() * 2);
  for (const auto& tri : triangles)
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = tri[e], b = tri[(e + 1) % 3];
      EdgeUse& use = edges[(uint64_t{std::min(a, b)} << 32) | std::max(a, b)];
      ++(a < b ? use.forward : use.backward);
    }
  for (const auto& [key, use] : edges)
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
