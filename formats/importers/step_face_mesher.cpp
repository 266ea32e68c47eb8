// BRepMesh with the conforming tessellator's grid inside B-spline faces. See step_face_mesher.h.
#include "step_face_mesher.h"

#include <BRepMesh_Context.hxx>
#include <BRepMesh_DelaunayBaseMeshAlgo.hxx>
#include <BRepMesh_DelaunayDeflectionControlMeshAlgo.hxx>
#include <BRepMesh_FaceDiscret.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepMesh_MeshAlgoFactory.hxx>
#include <BRepMesh_NURBSRangeSplitter.hxx>
#include <IMeshData_Edge.hxx>
#include <IMeshData_Face.hxx>
#include <IMeshData_PCurve.hxx>
#include <IMeshData_Wire.hxx>
#include <IMeshTools_MeshAlgoFactory.hxx>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "step_bspline_faces.h"

namespace tw {
namespace {

// A planned node nearer to a wire than this many grid steps is left out: Delaunay would join it
// to the wire's nodes by slivers.
constexpr double kWireClearance = 1.0 / 3.0;

// The nodes BRepMesh inserts into a B-spline face before triangulating it: the tessellator's
// planned grid over the face's parameter range, clipped to its wires (BRepMesh drops the nodes its
// classifier finds outside; this drops those too near a wire).
class PlannedGridSplitter : public BRepMesh_NURBSRangeSplitter {
 public:
  Handle(IMeshData::ListOfPnt2d) GenerateSurfaceNodes(
      const IMeshTools_Parameters& parameters) const override {
    generated_ = false;
    const auto [u0, u1] = GetRangeU();
    const auto [v0, v1] = GetRangeV();
    uint32_t n = 0, m = 0;
    if (!planBSplineFaceGrid(GetDFace()->GetFace(), u0, u1, v0, v1, GetDFace()->GetDeflection(),
                             n, m))
      return BRepMesh_NURBSRangeSplitter::GenerateSurfaceNodes(parameters);
    const double step_u = (u1 - u0) / n, step_v = (v1 - v0) / m;
    const std::vector<bool> near = nodesNearWires(n, m, u0, v0, step_u, step_v);
    Handle(IMeshData::ListOfPnt2d) nodes = new IMeshData::ListOfPnt2d;
    for (uint32_t j = 1; j < m; ++j)
      for (uint32_t i = 1; i < n; ++i)
        if (!near[size_t(j) * (n + 1) + i]) nodes->Append(gp_Pnt2d(u0 + i * step_u, v0 + j * step_v));
    generated_ = true;
    return nodes;
  }

  bool generated() const { return generated_; }

 private:
  // Marks the grid nodes within kWireClearance steps of a segment of the face's discretized
  // wires, visiting only the nodes around each segment.
  std::vector<bool> nodesNearWires(uint32_t n, uint32_t m, double u0, double v0, double step_u,
                                   double step_v) const {
    std::vector<bool> near(size_t(n + 1) * (m + 1), false);
    auto mark = [&](const gp_Pnt2d& a_uv, const gp_Pnt2d& b_uv) {
      const double ax = (a_uv.X() - u0) / step_u, ay = (a_uv.Y() - v0) / step_v;
      const double bx = (b_uv.X() - u0) / step_u, by = (b_uv.Y() - v0) / step_v;
      const double dx = bx - ax, dy = by - ay, length2 = dx * dx + dy * dy;
      const int i0 = std::max(0, int(std::floor(std::min(ax, bx) - kWireClearance)));
      const int i1 = std::min(int(n), int(std::ceil(std::max(ax, bx) + kWireClearance)));
      const int j0 = std::max(0, int(std::floor(std::min(ay, by) - kWireClearance)));
      const int j1 = std::min(int(m), int(std::ceil(std::max(ay, by) + kWireClearance)));
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
          const double s = length2 > 0.0 ? std::clamp(((i - ax) * dx + (j - ay) * dy) / length2, 0.0, 1.0) : 0.0;
          const double ex = ax + s * dx - i, ey = ay + s * dy - j;
          if (ex * ex + ey * ey < kWireClearance * kWireClearance) near[size_t(j) * (n + 1) + i] = true;
        }
    };
    const IMeshData::IFaceHandle& face = GetDFace();
    for (int w = 0; w < face->WiresNb(); ++w) {
      const IMeshData::IWireHandle& wire = face->GetWire(w);
      for (int e = 0; e < wire->EdgesNb(); ++e) {
        const IMeshData::IPCurveHandle& curve =
            wire->GetEdge(e)->GetPCurve(face.get(), wire->GetEdgeOrientation(e));
        for (int p = 1; p < curve->ParametersNb(); ++p) mark(curve->GetPoint(p - 1), curve->GetPoint(p));
      }
    }
    return near;
  }

  mutable bool generated_ = false;
};

using PlannedGridAlgoBase =
    BRepMesh_DelaunayDeflectionControlMeshAlgo<PlannedGridSplitter, BRepMesh_DelaunayBaseMeshAlgo>;

// BRepMesh's deflection-controlled Delaunay with the planned nodes registered before the first
// triangulation: the constrained Delaunay of wires and planned nodes, refined only where a
// triangle still deviates. Records the faces it meshed.
class PlannedGridAlgo : public PlannedGridAlgoBase {
 public:
  explicit PlannedGridAlgo(TopTools_MapOfShape& planned) : planned_(planned) {
    SetPreProcessSurfaceNodes(true);
  }

  void Perform(const IMeshData::IFaceHandle& face, const IMeshTools_Parameters& parameters,
               const Message_ProgressRange& range) override {
    PlannedGridAlgoBase::Perform(face, parameters, range);
    if (getRangeSplitter().generated() && !face->IsSet(IMeshData_Failure))
      planned_.Add(face->GetFace());
  }

 private:
  TopTools_MapOfShape& planned_;
};

// B-spline and Bézier faces to PlannedGridAlgo, the rest to BRepMesh's own choice.
class PlannedGridAlgoFactory : public IMeshTools_MeshAlgoFactory {
 public:
  explicit PlannedGridAlgoFactory(TopTools_MapOfShape& planned)
      : planned_(planned), default_(new BRepMesh_MeshAlgoFactory) {}

  Handle(IMeshTools_MeshAlgo) GetAlgo(const GeomAbs_SurfaceType type,
                                      const IMeshTools_Parameters& parameters) const override {
    if (type == GeomAbs_BSplineSurface || type == GeomAbs_BezierSurface)
      return new PlannedGridAlgo(planned_);
    return default_->GetAlgo(type, parameters);
  }

 private:
  TopTools_MapOfShape& planned_;
  Handle(IMeshTools_MeshAlgoFactory) default_;
};

}  // namespace

void meshShapeFaces(const TopoDS_Shape& shape, double deflection, double angle_rad,
                    TopTools_MapOfShape& planned) {
  Handle(IMeshTools_Context) context = new BRepMesh_Context;
  context->SetFaceDiscret(new BRepMesh_FaceDiscret(new PlannedGridAlgoFactory(planned)));
  BRepMesh_IncrementalMesh mesher;
  mesher.SetShape(shape);
  IMeshTools_Parameters& parameters = mesher.ChangeParameters();
  parameters.Deflection = deflection;
  parameters.Angle = angle_rad;
  parameters.Relative = false;
  parameters.InParallel = false;
  mesher.Perform(context);
}

}  // namespace tw
