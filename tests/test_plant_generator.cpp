// Tests for the procedural plant generator: determinism, the triangle budget, metadata
// integrity (layers, ids, database keys), geometry validity, exact elbow joints and a
// watertight NURBS hull.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <string>

#include "closed_surface.h"
#include "nurbs_conforming.h"
#include "plant_generator.h"
#include "project_database.h"
#include "scene_stats.h"
#include "tessellate.h"
#include "test_support.h"
#include "watertight_check.h"

namespace tw {
namespace {

// Folds every field of the stream into a 64-bit FNV-1a hash: equal hashes, equal streams.
class HashingSink : public SceneSink {
 public:
  void onLayer(uint32_t index, const Layer& layer) override {
    mix(index);
    mixString(layer.name);
    mix(layer.color_rgba);
  }
  void onObject(const SceneObject& o) override {
    ++objects;
    mix(o.info.id);
    mixString(o.info.name);
    mix(o.info.layer);
    mixString(o.info.db_key);
    mix(o.info.color_rgba);
    mix(o.info.transform.origin);
    mix(o.info.transform.linear);
    mix(o.geometry.index());
    if (const auto* m = std::get_if<TriangleMesh>(&o.geometry)) {
      mixVector(m->positions);
      mixVector(m->normals);
      mixVector(m->colors);
      mixVector(m->indices);
    } else if (const auto* p = std::get_if<Primitive>(&o.geometry)) {
      mix(p->index());
      std::visit([&](const auto& prim) { mixPrimitive(prim); }, *p);
    } else if (const auto* n = std::get_if<NurbsPatchSet>(&o.geometry)) {
      for (const NurbsPatch& patch : n->patches) {
        mix(patch.degree_u);
        mix(patch.degree_v);
        mix(patch.count_u);
        mix(patch.count_v);
        mixVector(patch.knots_u);
        mixVector(patch.knots_v);
        mixVector(patch.control_points);
      }
    }
  }

  uint64_t hash = 1469598103934665603ull;
  uint64_t objects = 0;

 private:
  void bytes(const void* data, size_t size) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < size; ++i) hash = (hash ^ b[i]) * 1099511628211ull;
  }
  template <typename T>
  void mix(const T& value) {
    bytes(&value, sizeof value);
  }
  void mixString(const std::string& s) {
    mix(s.size());
    bytes(s.data(), s.size());
  }
  template <typename T>
  void mixVector(const std::vector<T>& v) {
    mix(v.size());
    if (!v.empty()) bytes(v.data(), v.size() * sizeof(T));
  }
  void mixPrimitive(const Cylinder& c) { mix(c.radius), mix(c.height), mix(c.capped); }
  void mixPrimitive(const Cone& c) {
    mix(c.radius_bottom), mix(c.radius_top), mix(c.height), mix(c.capped);
  }
  void mixPrimitive(const Sphere& s) { mix(s.radius); }
  void mixPrimitive(const TorusSegment& t) {
    mix(t.major_radius), mix(t.minor_radius), mix(t.sweep_rad);
  }
  void mixPrimitive(const Box& b) { mix(b.half_extents); }
  void mixPrimitive(const Extrusion& e) { mixVector(e.profile), mix(e.height); }
  void mixPrimitive(const Revolution& r) { mixVector(r.profile), mix(r.sweep_rad); }
};

uint64_t streamHash(uint64_t target, uint64_t seed) {
  PlantOptions options;
  options.target_triangles = target;
  options.seed = seed;
  HashingSink sink;
  generatePlant(options, sink, nullptr, nullptr);
  return sink.hash;
}

TEST(PlantGenerator, SameSeedSameStreamDifferentSeedDifferentStream) {
  uint64_t a = streamHash(150'000, 7);
  EXPECT_EQ(a, streamHash(150'000, 7));
  EXPECT_NE(a, streamHash(150'000, 8));
  EXPECT_NE(a, streamHash(300'000, 7));
}

// Checks metadata rules as objects stream by, without keeping them.
class CheckingSink : public SceneSink {
 public:
  void onLayer(uint32_t index, const Layer& layer) override {
    EXPECT_EQ(index, layers.size()) << "layers must be declared in order without gaps";
    EXPECT_FALSE(layer.name.empty());
    EXPECT_TRUE(colors.insert(layer.color_rgba).second) << "layer colours must be distinct";
    layers.push_back(layer);
  }
  void onObject(const SceneObject& o) override {
    ASSERT_LT(o.info.layer, layers.size()) << "object " << o.info.name << " uses an undeclared layer";
    EXPECT_TRUE(ids.insert(o.info.id).second) << "duplicate id " << o.info.id;
    EXPECT_FALSE(o.info.db_key.empty()) << o.info.name;
    EXPECT_FALSE(o.info.name.empty());
    keys.insert(o.info.db_key);
    ++objects;
    ++kinds[o.geometry.index()];
    if (const auto* p = std::get_if<Primitive>(&o.geometry)) {
      ++primitive_types[p->index()];
      checkTransform(o);
      std::visit([&](const auto& prim) { checkPrimitive(o, prim); }, *p);
    }
    if (const auto* m = std::get_if<TriangleMesh>(&o.geometry)) {
      EXPECT_GT(m->triangleCount(), 1000u) << o.info.name;
      for (uint32_t i : m->indices) ASSERT_LT(i, m->positions.size()) << o.info.name;
    }
    if (o.info.name.rfind("pipe ", 0) == 0) {
      EXPECT_NE(o.info.name.find(o.info.db_key), std::string::npos) << o.info.name;
      EXPECT_NE(o.info.name.find(" seg "), std::string::npos) << o.info.name;
    }
  }

  std::vector<Layer> layers;
  std::set<uint32_t> colors;
  std::set<uint32_t> ids;
  std::set<std::string> keys;
  uint64_t objects = 0;
  std::map<size_t, uint64_t> kinds;
  std::map<size_t, uint64_t> primitive_types;

 private:
  static void checkTransform(const SceneObject& o) {
    float det = glm::determinant(o.info.transform.linear);
    EXPECT_NEAR(det, 1.0f, 1e-3f) << o.info.name << ": frames are rotations";
  }
  static void checkPrimitive(const SceneObject& o, const Cylinder& c) {
    EXPECT_GT(c.radius, 0.0f) << o.info.name;
    EXPECT_GT(c.height, 0.0f) << o.info.name;
  }
  static void checkPrimitive(const SceneObject& o, const Cone& c) {
    EXPECT_GT(c.radius_bottom + c.radius_top, 0.0f) << o.info.name;
    EXPECT_GT(c.height, 0.0f) << o.info.name;
  }
  static void checkPrimitive(const SceneObject& o, const Sphere& s) { EXPECT_GT(s.radius, 0.0f) << o.info.name; }
  static void checkPrimitive(const SceneObject& o, const TorusSegment& t) {
    EXPECT_GT(t.major_radius, t.minor_radius) << o.info.name;
    EXPECT_GT(t.minor_radius, 0.0f) << o.info.name;
    EXPECT_GT(t.sweep_rad, 0.0f) << o.info.name;
  }
  static void checkPrimitive(const SceneObject& o, const Box& b) {
    EXPECT_GT(b.half_extents.x, 0.0f) << o.info.name;
    EXPECT_GT(b.half_extents.y, 0.0f) << o.info.name;
    EXPECT_GT(b.half_extents.z, 0.0f) << o.info.name;
  }
  static void checkPrimitive(const SceneObject& o, const Extrusion& e) {
    double area2 = 0.0;
    for (size_t i = 0; i < e.profile.size(); ++i) {
      const glm::vec2& a = e.profile[i];
      const glm::vec2& b = e.profile[(i + 1) % e.profile.size()];
      area2 += double(a.x) * b.y - double(b.x) * a.y;
    }
    EXPECT_GT(area2, 0.0) << o.info.name << ": extrusion profiles are counter-clockwise";
    EXPECT_GT(e.height, 0.0f) << o.info.name;
  }
  static void checkPrimitive(const SceneObject& o, const Revolution& r) {
    ASSERT_GE(r.profile.size(), 3u) << o.info.name;
    for (const glm::vec2& p : r.profile) EXPECT_GE(p.x, 0.0f) << o.info.name;
    EXPECT_EQ(r.profile.front().x, 0.0f) << o.info.name << ": closed solids start on the axis";
    EXPECT_EQ(r.profile.back().x, 0.0f) << o.info.name;
  }
};

class PlantBudget : public ::testing::TestWithParam<uint64_t> {};

TEST_P(PlantBudget, LandsOnTargetAndSceneStatsAgrees) {
  PlantOptions options;
  options.target_triangles = GetParam();
  options.seed = 42;
  SceneStats stats(options.tolerance);
  CheckingSink checker;
  FanOutSink sink;
  sink.add(stats);
  sink.add(checker);
  auto db_path = test::scratchDir() / "plant.db";
  PlantSummary summary;
  {
    ProjectDatabase db = ProjectDatabase::create(db_path);
    summary = generatePlant(options, sink, &db, nullptr);
    db.commit();
  }
  // The target counts NURBS per patch (PlantOptions::target_triangles).
  double ratio = double(summary.budget_triangles) / double(options.target_triangles);
  EXPECT_GT(ratio, 0.9) << summary.budget_triangles;
  EXPECT_LT(ratio, 1.1) << summary.budget_triangles;

  // The summary counts exactly what a consumer counts from the stream.
  EXPECT_EQ(stats.totalTriangles(), summary.triangles);
  EXPECT_EQ(stats.mesh_triangles, summary.mesh_triangles);
  EXPECT_EQ(stats.objects, summary.objects);
  EXPECT_EQ(stats.parts, summary.objects);
  EXPECT_EQ(stats.objects_with_db_key, summary.objects);
  EXPECT_EQ(stats.objects_by_kind[size_t(GeometryKind::Mesh)], summary.mesh_objects);
  EXPECT_EQ(stats.objects_by_kind[size_t(GeometryKind::Parametric)], summary.primitive_objects);
  EXPECT_EQ(stats.objects_by_kind[size_t(GeometryKind::Nurbs)], summary.nurbs_objects);
  EXPECT_EQ(stats.nurbs_patches, summary.nurbs_patches);
  EXPECT_EQ(checker.layers.size(), summary.layers);
  EXPECT_GE(summary.layers, 8u);

  // Every geometry kind and every primitive type appears.
  EXPECT_GT(summary.mesh_objects, 0u);
  EXPECT_GT(summary.nurbs_objects, 0u);
  EXPECT_GT(summary.primitive_objects, 100u);
  for (size_t t = 0; t < SceneStats::kPrimitiveTypes; ++t)
    EXPECT_GT(stats.primitives_by_type[t], 0u) << SceneStats::primitiveTypeName(t);

  // One record per distinct key, and every key resolves.
  EXPECT_EQ(summary.db_records, checker.keys.size());
  ProjectDatabase db = ProjectDatabase::open(db_path);
  EXPECT_EQ(db.recordCount(), checker.keys.size());
  for (const std::string& key : checker.keys) {
    auto record = db.find(key);
    ASSERT_TRUE(record.has_value()) << "no record for " << key;
    EXPECT_FALSE(record->type.empty()) << key;
  }
}

INSTANTIATE_TEST_SUITE_P(Targets, PlantBudget, ::testing::Values(100'000u, 1'000'000u));

TEST(PlantGenerator, PipingDominatesAtDefaultScale) {
  PlantOptions options;
  SceneStats stats(options.tolerance);
  generatePlant(options, stats, nullptr, nullptr);
  uint64_t piping = 0, total = stats.totalTriangles();
  for (const auto& layer : stats.layers)
    if (layer.name.rfind("piping", 0) == 0 || layer.name == "valves") piping += layer.triangles;
  EXPECT_GT(double(piping) / double(total), 0.35);
  EXPECT_GT(double(stats.mesh_triangles) / double(total), 0.05);
}

// Keeps the pipe cylinders' end points and the elbows, to check the joints afterwards.
class ElbowSink : public SceneSink {
 public:
  void onLayer(uint32_t, const Layer& layer) override { layer_names.push_back(layer.name); }
  void onObject(const SceneObject& o) override {
    const auto* p = std::get_if<Primitive>(&o.geometry);
    if (!p || layer_names[o.info.layer].rfind("piping", 0) != 0) return;
    const Transform& t = o.info.transform;
    if (const auto* c = std::get_if<Cylinder>(p)) {
      if (o.info.name.rfind("pipe ", 0) != 0) return;
      ends.insert(key(o.info.db_key, t.apply(glm::vec3(0.0f))));
      ends.insert(key(o.info.db_key, t.apply(glm::vec3(0.0f, 0.0f, c->height))));
    } else if (const auto* e = std::get_if<TorusSegment>(p)) {
      elbows.push_back({o.info.db_key, t, *e});
    }
  }
  static std::string key(const std::string& db_key, const glm::dvec3& p) {
    // Millimetre grid; a joint within 1 mm may land in a neighbouring cell, so callers probe.
    return db_key + "@" + std::to_string(std::llround(p.x * 1000.0)) + "," +
           std::to_string(std::llround(p.y * 1000.0)) + "," + std::to_string(std::llround(p.z * 1000.0));
  }
  bool hasEnd(const std::string& db_key, const glm::dvec3& p) const {
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz)
          if (ends.count(key(db_key, p + glm::dvec3(dx, dy, dz) * 0.001))) return true;
    return false;
  }
  struct Elbow {
    std::string db_key;
    Transform transform;
    TorusSegment torus;
  };
  std::vector<std::string> layer_names;
  std::set<std::string> ends;
  std::vector<Elbow> elbows;
};

TEST(PlantGenerator, ElbowsJoinTheStraightPipesExactly) {
  PlantOptions options;
  options.target_triangles = 400'000;
  ElbowSink sink;
  generatePlant(options, sink, nullptr, nullptr);
  ASSERT_GT(sink.elbows.size(), 50u);
  for (const auto& e : sink.elbows) {
    const float r = e.torus.major_radius, a = e.torus.sweep_rad;
    // The arc starts on local +X and turns counter-clockwise about +Z.
    glm::dvec3 start = e.transform.apply(glm::vec3(r, 0.0f, 0.0f));
    glm::dvec3 end = e.transform.apply(glm::vec3(r * std::cos(a), r * std::sin(a), 0.0f));
    EXPECT_TRUE(sink.hasEnd(e.db_key, start)) << e.db_key << " elbow start is not on a pipe end";
    EXPECT_TRUE(sink.hasEnd(e.db_key, end)) << e.db_key << " elbow end is not on a pipe end";
    // And the pipe leaves along the arc's tangent: the start tangent is local +Y.
    glm::dvec3 tangent = glm::dvec3(e.transform.linear * glm::vec3(0, 1, 0));
    EXPECT_NEAR(glm::length(tangent), 1.0, 1e-4);
  }
}

// Keeps the hull patch sets.
class HullSink : public SceneSink {
 public:
  void onLayer(uint32_t, const Layer&) override {}
  void onObject(const SceneObject& o) override {
    if (const auto* n = std::get_if<NurbsPatchSet>(&o.geometry)) hulls.push_back(*n);
  }
  std::vector<NurbsPatchSet> hulls;
};

void expectWatertightHull(uint64_t target) {
  PlantOptions options;
  options.target_triangles = target;
  HullSink sink;
  generatePlant(options, sink, nullptr, nullptr);
  ASSERT_FALSE(sink.hulls.empty());
  const NurbsPatchSet& hull = sink.hulls.front();
  ASSERT_GT(hull.patches.size(), 50u);

  // Every patch border (its 4 control points) is shared, bit for bit, with another patch.
  std::map<std::vector<float>, int> borders;
  auto border_key = [](const NurbsPatch& p, int side) {
    std::vector<float> k;
    for (int i = 0; i < 4; ++i) {
      int u = side == 0 ? i : side == 1 ? 3 : side == 2 ? i : 0;
      int v = side == 0 ? 0 : side == 1 ? i : side == 2 ? 3 : i;
      const glm::vec4& c = p.control_points[v * 4 + u];
      k.insert(k.end(), {c.x + 0.0f, c.y + 0.0f, c.z + 0.0f, c.w});
    }
    // Canonical direction: shared borders may run either way.
    std::vector<float> reversed;
    for (int i = 3; i >= 0; --i) reversed.insert(reversed.end(), k.begin() + 4 * i, k.begin() + 4 * i + 4);
    return std::min(k, reversed);
  };
  for (const NurbsPatch& p : hull.patches) {
    ASSERT_EQ(p.count_u, 4u);
    ASSERT_EQ(p.control_points.size(), 16u);
    for (int side = 0; side < 4; ++side) ++borders[border_key(p, side)];
  }
  for (const auto& [border, uses] : borders) EXPECT_EQ(uses, 2) << "a hull border is not shared";

  TriangleMesh mesh;
  tessellateNurbs(hull, options.tolerance, mesh);
  MeshTopologyReport report = checkWatertight(mesh);
  EXPECT_TRUE(report.watertight()) << "boundary " << report.boundary_edges << " non-manifold "
                                   << report.non_manifold_edges << " rejected "
                                   << report.rejected_faces << " degenerate "
                                   << report.degenerate_faces;

  // As the preprocessor tessellates it (conforming across patches), it bounds a solid seen from
  // outside, so the runtime may cull its back faces.
  TriangleMesh conforming;
  tessellateNurbsConforming(hull, options.tolerance, conforming);
  const ClosedSurfaceReport closed = checkClosedSurface(conforming);
  EXPECT_TRUE(closed.enclosesSolid())
      << "skipped " << closed.skipped << " unpaired edges " << closed.unpaired_edges
      << " pieces " << closed.components << " inward " << closed.inward_components;
}

TEST(PlantGenerator, ShipHullIsWatertight) { expectWatertightHull(2'000'000); }
TEST(PlantGenerator, BargeHullOfSmallPlantsIsWatertight) { expectWatertightHull(100'000); }

class RecordingProgress : public Progress {
 public:
  void beginStage(std::string_view, uint64_t total) override { totals.push_back(total); }
  void update(uint64_t done) override {
    EXPECT_GE(done, last);
    last = done;
    ++updates;
  }
  void endStage() override { ++ends; }
  bool cancelled() const override { return cancel; }
  std::vector<uint64_t> totals;
  uint64_t last = 0, updates = 0, ends = 0;
  bool cancel = false;
};

TEST(PlantGenerator, ReportsProgressAndStopsWhenCancelled) {
  PlantOptions options;
  options.target_triangles = 3'000'000;
  test::NullSink sink;
  RecordingProgress progress;
  generatePlant(options, sink, nullptr, &progress);
  ASSERT_EQ(progress.totals.size(), 1u);
  EXPECT_EQ(progress.totals[0], options.target_triangles);
  EXPECT_GT(progress.updates, 3u);
  EXPECT_EQ(progress.ends, 1u);

  RecordingProgress cancelling;
  cancelling.cancel = true;
  EXPECT_THROW(generatePlant(options, sink, nullptr, &cancelling), std::runtime_error);
}

TEST(PlantGenerator, RejectsBadOptions) {
  test::NullSink sink;
  PlantOptions zero;
  zero.target_triangles = 0;
  EXPECT_THROW(generatePlant(zero, sink, nullptr, nullptr), std::invalid_argument);
  PlantOptions bad_tolerance;
  bad_tolerance.tolerance = 0.0f;
  EXPECT_THROW(generatePlant(bad_tolerance, sink, nullptr, nullptr), std::invalid_argument);
}

TEST(PlantGenerator, CoarserToleranceStillLandsOnTarget) {
  PlantOptions options;
  options.target_triangles = 500'000;
  options.tolerance = 0.01f;
  SceneStats stats(options.tolerance);
  PlantSummary summary = generatePlant(options, stats, nullptr, nullptr);
  EXPECT_EQ(stats.totalTriangles(), summary.triangles);
  EXPECT_NEAR(double(summary.budget_triangles) / 500'000.0, 1.0, 0.1);
}

}  // namespace
}  // namespace tw
