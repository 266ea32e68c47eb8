// Boolean differences of scene solids through OpenCASCADE. See solid_cut.h.
#include "solid_cut.h"

#include <BRepAlgoAPI_Common.hxx>
#include <BRepAlgoAPI_Cut.hxx>
#include <BRepBndLib.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepBuilderAPI_Sewing.hxx>
#include <BRepBuilderAPI_Transform.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCone.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <Poly_Triangulation.hxx>
#include <ShapeFix_Solid.hxx>
#include <Standard_Failure.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shell.hxx>
#include <gp_Trsf.hxx>

#include <cmath>
#include <memory>
#include <variant>

#include "face_weld.h"
#include "tessellate.h"

namespace tw {
namespace {

constexpr double kAngularDeflectionRad = 0.35;  // 20 degrees, as the STEP importer meshes
constexpr double kSewingTolerance = 1e-6;        // metres: mesh shells share exact positions

gp_Pnt toPnt(const glm::dvec3& p) { return gp_Pnt(p.x, p.y, p.z); }

bool positiveFinite(double v) { return std::isfinite(v) && v > 0.0; }

// A rigid frame as OpenCASCADE's transformation (which refuses anything but a rotation).
gp_Trsf toTrsf(const glm::dmat4& m) {
  gp_Trsf t;
  t.SetValues(m[0][0], m[1][0], m[2][0], m[3][0],  //
              m[0][1], m[1][1], m[2][1], m[3][1],  //
              m[0][2], m[1][2], m[2][2], m[3][2]);
  return t;
}

TopoDS_Shape placed(const TopoDS_Shape& shape, const glm::dmat4& frame) {
  return BRepBuilderAPI_Transform(shape, toTrsf(frame), true).Shape();
}

TopoDS_Face polygonFace(const std::vector<glm::dvec3>& points) {
  BRepBuilderAPI_MakePolygon polygon;
  for (const glm::dvec3& p : points) polygon.Add(toPnt(p));
  polygon.Close();
  if (!polygon.IsDone()) throw SolidCutError("a polygon that OpenCASCADE cannot close");
  BRepBuilderAPI_MakeFace face(polygon.Wire(), true);
  if (!face.IsDone()) throw SolidCutError("a polygon that is not planar");
  return face.Face();
}

// Closed shells of triangles, sewn by their shared positions, as oriented solids.
void appendMeshSolids(const TriangleMesh& mesh, TopTools_ListOfShape& out) {
  if (mesh.indices.empty()) return;
  if (mesh.triangleCount() > kMaxCutMeshTriangles)
    throw SolidCutError("a mesh of " + std::to_string(mesh.triangleCount()) +
                        " triangles (at most " + std::to_string(kMaxCutMeshTriangles) + " are cut)");
  BRepBuilderAPI_Sewing sewing(kSewingTolerance);
  for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
    const glm::dvec3 a(mesh.positions[mesh.indices[i]]), b(mesh.positions[mesh.indices[i + 1]]),
        c(mesh.positions[mesh.indices[i + 2]]);
    if (glm::length(glm::cross(b - a, c - a)) <= 1e-18) continue;  // degenerate: no face
    sewing.Add(polygonFace({a, b, c}));
  }
  sewing.Perform();
  int shells = 0;
  for (TopExp_Explorer e(sewing.SewedShape(), TopAbs_SHELL); e.More(); e.Next()) {
    const TopoDS_Shell& shell = TopoDS::Shell(e.Current());
    if (!BRep_Tool::IsClosed(shell)) throw SolidCutError("a mesh that is not a closed shell");
    ShapeFix_Solid fix;
    out.Append(fix.SolidFromShell(shell));
    ++shells;
  }
  if (shells == 0) throw SolidCutError("a mesh that sews into no closed shell");
}

// One primitive in its canonical frame (scene.h), exactly where OpenCASCADE has the solid.
TopoDS_Shape primitiveSolid(const Primitive& primitive) {
  struct Builder {
    TopoDS_Shape operator()(const Box& b) const {
      const glm::dvec3 h(b.half_extents);
      if (!(positiveFinite(h.x) && positiveFinite(h.y) && positiveFinite(h.z)))
        throw SolidCutError("a box without volume");
      return BRepPrimAPI_MakeBox(toPnt(-h), toPnt(h)).Shape();
    }
    TopoDS_Shape operator()(const Cylinder& c) const {
      if (!(positiveFinite(c.radius) && positiveFinite(c.height))) throw SolidCutError("a cylinder without volume");
      return BRepPrimAPI_MakeCylinder(c.radius, c.height).Shape();
    }
    TopoDS_Shape operator()(const Cone& c) const {
      if (!positiveFinite(c.height) || !(c.radius_bottom >= 0.0f && c.radius_top >= 0.0f) ||
          !(c.radius_bottom > 0.0f || c.radius_top > 0.0f))
        throw SolidCutError("a cone without volume");
      if (c.radius_bottom == c.radius_top) return BRepPrimAPI_MakeCylinder(c.radius_bottom, c.height).Shape();
      return BRepPrimAPI_MakeCone(c.radius_bottom, c.radius_top, c.height).Shape();
    }
    TopoDS_Shape operator()(const Sphere& s) const {
      if (!positiveFinite(s.radius)) throw SolidCutError("a sphere without volume");
      return BRepPrimAPI_MakeSphere(s.radius).Shape();
    }
    TopoDS_Shape operator()(const TorusSegment& t) const {
      if (!(positiveFinite(t.minor_radius) && t.major_radius > t.minor_radius && positiveFinite(t.sweep_rad)))
        throw SolidCutError("a torus segment without volume");
      return BRepPrimAPI_MakeTorus(t.major_radius, t.minor_radius, std::min(double(t.sweep_rad), 2.0 * M_PI)).Shape();
    }
    TopoDS_Shape operator()(const Extrusion& e) const {
      if (e.profile.size() < 3 || !positiveFinite(e.height)) throw SolidCutError("an extrusion without volume");
      std::vector<glm::dvec3> ring;
      for (const glm::vec2& p : e.profile) ring.push_back(glm::dvec3(p.x, p.y, 0.0));
      return BRepPrimAPI_MakePrism(polygonFace(ring), gp_Vec(0.0, 0.0, e.height)).Shape();
    }
    TopoDS_Shape operator()(const Revolution& r) const {
      // Its facets, sewn: the profile may touch the axis, which a revolved face handles badly.
      TriangleMesh mesh;
      tessellatePrimitive(r, kDefaultChordalTolerance, mesh);
      TopTools_ListOfShape solids;
      appendMeshSolids(mesh, solids);
      return solids.First();
    }
  };
  return std::visit(Builder{}, primitive);
}

TopTools_ListOfShape solidsOf(const SolidSet& set) {
  TopTools_ListOfShape out;
  appendMeshSolids(set.mesh, out);
  for (const auto& [frame, primitive] : set.primitives) out.Append(placed(primitiveSolid(primitive), frame));
  return out;
}

// A half-space as a finite solid reaching well past `reach` (the host's box): a slab of the
// plane's side, cut to the boundary's prism when it has one.
TopoDS_Shape halfSpaceSolid(const HalfSpace& h, const Bnd_Box& reach) {
  double x0, y0, z0, x1, y1, z1;
  reach.Get(x0, y0, z0, x1, y1, z1);
  const glm::dvec3 lo(x0, y0, z0), hi(x1, y1, z1), centre = 0.5 * (lo + hi);
  const double diagonal = glm::length(hi - lo);
  auto extent = [&](const glm::dmat4& frame) {
    return glm::length(glm::dvec3(frame[3]) - centre) + diagonal + 1.0;
  };
  const double l = extent(h.plane);
  const glm::dvec3 slab_lo(-l, -l, h.material_below ? -l : 0.0), slab_hi(l, l, h.material_below ? 0.0 : l);
  TopoDS_Shape slab = placed(BRepPrimAPI_MakeBox(toPnt(slab_lo), toPnt(slab_hi)).Shape(), h.plane);
  if (h.boundary.empty()) return slab;
  if (h.boundary.size() < 3) throw SolidCutError("a bounded half-space whose boundary has fewer than three points");
  const double b = extent(h.boundary_frame);
  std::vector<glm::dvec3> ring;
  for (const glm::dvec2& p : h.boundary) ring.push_back(glm::dvec3(p, -b));
  const TopoDS_Shape prism =
      placed(BRepPrimAPI_MakePrism(polygonFace(ring), gp_Vec(0.0, 0.0, 2.0 * b)).Shape(), h.boundary_frame);
  BRepAlgoAPI_Common common(slab, prism);
  if (!common.IsDone() || common.HasErrors()) throw SolidCutError("OpenCASCADE could not bound a half-space");
  return common.Shape();
}

// The faces' triangles, welded by exact position (face_weld.h).
TriangleMesh meshShape(const TopoDS_Shape& shape, double deflection) {
  TriangleMesh out;
  BRepMesh_IncrementalMesh mesher(shape, deflection, false, kAngularDeflectionRad, false);
  FaceWeld weld(out);
  for (TopExp_Explorer e(shape, TopAbs_FACE); e.More(); e.Next()) {
    const TopoDS_Face& face = TopoDS::Face(e.Current());
    TopLoc_Location location;
    const Handle(Poly_Triangulation) triangulation = BRep_Tool::Triangulation(face, location);
    if (triangulation.IsNull()) continue;
    weld.addNodes(*triangulation, location.Transformation());
    weld.addTriangles(*triangulation, face.Orientation() == TopAbs_REVERSED);
  }
  return out;
}

}  // namespace

namespace {

enum class Operation { Difference, Intersection };

// `host` combined with `others` and the half-spaces by `op`, meshed.
TriangleMesh combine(Operation op, const SolidSet& host, const SolidSet& others,
                     const std::vector<HalfSpace>& half_spaces, double chordal_tolerance_m) {
  if (!positiveFinite(chordal_tolerance_m)) throw SolidCutError("a chordal tolerance that is not positive");
  try {
    const TopTools_ListOfShape arguments = solidsOf(host);
    if (arguments.IsEmpty()) return TriangleMesh{};
    TopTools_ListOfShape tools = solidsOf(others);
    if (!half_spaces.empty()) {
      Bnd_Box reach;
      for (const TopoDS_Shape& s : arguments) BRepBndLib::Add(s, reach);
      for (const HalfSpace& h : half_spaces) tools.Append(halfSpaceSolid(h, reach));
    }
    if (tools.IsEmpty()) {
      if (op == Operation::Intersection) throw SolidCutError("an intersection with nothing");
      TopoDS_Compound whole;
      BRep_Builder builder;
      builder.MakeCompound(whole);
      for (const TopoDS_Shape& s : arguments) builder.Add(whole, s);
      return meshShape(whole, chordal_tolerance_m);
    }
    std::unique_ptr<BRepAlgoAPI_BooleanOperation> boolean;
    if (op == Operation::Difference) boolean = std::make_unique<BRepAlgoAPI_Cut>();
    else boolean = std::make_unique<BRepAlgoAPI_Common>();
    boolean->SetArguments(arguments);
    boolean->SetTools(tools);
    boolean->Build();
    if (!boolean->IsDone() || boolean->HasErrors())
      throw SolidCutError(op == Operation::Difference ? "OpenCASCADE's boolean difference failed"
                                                      : "OpenCASCADE's boolean intersection failed");
    return meshShape(boolean->Shape(), chordal_tolerance_m);
  } catch (const Standard_Failure& e) {
    throw SolidCutError(std::string("OpenCASCADE: ") + e.GetMessageString());
  }
}

}  // namespace

TriangleMesh subtractSolids(const SolidSet& host, const SolidSet& cutters,
                            const std::vector<HalfSpace>& half_spaces, double chordal_tolerance_m) {
  return combine(Operation::Difference, host, cutters, half_spaces, chordal_tolerance_m);
}

TriangleMesh intersectSolids(const SolidSet& host, const SolidSet& others,
                             const std::vector<HalfSpace>& half_spaces, double chordal_tolerance_m) {
  return combine(Operation::Intersection, host, others, half_spaces, chordal_tolerance_m);
}

}  // namespace tw
