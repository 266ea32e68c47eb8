// OpenMesh verification of tessellated patch sets: see patch_mesh_check.h.
//
// The mesh is welded by exact position bits only (a crack of one ulp must stay visible), built
// as an OpenMesh half-edge mesh, and its boundary is classified against the patches' own
// borders, found here independently of the tessellator: a border is shared when all its
// samples lie on another border curve.
#include "patch_mesh_check.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <unordered_map>
#include <vector>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include "exact_weld.h"
#include "nurbs.h"
#include "position_key.h"
#include "quiet_openmesh.h"

namespace tw {
namespace {

using HalfEdgeMesh = OpenMesh::TriMesh_ArrayKernelT<>;

constexpr int kSamples = 32;  // segments of a border's sample polyline

double dist(const glm::dvec3& a, const glm::dvec3& b) { return glm::length(a - b); }

// One side of a patch (counter-clockwise: bottom, right, top, left) as a sampled curve.
struct BorderCurve {
  const NurbsPatch* patch = nullptr;
  NurbsDomain dom{};
  int side = 0;
  std::array<glm::dvec3, kSamples + 1> samples{};
  glm::dvec3 lo{INFINITY}, hi{-INFINITY};

  glm::dvec3 at(double t) const {
    const double x = side == 0 ? t : side == 1 ? 1.0 : side == 2 ? 1.0 - t : 0.0;
    const double y = side == 0 ? 0.0 : side == 1 ? t : side == 2 ? 1.0 : 1.0 - t;
    const float u = static_cast<float>(dom.u0 + (static_cast<double>(dom.u1) - dom.u0) * x);
    const float v = static_cast<float>(dom.v0 + (static_cast<double>(dom.v1) - dom.v0) * y);
    return glm::dvec3(evaluateNurbs(*patch, std::clamp(u, dom.u0, dom.u1), std::clamp(v, dom.v0, dom.v1)));
  }
  // Distance from q to the curve: nearest sample, then golden-section search around it (around
  // both ends when the curve is a closed loop).
  double distanceTo(const glm::dvec3& q, double quick_accept) const {
    int nearest = 0;
    double best = dist(samples[0], q);
    for (int k = 1; k <= kSamples; ++k)
      if (const double d = dist(samples[k], q); d < best) best = d, nearest = k;
    if (best <= quick_accept) return best;
    best = std::min(best, search(q, nearest));
    if (samples[0] == samples[kSamples] && (nearest == 0 || nearest == kSamples))
      best = std::min(best, search(q, kSamples - nearest));
    return best;
  }
  double search(const glm::dvec3& q, int around) const {
    double lo_t = std::max(0, around - 1) / static_cast<double>(kSamples);
    double hi_t = std::min(kSamples, around + 1) / static_cast<double>(kSamples);
    constexpr double kGolden = 0.6180339887498949;
    double a = hi_t - kGolden * (hi_t - lo_t), b = lo_t + kGolden * (hi_t - lo_t);
    double fa = dist(at(a), q), fb = dist(at(b), q);
    for (int it = 0; it < 32; ++it) {
      if (fa < fb) {
        hi_t = b, b = a, fb = fa;
        a = hi_t - kGolden * (hi_t - lo_t);
        fa = dist(at(a), q);
      } else {
        lo_t = a, a = b, fa = fb;
        b = lo_t + kGolden * (hi_t - lo_t);
        fb = dist(at(b), q);
      }
    }
    return std::min(fa, fb);
  }
  bool near(const glm::dvec3& q, double tol) const {
    return glm::all(glm::greaterThanEqual(q, lo - tol)) && glm::all(glm::lessThanEqual(q, hi + tol));
  }
};

using CellKey = GridCellKey;
using CellHash = GridCellHash;

std::string where(const glm::dvec3& p) {
  std::ostringstream s;
  s << "(" << p.x << ", " << p.y << ", " << p.z << ")";
  return s.str();
}

}  // namespace

bool PatchMeshReport::ok() const {
  return refused_faces == 0 && inner_boundary_edges == 0 && t_vertices == 0 && inconsistent_orientation == 0;
}

using Triangles = std::vector<std::array<uint32_t, 3>>;
using Edges = std::vector<std::array<uint32_t, 2>>;

// The half-edge mesh: OpenMesh refuses faces that would make an edge or a vertex non-manifold
// (an edge used twice in one direction among them). Counts the faces it takes and refuses;
// returns the boundary edges of what it took.
Edges halfEdgeBoundary(const std::vector<glm::dvec3>& points, const Triangles& triangles,
                       PatchMeshReport& report) {
  QuietOpenMesh quiet;
  HalfEdgeMesh he;
  he.reserve(points.size(), points.size() + triangles.size(), triangles.size());
  std::vector<HalfEdgeMesh::VertexHandle> handles;
  handles.reserve(points.size());
  for (const glm::dvec3& p : points) handles.push_back(he.add_vertex(HalfEdgeMesh::Point(p.x, p.y, p.z)));
  for (const auto& tri : triangles) {
    if (he.add_face(handles[tri[0]], handles[tri[1]], handles[tri[2]]).is_valid())
      ++report.faces;
    else
      ++report.refused_faces;
  }
  std::vector<std::array<uint32_t, 2>> boundary;
  for (const auto& eh : he.edges())
    if (he.is_boundary(eh)) {
      const auto h = he.halfedge_handle(eh, 0);
      boundary.push_back({static_cast<uint32_t>(he.from_vertex_handle(h).idx()),
                          static_cast<uint32_t>(he.to_vertex_handle(h).idx())});
    }
  return boundary;
}

// The patches' borders, sampled, and which of them are shared with another border.
struct PatchBorders {
  std::vector<BorderCurve> curves;
  std::vector<char> shared;  // one per curve
};

PatchBorders patchBorders(const NurbsPatchSet& patches, double tol) {
  PatchBorders out;
  std::vector<BorderCurve>& borders = out.curves;
  for (const NurbsPatch& patch : patches.patches) {
    if (!validateNurbsPatch(patch).empty()) continue;
    for (int side = 0; side < 4; ++side) {
      BorderCurve c;
      c.patch = &patch;
      c.dom = nurbsDomain(patch);
      c.side = side;
      for (int k = 0; k <= kSamples; ++k) {
        c.samples[k] = c.at(static_cast<double>(k) / kSamples);
        c.lo = glm::min(c.lo, c.samples[k]);
        c.hi = glm::max(c.hi, c.samples[k]);
      }
      borders.push_back(c);
    }
  }
  std::vector<char>& shared = out.shared;
  shared.assign(borders.size(), 0);
  for (size_t a = 0; a < borders.size(); ++a) {
    if (shared[a]) continue;
    for (size_t b = 0; b < borders.size() && !shared[a]; ++b) {
      if (a == b || !borders[b].near(borders[a].lo, tol) || !borders[b].near(borders[a].hi, tol)) continue;
      bool on = true;
      for (int k = 0; k <= kSamples && on; ++k) on = borders[b].distanceTo(borders[a].samples[k], tol) <= tol;
      if (on) shared[a] = 1;
    }
  }

  return out;
}

// Boundary edges on the outer border have both ends on one unshared border; the others are
// inside the set. Returns the middle of the first inside one.
glm::dvec3 countInnerBoundaryEdges(const std::vector<glm::dvec3>& points, const Edges& boundary,
                                   const PatchBorders& patch_borders, double tol,
                                   PatchMeshReport& report) {
  const std::vector<BorderCurve>& borders = patch_borders.curves;
  const std::vector<char>& shared = patch_borders.shared;
  std::unordered_map<uint32_t, std::vector<uint32_t>> on_outer;  // boundary vertex -> unshared borders
  auto outerBorders = [&](uint32_t v) -> const std::vector<uint32_t>& {
    auto [it, inserted] = on_outer.try_emplace(v);
    if (inserted)
      for (size_t b = 0; b < borders.size(); ++b)
        if (!shared[b] && borders[b].near(points[v], tol) && borders[b].distanceTo(points[v], tol * 0.5) <= tol)
          it->second.push_back(static_cast<uint32_t>(b));
    return it->second;
  };
  glm::dvec3 first_inner(0.0);
  for (const auto& e : boundary) {
    const std::vector<uint32_t>& a = outerBorders(e[0]);
    const std::vector<uint32_t>& b = outerBorders(e[1]);
    bool outer = false;
    for (uint32_t x : a)
      if (std::find(b.begin(), b.end(), x) != b.end()) outer = true;
    if (!outer) {
      if (report.inner_boundary_edges == 0) first_inner = 0.5 * (points[e[0]] + points[e[1]]);
      ++report.inner_boundary_edges;
    }
  }

  return first_inner;
}

// T-vertices: boundary vertices strictly inside a boundary edge (grid of boundary vertices,
// cells the size of the mean boundary edge).
// Returns the first one found.
glm::dvec3 countTVertices(const std::vector<glm::dvec3>& points, const Edges& boundary, double tol,
                          PatchMeshReport& report) {
  glm::dvec3 first_t(0.0);
  if (!boundary.empty()) {
    std::vector<uint32_t> boundary_vertices;
    double total = 0.0;
    for (const auto& e : boundary) {
      boundary_vertices.push_back(e[0]);
      boundary_vertices.push_back(e[1]);
      total += dist(points[e[0]], points[e[1]]);
    }
    std::sort(boundary_vertices.begin(), boundary_vertices.end());
    boundary_vertices.erase(std::unique(boundary_vertices.begin(), boundary_vertices.end()), boundary_vertices.end());
    const double cell = std::max(total / static_cast<double>(boundary.size()), 1e-30);
    auto cellOf = [&](const glm::dvec3& p) {
      const glm::dvec3 q = glm::floor(p / cell);
      return CellKey{static_cast<int64_t>(q.x), static_cast<int64_t>(q.y), static_cast<int64_t>(q.z)};
    };
    std::unordered_map<CellKey, std::vector<uint32_t>, CellHash> grid;
    for (uint32_t v : boundary_vertices) grid[cellOf(points[v])].push_back(v);
    std::vector<char> is_t(points.size(), 0);
    auto test = [&](uint32_t v, const std::array<uint32_t, 2>& e) {
      if (v == e[0] || v == e[1] || is_t[v]) return;
      const glm::dvec3 a = points[e[0]], ab = points[e[1]] - a, av = points[v] - a;
      const double len2 = glm::dot(ab, ab);
      if (!(len2 > 0.0)) return;
      const double s = glm::dot(av, ab) / len2;
      if (!(s > 0.0 && s < 1.0)) return;
      if (glm::length(av - s * ab) <= tol) {
        if (report.t_vertices == 0) first_t = points[v];
        is_t[v] = 1;
        ++report.t_vertices;
      }
    };
    for (const auto& e : boundary) {
      const glm::dvec3 lo = glm::min(points[e[0]], points[e[1]]) - tol, hi = glm::max(points[e[0]], points[e[1]]) + tol;
      const CellKey c0 = cellOf(lo), c1 = cellOf(hi);
      const double cells = (static_cast<double>(c1.x - c0.x) + 1) * (static_cast<double>(c1.y - c0.y) + 1) *
                           (static_cast<double>(c1.z - c0.z) + 1);
      if (!(cells <= 4096.0)) {  // a very long edge: test every boundary vertex
        for (uint32_t v : boundary_vertices) test(v, e);
        continue;
      }
      for (int64_t z = c0.z; z <= c1.z; ++z)
        for (int64_t y = c0.y; y <= c1.y; ++y)
          for (int64_t x = c0.x; x <= c1.x; ++x)
            if (const auto it = grid.find(CellKey{x, y, z}); it != grid.end())
              for (uint32_t v : it->second) test(v, e);
    }
  }

  return first_t;
}

std::string firstProblem(const PatchMeshReport& report, const glm::dvec3& first_t,
                         const glm::dvec3& first_inner) {
  if (report.refused_faces)
    return std::to_string(report.refused_faces) + " faces refused by OpenMesh (non-manifold)";
  if (report.inconsistent_orientation)
    return std::to_string(report.inconsistent_orientation) +
           " edges between faces of opposite orientation";
  if (report.t_vertices)
    return std::to_string(report.t_vertices) + " T-vertices, the first at " + where(first_t);
  if (report.inner_boundary_edges)
    return std::to_string(report.inner_boundary_edges) +
           " boundary edges inside the set, the first near " + where(first_inner);
  return {};
}

PatchMeshReport checkPatchMesh(const TriangleMesh& mesh, const NurbsPatchSet& patches, float tolerance) {
  PatchMeshReport report;
  // Exact weld (exact_weld.h); the geometry below works in double.
  const WeldedTriangles welded = weldExactly(mesh);
  const std::vector<std::array<uint32_t, 3>>& triangles = welded.triangles;
  const std::vector<glm::dvec3> points(welded.points.begin(), welded.points.end());
  report.degenerate_faces = welded.skipped;
  for (const auto& [a, b, c] : triangles)  // zero area, kept in the mesh
    if (glm::length(glm::cross(points[b] - points[a], points[c] - points[a])) == 0.0)
      ++report.degenerate_faces;
  report.vertices = points.size();

  // Orientation: an edge shared by two faces must be used once in each direction.
  for (const auto& [key, use] : countEdgeUses(triangles))
    if (use.forward + use.backward == 2 && use.forward != 1) ++report.inconsistent_orientation;

  const Edges boundary = halfEdgeBoundary(points, triangles, report);
  report.boundary_edges = boundary.size();

  // Distances: the given tolerance plus float rounding at the set's magnitude.
  double magnitude = 0.0;
  for (const glm::dvec3& p : points) magnitude = std::max({magnitude, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  double tol = static_cast<double>(std::max(tolerance, 0.0f)) + 1e-6 * magnitude;
  if (!std::isfinite(tol)) tol = 0.0;

  const PatchBorders borders = patchBorders(patches, tol);
  const glm::dvec3 first_inner = countInnerBoundaryEdges(points, boundary, borders, tol, report);
  const glm::dvec3 first_t = countTVertices(points, boundary, tol, report);
  report.first_problem = firstProblem(report, first_t, first_inner);
  return report;
}

}  // namespace tw
