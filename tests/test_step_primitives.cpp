// Primitive recognition from B-rep solids: OpenCASCADE's own primitives, placed anywhere, are
// recognized with their parameters and frames; near misses (a hole, a cut, a partial sweep) are
// not. Then a real STEP part: as1_pe_203's rod is a cylinder that lies where its mesh does.
#include <gtest/gtest.h>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepBuilderAPI_Transform.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCone.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <gp_Ax1.hxx>
#include <gp_Trsf.hxx>

#include <cmath>

#include "step_importer.h"
#include "step_primitives.h"
#include "test_support.h"

namespace tw {
namespace {

// A rotation of 40 degrees about a skew axis, then a translation far from the origin.
gp_Trsf placement() {
  gp_Trsf rotation, translation;
  rotation.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(1, 2, 3)), 40.0 * M_PI / 180.0);
  translation.SetTranslation(gp_Vec(120.0, -35.0, 8.0));
  return translation * rotation;
}

TopoDS_Shape placed(const TopoDS_Shape& shape) {
  return BRepBuilderAPI_Transform(shape, placement(), true).Shape();
}

glm::dvec3 where(const gp_Pnt& p) {
  const gp_Pnt q = p.Transformed(placement());
  return {q.X(), q.Y(), q.Z()};
}

void expectNear(const glm::dvec3& a, const glm::dvec3& b, double tolerance = 1e-6) {
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
}

TEST(StepPrimitives, CylinderConeSphereAndBoxAreRecognizedWhereverPlaced) {
  {
    const auto r = recognizePrimitive(placed(BRepPrimAPI_MakeCylinder(0.5, 3.0).Shape()), 1e-7);
    ASSERT_TRUE(r.has_value());
    const Cylinder* c = std::get_if<Cylinder>(&r->primitive);
    ASSERT_NE(c, nullptr);
    EXPECT_NEAR(c->radius, 0.5f, 1e-6f);
    EXPECT_NEAR(c->height, 3.0f, 1e-6f);
    EXPECT_TRUE(c->capped);
    // The canonical axis runs from the base to the top: either way round is the same solid.
    const glm::dvec3 base = r->frame.apply(glm::vec3(0, 0, 0));
    const glm::dvec3 top = r->frame.apply(glm::vec3(0, 0, c->height));
    const glm::dvec3 b0 = where(gp_Pnt(0, 0, 0)), b1 = where(gp_Pnt(0, 0, 3));
    const bool forward = glm::length(base - b0) < 1e-5;
    expectNear(base, forward ? b0 : b1, 1e-5);
    expectNear(top, forward ? b1 : b0, 1e-5);
  }
  {
    const auto r = recognizePrimitive(placed(BRepPrimAPI_MakeCone(1.0, 0.25, 2.0).Shape()), 1e-7);
    ASSERT_TRUE(r.has_value());
    const Cone* c = std::get_if<Cone>(&r->primitive);
    ASSERT_NE(c, nullptr);
    EXPECT_NEAR(c->radius_bottom, 1.0f, 1e-5f);
    EXPECT_NEAR(c->radius_top, 0.25f, 1e-5f);
    EXPECT_NEAR(c->height, 2.0f, 1e-5f);
    expectNear(r->frame.apply(glm::vec3(0, 0, 0)), where(gp_Pnt(0, 0, 0)), 1e-5);
  }
  {
    const auto r = recognizePrimitive(placed(BRepPrimAPI_MakeCone(0.6, 0.0, 1.5).Shape()), 1e-7);
    ASSERT_TRUE(r.has_value()) << "a cone to its apex has one disc";
    const Cone* c = std::get_if<Cone>(&r->primitive);
    ASSERT_NE(c, nullptr);
    EXPECT_NEAR(c->radius_top, 0.0f, 1e-5f);
    EXPECT_NEAR(c->height, 1.5f, 1e-5f);
  }
  {
    const auto r = recognizePrimitive(placed(BRepPrimAPI_MakeSphere(gp_Pnt(1, 2, 3), 0.75).Shape()), 1e-7);
    ASSERT_TRUE(r.has_value());
    const Sphere* s = std::get_if<Sphere>(&r->primitive);
    ASSERT_NE(s, nullptr);
    EXPECT_NEAR(s->radius, 0.75f, 1e-6f);
    expectNear(r->frame.origin, where(gp_Pnt(1, 2, 3)), 1e-5);
  }
  {
    const auto r = recognizePrimitive(placed(BRepPrimAPI_MakeBox(2.0, 0.5, 1.0).Shape()), 1e-7);
    ASSERT_TRUE(r.has_value());
    const Box* b = std::get_if<Box>(&r->primitive);
    ASSERT_NE(b, nullptr);
    // The half extents are the box's, in some order of the frame's axes.
    std::vector<float> half{b->half_extents.x, b->half_extents.y, b->half_extents.z};
    std::sort(half.begin(), half.end());
    EXPECT_NEAR(half[0], 0.25f, 1e-6f);
    EXPECT_NEAR(half[1], 0.5f, 1e-6f);
    EXPECT_NEAR(half[2], 1.0f, 1e-6f);
    expectNear(r->frame.origin, where(gp_Pnt(1.0, 0.25, 0.5)), 1e-5);
    EXPECT_GT(glm::determinant(r->frame.linear), 0.0f) << "right-handed";
    // Every corner of the canonical box lands on a corner of the placed one.
    for (int i = 0; i < 8; ++i) {
      const glm::vec3 corner((i & 1 ? 1 : -1) * b->half_extents.x,
                             (i & 2 ? 1 : -1) * b->half_extents.y,
                             (i & 4 ? 1 : -1) * b->half_extents.z);
      const glm::dvec3 p = r->frame.apply(corner);
      double best = 1e9;
      for (int k = 0; k < 8; ++k)
        best = std::min(best, glm::length(p - where(gp_Pnt(k & 1 ? 2.0 : 0.0, k & 2 ? 0.5 : 0.0,
                                                            k & 4 ? 1.0 : 0.0))));
      EXPECT_LT(best, 1e-5) << "corner " << i;
    }
  }
}

// An elbow: 90 degrees of a torus (major 1.5, tube 0.3) closed by two discs. The recognized
// segment's tube centre line starts and ends where OpenCASCADE's does.
TEST(StepPrimitives, TorusSegmentIsAnElbowWithItsSweep) {
  for (const double degrees : {90.0, 135.0, 270.0}) {
    const double angle = degrees * M_PI / 180.0;
    const auto r = recognizePrimitive(placed(BRepPrimAPI_MakeTorus(1.5, 0.3, angle).Shape()), 1e-7);
    ASSERT_TRUE(r.has_value()) << degrees;
    const TorusSegment* t = std::get_if<TorusSegment>(&r->primitive);
    ASSERT_NE(t, nullptr);
    EXPECT_NEAR(t->major_radius, 1.5f, 1e-5f);
    EXPECT_NEAR(t->minor_radius, 0.3f, 1e-5f);
    EXPECT_NEAR(t->sweep_rad, float(angle), 1e-5f) << degrees;
    // The canonical centre line: (R cos a, R sin a, 0) for a in [0, sweep].
    const glm::dvec3 start = r->frame.apply(glm::vec3(t->major_radius, 0, 0));
    const glm::dvec3 end = r->frame.apply(
        glm::vec3(t->major_radius * std::cos(t->sweep_rad), t->major_radius * std::sin(t->sweep_rad), 0));
    expectNear(start, where(gp_Pnt(1.5, 0, 0)), 1e-5);
    expectNear(end, where(gp_Pnt(1.5 * std::cos(angle), 1.5 * std::sin(angle), 0)), 1e-5);
  }
  const auto ring = recognizePrimitive(BRepPrimAPI_MakeTorus(2.0, 0.25).Shape(), 1e-7);
  ASSERT_TRUE(ring.has_value());
  EXPECT_NEAR(std::get<TorusSegment>(ring->primitive).sweep_rad, float(2.0 * M_PI), 1e-5f);
}

TEST(StepPrimitives, NearMissesStayMeshes) {
  const TopoDS_Shape cylinder = BRepPrimAPI_MakeCylinder(0.5, 3.0).Shape();
  const TopoDS_Shape hole = BRepPrimAPI_MakeCylinder(0.2, 3.0).Shape();
  EXPECT_FALSE(recognizePrimitive(BRepAlgoAPI_Cut(cylinder, hole).Shape(), 1e-7))
      << "a tube is not a capped cylinder";
  const TopoDS_Shape notch = BRepPrimAPI_MakeBox(gp_Pnt(0.3, -1, -1), gp_Pnt(1, 1, 0.5)).Shape();
  EXPECT_FALSE(recognizePrimitive(BRepAlgoAPI_Cut(cylinder, notch).Shape(), 1e-7));
  const TopoDS_Shape box = BRepPrimAPI_MakeBox(2.0, 1.0, 1.0).Shape();
  const TopoDS_Shape corner = BRepPrimAPI_MakeBox(gp_Pnt(1.5, 0.5, 0.5), gp_Pnt(3, 2, 2)).Shape();
  EXPECT_FALSE(recognizePrimitive(BRepAlgoAPI_Cut(box, corner).Shape(), 1e-7))
      << "an L-shaped block has more than six faces";
  EXPECT_FALSE(recognizePrimitive(BRepPrimAPI_MakeCylinder(0.5, 3.0, M_PI).Shape(), 1e-7))
      << "half a cylinder";
  EXPECT_FALSE(recognizePrimitive(BRepPrimAPI_MakeSphere(1.0, M_PI).Shape(), 1e-7))
      << "half a sphere";
}

// The rod of as1_pe_203 (two half-cylinder faces and two discs) comes in as one cylinder; its
// axis end points lie where the meshed rod's extremes are.
TEST(StepPrimitives, RealRodIsACylinderWhereItsMeshIs) {
  const auto file = test::sharedDataDir() / "as1_pe_203.stp";
  test::CollectingSink kept, meshed;
  readStep(file, kept);
  ReadOptions mesh_all;
  mesh_all.cad.primitives = false;
  readStep(file, meshed, mesh_all);
  ASSERT_EQ(kept.objects.size(), meshed.objects.size());
  int cylinders = 0;
  for (size_t i = 0; i < kept.objects.size(); ++i) {
    const auto* primitive = std::get_if<Primitive>(&kept.objects[i].geometry);
    if (!primitive) continue;
    const Cylinder* c = std::get_if<Cylinder>(primitive);
    ASSERT_NE(c, nullptr);
    ++cylinders;
    EXPECT_EQ(kept.objects[i].info.name, meshed.objects[i].info.name);
    // The meshed rod's points all lie within the cylinder, and its extremes reach its ends.
    const SceneObject& m = meshed.objects[i];
    const Transform& frame = kept.objects[i].info.transform;
    const glm::dmat3 inverse = glm::inverse(glm::dmat3(frame.linear));
    double z_min = 1e9, z_max = -1e9, r_max = 0.0;
    for (const glm::vec3& p : std::get<TriangleMesh>(m.geometry).positions) {
      const glm::dvec3 local = inverse * (m.info.transform.apply(p) - frame.origin);
      z_min = std::min(z_min, local.z);
      z_max = std::max(z_max, local.z);
      r_max = std::max(r_max, std::hypot(local.x, local.y));
    }
    EXPECT_NEAR(z_min, 0.0, 1e-6);
    EXPECT_NEAR(z_max, c->height, 1e-5);
    EXPECT_NEAR(r_max, c->radius, 1e-5);
  }
  EXPECT_EQ(cylinders, 1);
}

}  // namespace
}  // namespace tw
