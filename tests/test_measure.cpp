// Measuring: the closest points of segments, triangles and cylinders, and `terawalk measure` on a
// package of known geometry (two boxes, two parallel pipes, a pipe over a plate), exact to a
// millionth of the model's size. The boxes sit on dyadic coordinates, which the package's
// 2^-16 m grid stores exactly, so the distances measured on the stored geometry are the drawn
// ones.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include <nlohmann/json.hpp>

#include "closest_points.h"
#include "object_distance.h"
#include "object_queries.h"
#include "package_view.h"
#include "point_snap.h"
#include "scene.h"
#include "test_support.h"
#include "tws_writer.h"

namespace tw {
namespace {

TEST(ClosestPoints, SegmentsTrianglesAndCylinders) {
  // Skew segments: the common perpendicular between x = 0..2 at z = 0 and y = -1..1 at x = 1,
  // z = 3.
  SegmentClosest s = closestOnSegments({0, 0, 0}, {2, 0, 0}, {1, -1, 3}, {1, 1, 3});
  EXPECT_DOUBLE_EQ(s.points.distance, 3.0);
  EXPECT_DOUBLE_EQ(s.s, 0.5);
  EXPECT_DOUBLE_EQ(s.t, 0.5);
  // Past an end: the end point.
  s = closestOnSegments({0, 0, 0}, {1, 0, 0}, {3, 0, 4}, {3, 0, 5});
  EXPECT_DOUBLE_EQ(s.points.distance, std::hypot(2.0, 4.0));
  // A point over a triangle's inside, beside an edge, past a vertex.
  const Triangle3d t{glm::dvec3(0, 0, 0), glm::dvec3(4, 0, 0), glm::dvec3(0, 4, 0)};
  EXPECT_EQ(closestOnTriangle({1, 1, 5}, t), glm::dvec3(1, 1, 0));
  EXPECT_EQ(closestOnTriangle({2, -3, 0}, t), glm::dvec3(2, 0, 0));
  EXPECT_EQ(closestOnTriangle({-1, -1, 1}, t), glm::dvec3(0, 0, 0));
  // Triangles: parallel, one above the other (a vertex over a face), and crossing.
  const Triangle3d above{glm::dvec3(1, 1, 2), glm::dvec3(2, 1, 2), glm::dvec3(1, 2, 2)};
  EXPECT_DOUBLE_EQ(closestBetweenTriangles(t, above).distance, 2.0);
  const Triangle3d through{glm::dvec3(1, 1, -1), glm::dvec3(1, 1, 1), glm::dvec3(9, 9, 0)};
  EXPECT_DOUBLE_EQ(closestBetweenTriangles(t, through).distance, 0.0);
  // Edge against edge: a triangle standing beside t's hypotenuse.
  const Triangle3d beside{glm::dvec3(3, 3, -1), glm::dvec3(3, 3, 1), glm::dvec3(5, 5, 0)};
  EXPECT_NEAR(closestBetweenTriangles(t, beside).distance, std::sqrt(2.0), 1e-12);

  // Cylinders: parallel pipes side by side, crossed pipes, and the cases left to the mesh.
  const CylinderAxis a{{0, 0, 0}, {0, 0, 10}, 0.5};
  auto p = closestBetweenCylinders(a, {{3, 0, 2}, {3, 0, 20}, 1.0});
  ASSERT_TRUE(p);
  EXPECT_DOUBLE_EQ(p->distance, 1.5);
  EXPECT_DOUBLE_EQ(p->a.z, 6.0);  // the middle of the stretch they share (2 to 10)
  p = closestBetweenCylinders(a, {{-5, 4, 5}, {5, 4, 5}, 1.0});
  ASSERT_TRUE(p);
  EXPECT_DOUBLE_EQ(p->distance, 2.5);
  EXPECT_FALSE(closestBetweenCylinders(a, {{0, 0, 12}, {0, 0, 20}, 0.5})) << "end to end";
  EXPECT_FALSE(closestBetweenCylinders(a, {{-5, 4, 15}, {5, 4, 15}, 1.0})) << "past a's top";
  EXPECT_FALSE(closestBetweenCylinders(a, {{1, 0, 0}, {1, 0, 10}, 0.5})) << "overlapping";
}

// A closed box mesh from lo to hi.
SceneObject boxObject(uint32_t id, const std::string& key, glm::vec3 lo, glm::vec3 hi) {
  SceneObject o;
  o.info.id = id;
  o.info.name = key;
  o.info.db_key = key;
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i)
    mesh.positions.push_back({i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z});
  const uint32_t faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces)
    mesh.indices.insert(mesh.indices.end(), {f[0], f[1], f[2], f[0], f[2], f[3]});
  o.geometry = std::move(mesh);
  return o;
}

// A capped cylinder of radius r along +X from `start`, `length` long.
SceneObject pipeObject(uint32_t id, const std::string& key, glm::dvec3 start, float length,
                       float r) {
  SceneObject o;
  o.info.id = id;
  o.info.name = key;
  o.info.db_key = key;
  o.info.transform.origin = start;
  // Canonical +Z to +X: columns are the images of x, y, z.
  o.info.transform.linear = glm::mat3(glm::vec3(0, 0, -1), glm::vec3(0, 1, 0), glm::vec3(1, 0, 0));
  o.geometry = Primitive{Cylinder{r, length, true}};
  return o;
}

nlohmann::json measure(const std::filesystem::path& package, const std::string& args) {
  const auto r = test::runTerawalk("measure " + package.string() + " " + args + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return r.exit_code == 0 ? nlohmann::json::parse(r.output) : nlohmann::json::object();
}

TEST(Measure, DistancesBetweenBoxesPipesAndAPlateAreExact) {
  const auto dir = test::scratchDir();
  const auto scene = dir / "measure.tws", package = dir / "measure.twk";
  {
    TwsWriter writer(scene);
    writer.onLayer(0, {"equipment", 0xff808080u});
    writer.onObject(boxObject(0, "box-a", {0, 0, 0}, {1, 1, 1}));
    writer.onObject(boxObject(1, "box-b", {1.25f, 0.5f, 0}, {2.25f, 1.5f, 1}));  // 0.25 m in x
    writer.onObject(pipeObject(2, "pipe-a", {0, 3, 0.5}, 2.0f, 0.125f));
    writer.onObject(pipeObject(3, "pipe-b", {0.5, 3.5, 0.5}, 2.0f, 0.125f));  // axes 0.5 apart
    writer.onObject(boxObject(4, "plate", {0, 4, 0}, {2, 5, 0.0625f}));
    writer.onObject(pipeObject(5, "pipe-c", {0, 4.5, 0.5}, 2.0f, 0.125f));  // 0.3125 above it
    writer.finish();
  }
  const auto pre = test::runTerawalk("-q preprocess " + scene.string() + " -o " + package.string());
  ASSERT_EQ(pre.exit_code, 0) << pre.output;
  const double size = std::sqrt(2.5 * 2.5 + 5.0 * 5.0 + 1.0);  // the model's diagonal
  const double exact = 1e-6 * size;

  const auto boxes = measure(package, "--between box-a box-b");
  EXPECT_NEAR(boxes["distance_m"].get<double>(), 0.25, exact);
  EXPECT_EQ(boxes["method"], "triangles");
  EXPECT_NEAR(boxes["delta_m"][0].get<double>(), 0.25, exact);
  EXPECT_NEAR(boxes["point_a"][0].get<double>(), 1.0, exact);  // on a's +X face
  EXPECT_GE(boxes["point_a"][1].get<double>(), 0.5 - exact);   // where the faces face each other

  const auto pipes = measure(package, "--between pipe-a pipe-b");
  EXPECT_NEAR(pipes["distance_m"].get<double>(), 0.25, exact);
  EXPECT_EQ(pipes["method"], "cylinders (closed form)");
  EXPECT_NEAR(pipes["point_a"][1].get<double>(), 3.125, exact);
  EXPECT_NEAR(pipes["point_a"][0].get<double>(), 1.25, exact);  // the middle of their overlap
  const auto axes = measure(package, "--between pipe-a pipe-b --centre-lines");
  EXPECT_NEAR(axes["distance_m"].get<double>(), 0.5, exact);

  const auto plate = measure(package, "--between pipe-c plate");
  EXPECT_NEAR(plate["distance_m"].get<double>(), 0.5 - 0.125 - 0.0625, exact);
  EXPECT_LE(plate["error_bound_m"].get<double>(), exact);
  EXPECT_NEAR(plate["point_b"][2].get<double>(), 0.0625, exact);  // on the plate's top

  const auto points = measure(package, "--points 0,0,0 3,4,12");
  EXPECT_DOUBLE_EQ(points["distance_m"].get<double>(), 13.0);
  const auto angle = measure(package, "--angle 1,0,0 0,0,0 1,1,0");
  EXPECT_NEAR(angle["angle_deg"].get<double>(), 45.0, 1e-12);

  const auto missing = test::runTerawalk("measure " + package.string() + " --between box-a nothing");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.output.find("no object has the database key or name 'nothing'"),
            std::string::npos)
      << missing.output;
  const auto no_axis = test::runTerawalk("measure " + package.string() +
                                         " --between box-a pipe-a --centre-lines");
  EXPECT_EQ(no_axis.exit_code, 1);
  EXPECT_NE(no_axis.output.find("no cylinder"), std::string::npos) << no_axis.output;
}

// Snapping: a point picked near a box's corner lands on the corner, near an edge on the edge (and
// never on the diagonal of a face's two triangles), on a face stays; near a pipe's end, on its
// axis's end centre.
TEST(Measure, PickedPointsSnapToVerticesEdgesAndAxisEnds) {
  const auto dir = test::scratchDir();
  const auto scene = dir / "snap.tws", package = dir / "snap.twk";
  {
    TwsWriter writer(scene);
    writer.onLayer(0, {"equipment", 0xff808080u});
    writer.onObject(boxObject(0, "box", {0, 0, 0}, {1, 1, 1}));
    writer.onObject(pipeObject(1, "pipe", {0, 3, 0.5}, 2.0f, 0.125f));
    writer.finish();
  }
  ASSERT_EQ(test::runTerawalk("-q preprocess " + scene.string() + " -o " + package.string()).exit_code, 0);
  const PackageView view = PackageView::open(package);
  const double tolerance = 1e-5;  // the package's position grid and the tessellation, well inside
  const MeasureShape box = measureShape(view, objectsWithKeys(view, {"box"}), 1e-4);
  const MeasureShape pipe = measureShape(view, objectsWithKeys(view, {"pipe"}), 1e-4);

  const SnappedPoint corner = snapPoint(view, box, {0.98, 0.97, 1.0}, 0.05);
  EXPECT_EQ(corner.kind, SnappedPoint::Kind::Vertex);
  EXPECT_LE(glm::length(corner.world - glm::dvec3(1, 1, 1)), tolerance);
  const SnappedPoint edge = snapPoint(view, box, {0.5, 0.02, 1.0}, 0.05);
  EXPECT_EQ(edge.kind, SnappedPoint::Kind::Edge);
  EXPECT_LE(glm::length(edge.world - glm::dvec3(0.5, 0.0, 1.0)), tolerance);
  const SnappedPoint diagonal = snapPoint(view, box, {0.51, 0.49, 1.0}, 0.05);
  EXPECT_EQ(diagonal.kind, SnappedPoint::Kind::Surface) << "a face's diagonal is no edge";
  EXPECT_EQ(diagonal.world, glm::dvec3(0.51, 0.49, 1.0));
  const SnappedPoint end = snapPoint(view, pipe, {0.0, 3.05, 0.48}, 0.1);
  EXPECT_EQ(end.kind, SnappedPoint::Kind::AxisEnd);
  EXPECT_LE(glm::length(end.world - glm::dvec3(0.0, 3.0, 0.5)), tolerance);
}

}  // namespace
}  // namespace tw
