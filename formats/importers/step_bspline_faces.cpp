// Conforming tessellation of untrimmed B-spline faces, and the grid planned for trimmed ones. See step_bspline_faces.h.
#include "step_bspline_faces.h"

#include <BRepTools.hxx>
#include <BRep_Tool.hxx>
#include <GeomConvert.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_BezierSurface.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <Geom_Surface.hxx>
#include <Poly_PolygonOnTriangulation.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>

#include <algorithm>
#include <array>
#include <cmath>

#include "nurbs_conforming.h"

namespace tw {
namespace {

// Border nodes lie on the rectangle's sides within this share of its extent.
constexpr double kRelativeSideTolerance = 1e-5;
// A side's first and last nodes are its corners within this share of it (BRepMesh's nodes come
// from the edges' parameter curves, which OpenCASCADE fits when the file has none).
constexpr double kCornerTolerance = 1e-3;

// The face's surface as a B-spline restricted to [u0, u1] x [v0, v1], or null when it is not a
// B-spline or Bézier surface or cannot be restricted.
Handle(Geom_BSplineSurface) restrictedBSpline(const TopoDS_Face& face, double u0, double u1,
                                              double v0, double v1) {
  Handle(Geom_Surface) surface = BRep_Tool::Surface(face);
  while (auto trimmed = Handle(Geom_RectangularTrimmedSurface)::DownCast(surface))
    surface = trimmed->BasisSurface();
  Handle(Geom_BSplineSurface) bspline;
  if (auto b = Handle(Geom_BSplineSurface)::DownCast(surface))
    bspline = Handle(Geom_BSplineSurface)::DownCast(b->Copy());
  else if (auto bezier = Handle(Geom_BezierSurface)::DownCast(surface))
    bspline = GeomConvert::SurfaceToBSplineSurface(bezier);
  if (bspline.IsNull()) return bspline;
  try {
    if (bspline->IsUPeriodic()) bspline->SetUNotPeriodic();
    if (bspline->IsVPeriodic()) bspline->SetVNotPeriodic();
    double su0, su1, sv0, sv1;
    bspline->Bounds(su0, su1, sv0, sv1);
    const double eu = 1e-9 * (su1 - su0), ev = 1e-9 * (sv1 - sv0);
    if (u0 > su0 + eu || u1 < su1 - eu || v0 > sv0 + ev || v1 < sv1 - ev)
      bspline->Segment(u0, u1, v0, v1);
  } catch (const Standard_Failure&) {
    return Handle(Geom_BSplineSurface)();
  }
  return bspline;
}

// The surface in the scene model's form: control points placed and relative to `centre`.
NurbsPatch patchOf(const Geom_BSplineSurface& s, const gp_Trsf& placement, const glm::dvec3& centre) {
  NurbsPatch patch;
  patch.degree_u = uint32_t(s.UDegree());
  patch.degree_v = uint32_t(s.VDegree());
  patch.count_u = uint32_t(s.NbUPoles());
  patch.count_v = uint32_t(s.NbVPoles());
  TColStd_Array1OfReal knots_u(1, s.NbUPoles() + s.UDegree() + 1);
  TColStd_Array1OfReal knots_v(1, s.NbVPoles() + s.VDegree() + 1);
  s.UKnotSequence(knots_u);
  s.VKnotSequence(knots_v);
  for (int i = knots_u.Lower(); i <= knots_u.Upper(); ++i) patch.knots_u.push_back(float(knots_u(i)));
  for (int i = knots_v.Lower(); i <= knots_v.Upper(); ++i) patch.knots_v.push_back(float(knots_v(i)));
  patch.control_points.reserve(size_t(patch.count_u) * patch.count_v);
  for (int v = 1; v <= s.NbVPoles(); ++v)
    for (int u = 1; u <= s.NbUPoles(); ++u) {
      const gp_Pnt p = s.Pole(u, v).Transformed(placement);
      patch.control_points.push_back(glm::vec4(
          glm::vec3(glm::dvec3(p.X(), p.Y(), p.Z()) - centre), float(s.Weight(u, v))));
    }
  return patch;
}

int wireCount(const TopoDS_Face& face) {
  int wires = 0;
  for (TopExp_Explorer w(face, TopAbs_WIRE); w.More(); w.Next()) ++wires;
  return wires;
}

}  // namespace

bool planBSplineFaceGrid(const TopoDS_Face& face, double u0, double u1, double v0, double v1,
                         double deflection, uint32_t& n, uint32_t& m) {
  if (!(u1 > u0) || !(v1 > v0)) return false;
  const Handle(Geom_BSplineSurface) surface = restrictedBSpline(face, u0, u1, v0, v1);
  if (surface.IsNull()) return false;
  // Curvature does not change under the part's placement: the surface as it is in the file.
  return planPatchGrid(patchOf(*surface, gp_Trsf(), glm::dvec3(0.0)), float(deflection), n, m);
}

bool tessellateBSplineFace(const TopoDS_Face& face, const Poly_Triangulation& triangulation,
                           const gp_Trsf& placement, const glm::dvec3& centre,
                           const std::vector<uint32_t>& node_vertex, double deflection,
                           TriangleMesh& out) {
  if (!triangulation.HasUVNodes() || wireCount(face) != 1) return false;
  double u0, u1, v0, v1;
  BRepTools::UVBounds(face, u0, u1, v0, v1);
  if (!(u1 > u0) || !(v1 > v0)) return false;
  const Handle(Geom_BSplineSurface) surface = restrictedBSpline(face, u0, u1, v0, v1);
  if (surface.IsNull()) return false;

  // The border: the triangulation's nodes on the rectangle's sides, by side in the patch's
  // counter-clockwise order. The wire is closed, so when all edge nodes lie on the sides it runs
  // round the whole rectangle.
  const double eu = kRelativeSideTolerance * (u1 - u0) + 1e-12;
  const double ev = kRelativeSideTolerance * (v1 - v0) + 1e-12;
  struct Node {
    double t;
    uint32_t vertex;
  };
  std::array<std::vector<Node>, 4> sides;
  std::vector<bool> on_border(size_t(triangulation.NbNodes()) + 1, false);
  for (int n = 1; n <= triangulation.NbNodes(); ++n) {
    const gp_Pnt2d uv = triangulation.UVNode(n);
    const double x = (uv.X() - u0) / (u1 - u0), y = (uv.Y() - v0) / (v1 - v0);
    const uint32_t vertex = node_vertex[size_t(n)];
    bool border = false;
    if (std::abs(uv.Y() - v0) <= ev) sides[0].push_back({x, vertex}), border = true;
    if (std::abs(uv.X() - u1) <= eu) sides[1].push_back({y, vertex}), border = true;
    if (std::abs(uv.Y() - v1) <= ev) sides[2].push_back({1.0 - x, vertex}), border = true;
    if (std::abs(uv.X() - u0) <= eu) sides[3].push_back({1.0 - y, vertex}), border = true;
    on_border[size_t(n)] = border;
  }
  // Every node on the face's edges must be one of them, or the wire cuts across the rectangle.
  TopLoc_Location location;
  const Handle(Poly_Triangulation) handle = BRep_Tool::Triangulation(face, location);
  for (TopExp_Explorer e(face, TopAbs_EDGE); e.More(); e.Next()) {
    const Handle(Poly_PolygonOnTriangulation) polygon =
        BRep_Tool::PolygonOnTriangulation(TopoDS::Edge(e.Current()), handle, location);
    if (polygon.IsNull()) return false;
    for (int i = 1; i <= polygon->NbNodes(); ++i) {
      const int n = polygon->Node(i);
      if (n < 1 || n > triangulation.NbNodes() || !on_border[size_t(n)]) return false;
    }
  }

  // Each side's vertices in order, nodes welded into one (the two sides of a seam's end)
  // counted once.
  std::array<PatchSideString, 4> strings;
  for (int s = 0; s < 4; ++s) {
    std::vector<Node>& side = sides[s];
    std::sort(side.begin(), side.end(), [](const Node& a, const Node& b) { return a.t < b.t; });
    for (const Node& node : side) {
      if (!strings[s].vertices.empty() && strings[s].vertices.back() == node.vertex) continue;
      strings[s].vertices.push_back(node.vertex);
      strings[s].t.push_back(std::clamp(node.t, 0.0, 1.0));
    }
  }
  // A side the surface collapses to a point (a pole) is its one vertex, and it is the corner of
  // the sides beside it even where BRepMesh put no node at that corner of the rectangle.
  std::array<bool, 4> pole{};
  for (int s = 0; s < 4; ++s) {
    if (strings[s].vertices.size() != 1) continue;
    static constexpr double kCorners[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    const gp_Pnt a = surface->Value(u0 + kCorners[s][0] * (u1 - u0), v0 + kCorners[s][1] * (v1 - v0));
    const gp_Pnt b = surface->Value(u0 + kCorners[(s + 1) % 4][0] * (u1 - u0),
                                    v0 + kCorners[(s + 1) % 4][1] * (v1 - v0));
    pole[s] = a.Distance(b) <= deflection;
    if (!pole[s]) return false;
    strings[s].t.front() = 0.0;
  }
  for (int s = 0; s < 4; ++s) {
    if (pole[s]) continue;
    PatchSideString& side = strings[s];
    if (side.vertices.empty()) return false;
    const PatchSideString& before = strings[(s + 3) % 4];
    const PatchSideString& after = strings[(s + 1) % 4];
    if (side.t.front() > kCornerTolerance) {
      if (!pole[(s + 3) % 4]) return false;  // the side is not whole
      side.vertices.insert(side.vertices.begin(), before.vertices.front());
      side.t.insert(side.t.begin(), 0.0);
    }
    if (side.t.back() < 1.0 - kCornerTolerance) {
      if (!pole[(s + 1) % 4]) return false;
      side.vertices.push_back(after.vertices.front());
      side.t.push_back(1.0);
    }
    if (side.vertices.size() < 2) return false;
    side.t.front() = 0.0;
    side.t.back() = 1.0;
  }
  const bool reversed = face.Orientation() == TopAbs_REVERSED;
  return tessellatePatchInside(patchOf(*surface, placement, centre), strings, float(deflection),
                               reversed, out);
}

}  // namespace tw
