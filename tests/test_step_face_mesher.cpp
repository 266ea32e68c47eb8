// The B-spline faces of a real STEP solid meshed on the conforming tessellator's grid
// (formats/importers/step_face_mesher.h): every one of them takes the planned grid, and the
// surface stays within the chordal tolerance of its triangles, as it does for BRepMesh's own
// refining algorithm at the same deflection.
#include <gtest/gtest.h>

#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepTools.hxx>
#include <BRep_Tool.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <Poly_Triangulation.hxx>
#include <STEPControl_Reader.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>

#include <algorithm>
#include <cstdio>

#include "step_face_mesher.h"
#include "test_support.h"

namespace tw {
namespace {

TopoDS_Shape readShape(const char* name) {
  STEPControl_Reader reader;
  const std::string path = (test::sharedDataDir() / name).string();
  if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) return TopoDS_Shape();
  reader.TransferRoots();
  return reader.OneShape();
}

bool isBSpline(const TopoDS_Face& face) {
  const GeomAbs_SurfaceType type = GeomAdaptor_Surface(BRep_Tool::Surface(face)).GetType();
  return type == GeomAbs_BSplineSurface || type == GeomAbs_BezierSurface;
}

struct FaceMeshFigures {
  int faces = 0;
  int triangles = 0;
  double largest_error = 0.0;  // surface to triangle, at centroids and edge midpoints
};

// The distance between each triangle's centroid and edge midpoints and the surface at the same
// parameters, over the B-spline faces.
FaceMeshFigures measure(const TopoDS_Shape& shape) {
  FaceMeshFigures figures;
  for (TopExp_Explorer e(shape, TopAbs_FACE); e.More(); e.Next()) {
    const TopoDS_Face& face = TopoDS::Face(e.Current());
    if (!isBSpline(face)) continue;
    TopLoc_Location location;
    const Handle(Poly_Triangulation) mesh = BRep_Tool::Triangulation(face, location);
    if (mesh.IsNull() || !mesh->HasUVNodes()) continue;
    const Handle(Geom_Surface) surface = BRep_Tool::Surface(face);
    ++figures.faces;
    figures.triangles += mesh->NbTriangles();
    auto error = [&](std::initializer_list<int> nodes) {
      gp_XYZ point(0, 0, 0);
      gp_XY uv(0, 0);
      for (int n : nodes) {
        point += mesh->Node(n).XYZ();
        uv += mesh->UVNode(n).XY();
      }
      point /= double(nodes.size());
      uv /= double(nodes.size());
      return surface->Value(uv.X(), uv.Y()).Distance(gp_Pnt(point));
    };
    for (int t = 1; t <= mesh->NbTriangles(); ++t) {
      int a, b, c;
      mesh->Triangle(t).Get(a, b, c);
      figures.largest_error = std::max({figures.largest_error, error({a, b, c}), error({a, b}),
                                        error({b, c}), error({c, a})});
    }
  }
  return figures;
}

TEST(StepFaceMesher, TrimmedBSplineFacesTakeThePlannedGridWithinTheChordalTolerance) {
  // The file's millimetres (this reader converts nothing): the importer's deflection for the part
  // (0.2 % of its 114 mm diagonal) and its angle.
  constexpr double kDeflection = 0.23, kAngle = 20.0 * M_PI / 180.0;
  const TopoDS_Shape shape = readShape("Ventilator.stp");
  ASSERT_FALSE(shape.IsNull());

  BRepMesh_IncrementalMesh reference(shape, kDeflection, false, kAngle, false);
  const FaceMeshFigures theirs = measure(shape);
  BRepTools::Clean(shape);

  TopTools_MapOfShape planned;
  meshShapeFaces(shape, kDeflection, kAngle, planned);
  const FaceMeshFigures ours = measure(shape);
  std::printf("B-spline faces %d: planned %d; triangles %d (BRepMesh %d); largest error %.3g mm "
              "(BRepMesh %.3g mm) at a deflection of %.3g mm\n",
              ours.faces, planned.Extent(), ours.triangles, theirs.triangles, ours.largest_error,
              theirs.largest_error, kDeflection);
  EXPECT_EQ(ours.faces, 189);
  EXPECT_EQ(planned.Extent(), 189) << "every B-spline face on the planned grid";
  EXPECT_LE(ours.largest_error, kDeflection);
  EXPECT_LE(ours.largest_error, std::max(theirs.largest_error, 0.5 * kDeflection));
}

}  // namespace
}  // namespace tw
