// Tests of out-of-core bricking (scene_bricking.h) and the resume store (brick_cache.h): the bricks
// hold exactly the input triangles with the right objects, no brick exceeds the limit, output is
// deterministic, buffers stay under the cap, damaged spill files and blobs are detected.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "brick_cache.h"
#include "file_reader.h"
#include "consistent_winding.h"
#include "repeated_triangles.h"
#include "scene_bricking.h"
#include "scene_io.h"
#include "tessellate.h"
#include "test_support.h"
#include "nurbs_conforming.h"
#include "tws_writer.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

// A quad-strip mesh of w x h quads in the XY plane, 1 m cells.
TriangleMesh gridMesh(int w, int h) {
  TriangleMesh m;
  for (int y = 0; y <= h; ++y)
    for (int x = 0; x <= w; ++x) m.positions.push_back({float(x), float(y), 0.0f});
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      uint32_t a = y * (w + 1) + x, b = a + 1, c = a + (w + 1), d = c + 1;
      m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
    }
  return m;
}

SceneObject makeObject(uint32_t id, std::string name, uint32_t layer, Geometry geometry,
                       glm::dvec3 origin, std::string db_key = {}) {
  SceneObject o;
  o.info.id = id;
  o.info.name = std::move(name);
  o.info.layer = layer;
  o.info.db_key = std::move(db_key);
  o.info.transform.origin = origin;
  o.geometry = std::move(geometry);
  return o;
}

NurbsPatchSet bumpPatch() {
  NurbsPatch p;  // bicubic Bezier, 4 x 4 control points over 10 m
  p.knots_u = p.knots_v = {0, 0, 0, 0, 1, 1, 1, 1};
  for (int v = 0; v < 4; ++v)
    for (int u = 0; u < 4; ++u)
      p.control_points.push_back(
          {u * 3.3f, v * 3.3f, (u == 1 || u == 2) && (v == 1 || v == 2) ? 2.0f : 0.0f, 1.0f});
  return {{p}};
}

// Plant-like scene far from the datum: a 40 x 20 spread of small meshes over ~2 km x 1 km, a
// dense cluster, 1,200 copies of one triangle (identical centroids), an object whose parts come
// back later, a NURBS patch set and parametrics of every type.
void writeGeneratedScene(const fs::path& path) {
  const glm::dvec3 datum(512345.25, 6712345.5, 10.0);
  TwsWriter w(path);
  w.onLayer(0, {"steel", 0xff0000ffu});
  w.onLayer(1, {"hull", 0xff00ff00u});
  uint32_t id = 100;
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 40; ++x, ++id)
      w.onObject(makeObject(id, "part-" + std::to_string(id), (x + y) % 2, gridMesh(2, 2),
                            datum + glm::dvec3(x * 50.0, y * 50.0, (x % 3) * 7.0),
                            "DB-" + std::to_string(id)));
  for (int i = 0; i < 30; ++i, ++id)  // dense cluster: 30 x 50 triangles within 10 m
    w.onObject(makeObject(id, "dense-" + std::to_string(i), 0, gridMesh(5, 5),
                          datum + glm::dvec3(1000.0 + i * 0.1, 500.0, i * 0.2)));
  TriangleMesh same;
  same.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (int i = 0; i < 1200; ++i) same.indices.insert(same.indices.end(), {0u, 1u, 2u});
  w.onObject(makeObject(7, "stack", 1, same, datum + glm::dvec3(300.0, 300.0, 0.0), "DB-stack"));
  w.onObject(makeObject(8, "split-part", 1, gridMesh(3, 1), datum + glm::dvec3(-20.0, 0.0, 0.0)));
  w.onObject(makeObject(9, "nurbs", 0, bumpPatch(), datum + glm::dvec3(600.0, 200.0, 5.0), "DB-n"));
  w.onObject(makeObject(8, "split-part", 1, gridMesh(1, 3), datum + glm::dvec3(-20.0, 10.0, 0.0)));
  SceneObject pipe = makeObject(10, "pipe", 0, Primitive{Cylinder{0.1f, 12.0f, false}},
                                datum + glm::dvec3(10.0, 20.0, 3.0), "DB-pipe");
  pipe.info.transform.linear =
      glm::mat3(glm::vec3(0, 0, 1), glm::vec3(0, 1, 0), glm::vec3(-1, 0, 0));
  w.onObject(pipe);
  w.onObject(makeObject(11, "cone", 0, Primitive{Cone{0.5f, 0.2f, 1.0f, true}}, datum));
  w.onObject(makeObject(12, "ball", 1, Primitive{Sphere{2.0f}}, datum + glm::dvec3(5, 5, 5)));
  w.onObject(makeObject(13, "elbow", 0, Primitive{TorusSegment{0.5f, 0.1f, 1.5f}}, datum));
  w.onObject(makeObject(14, "box", 1, Primitive{Box{{1.0f, 2.0f, 3.0f}}}, datum));
  w.onObject(makeObject(15, "beam", 0,
                        Primitive{Extrusion{{{0, 0}, {0.2f, 0}, {0.2f, 0.3f}, {0, 0.3f}}, 6.0f}},
                        datum + glm::dvec3(100, 0, 0)));
  w.onObject(makeObject(16, "vessel", 1,
                        Primitive{Revolution{{{0, 0}, {1, 0}, {1, 3}, {0, 3}}, 6.2831855f}},
                        datum + glm::dvec3(200, 0, 0)));
  w.finish();
}

struct Inputs {
  std::vector<fs::path> paths;
  fs::path dir;
};

Inputs makeInputs(const fs::path& dir) {
  Inputs in;
  in.dir = dir;
  writeGeneratedScene(dir / "plant.tws");
  in.paths = {dir / "plant.tws", test::dataDir() / "fixtures" / "features.obj"};
  return in;
}

using ObjectKey = std::pair<uint32_t, uint32_t>;  // (input, source id)
struct Tri {
  ObjectKey object;
  std::array<float, 9> v;
  bool operator<(const Tri& o) const { return std::tie(object, v) < std::tie(o.object, o.v); }
  bool operator==(const Tri& o) const { return object == o.object && v == o.v; }
};

// The input's triangles as the bricker must store them: world position (double) minus origin,
// rounded to float once; NURBS tessellated at the same tolerance; triangles wound against their
// piece turned (consistent_winding.h), counted in `turned`.
std::vector<Tri> referenceTriangles(const std::vector<fs::path>& inputs, const glm::dvec3& origin,
                                    float tolerance, std::vector<SceneObject>* primitives,
                                    uint64_t* turned = nullptr, uint64_t* repeated = nullptr) {
  std::vector<Tri> out;
  for (uint32_t i = 0; i < inputs.size(); ++i) {
    test::CollectingSink sink;
    readScene(inputs[i], sink);
    for (const auto& o : sink.objects) {
      TriangleMesh mesh;
      if (const auto* m = std::get_if<TriangleMesh>(&o.geometry))
        mesh = *m;
      else if (const auto* n = std::get_if<NurbsPatchSet>(&o.geometry))
        tessellateNurbsConforming(*n, tolerance, mesh);
      else if (primitives)
        primitives->push_back(o);
      const std::vector<uint32_t> repeats = repeatedTriangles(mesh);
      if (repeated) *repeated += repeats.size();
      mesh = withoutTriangles(mesh, repeats);
      const std::vector<uint32_t> turn = trianglesToTurn(mesh);
      turnTriangles(mesh, turn);
      if (turned) *turned += turn.size();
      for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        Tri tri{{i, o.info.id}, {}};
        for (int k = 0; k < 3; ++k) {
          glm::vec3 p(o.info.transform.apply(mesh.positions[mesh.indices[t + k]]) - origin);
          tri.v[3 * k] = p.x, tri.v[3 * k + 1] = p.y, tri.v[3 * k + 2] = p.z;
        }
        out.push_back(tri);
      }
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<BrickedObject> allObjects(const BrickedScene& scene) {
  std::vector<BrickedObject> objects;
  forEachObject(scene, [&](const BrickedObject& o) { objects.push_back(o); });
  return objects;
}

std::vector<Tri> brickTriangles(const BrickedScene& scene) {
  auto objects = allObjects(scene);
  std::vector<Tri> out;
  for (uint32_t b = 0; b < scene.bricks.size(); ++b) {
    BrickMesh mesh = loadBrick(scene, b);
    EXPECT_EQ(mesh.triangleCount(), scene.bricks[b].triangle_count);
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
      const BrickedObject& o = objects.at(mesh.triangle_object_ids[t]);
      Tri tri{{o.input, o.source_id}, {}};
      for (int k = 0; k < 3; ++k) {
        const glm::vec3& p = mesh.positions.at(mesh.indices[3 * t + k]);
        tri.v[3 * k] = p.x, tri.v[3 * k + 1] = p.y, tri.v[3 * k + 2] = p.z;
      }
      out.push_back(tri);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

BrickingOptions smallOptions(const fs::path& work_dir, uint64_t limit = 500) {
  BrickingOptions o;
  o.work_dir = work_dir;
  o.max_brick_triangles = limit;
  return o;
}

TEST(SceneBricking, BricksHoldExactlyTheInputTriangles) {
  auto dir = test::scratchDir();
  Inputs in = makeInputs(dir);
  SceneSurvey survey = surveyScene(in.paths);
  EXPECT_EQ(survey.primitives, 7u);
  EXPECT_EQ(survey.objects, 800u + 30 + 10 + 4);  // features.obj has 4 objects
  BrickingOptions options = smallOptions(dir / "work");
  BrickedScene scene = brickScene(in.paths, survey, options);

  EXPECT_GT(scene.triangle_count, survey.mesh_triangles);
  EXPECT_GT(scene.stats.cells_split, 0u);  // the dense cluster and the stack needed splitting
  uint64_t sum = 0;
  for (const auto& b : scene.bricks) {
    EXPECT_LE(b.triangle_count, 500u) << b.file;
    EXPECT_GT(b.triangle_count, 0u);
    sum += b.triangle_count;
  }
  EXPECT_EQ(sum, scene.triangle_count);
  // The origin is the rounded centre, so positions stay small.
  EXPECT_EQ(scene.origin, glm::round(survey.bounds.center()));

  std::vector<SceneObject> primitives;
  uint64_t turned = 0, repeated = 0;
  auto expected = referenceTriangles(in.paths, scene.origin, options.nurbs_tolerance, &primitives,
                                     &turned, &repeated);
  auto actual = brickTriangles(scene);
  ASSERT_EQ(actual.size(), expected.size());
  EXPECT_TRUE(actual == expected);
  EXPECT_EQ(scene.triangles_turned, turned);
  EXPECT_EQ(scene.triangles_repeated, repeated);

  // Brick bounds enclose their triangles.
  for (uint32_t b = 0; b < scene.bricks.size(); ++b) {
    BrickMesh mesh = loadBrick(scene, b);
    for (const auto& p : mesh.positions) {
      EXPECT_TRUE(glm::all(glm::greaterThanEqual(p, scene.bricks[b].bounds_min)));
      EXPECT_TRUE(glm::all(glm::lessThanEqual(p, scene.bricks[b].bounds_max)));
    }
  }
}

TEST(SceneBricking, WeldsSharedVerticesWithinABrick) {
  auto dir = test::scratchDir();
  Inputs in = makeInputs(dir);
  BrickedScene scene =
      brickScene(in.paths, surveyScene(in.paths), smallOptions(dir / "work", 100000));
  ASSERT_EQ(scene.bricks.size(), 1u);  // everything in one brick
  BrickMesh mesh = loadBrick(scene, 0);
  EXPECT_LT(mesh.positions.size(), mesh.indices.size() / 2);  // grids share most vertices
  std::set<std::array<float, 3>> distinct;
  for (const auto& p : mesh.positions) distinct.insert({p.x + 0.0f, p.y + 0.0f, p.z + 0.0f});
  EXPECT_EQ(distinct.size(), mesh.positions.size());
  for (uint32_t i : mesh.indices) ASSERT_LT(i, mesh.positions.size());
}

TEST(SceneBricking, MergesLayersByNameAndRenumbersObjectsDensely) {
  auto dir = test::scratchDir();
  Inputs in = makeInputs(dir);
  BrickedScene scene = brickScene(in.paths, surveyScene(in.paths), smallOptions(dir / "work"));
  // plant.tws: steel, hull; features.obj: default, steel, paint -> steel is shared.
  ASSERT_EQ(scene.layers.size(), 4u);
  EXPECT_EQ(scene.layers[0].name, "steel");
  EXPECT_EQ(scene.layers[0].color_rgba, 0xff0000ffu);  // the first input's colour wins
  EXPECT_EQ(scene.layers[1].name, "hull");
  EXPECT_EQ(scene.layers[2].name, "default");
  EXPECT_EQ(scene.layers[3].name, "paint");

  auto objects = allObjects(scene);
  ASSERT_EQ(objects.size(), scene.object_count);
  EXPECT_EQ(objects.size(), 844u);
  std::map<ObjectKey, SceneObject> reference;
  std::vector<std::vector<Layer>> reference_layers;
  for (uint32_t i = 0; i < in.paths.size(); ++i) {
    test::CollectingSink sink;
    readScene(in.paths[i], sink);
    for (const auto& o : sink.objects) reference.emplace(ObjectKey{i, o.info.id}, o);
    reference_layers.push_back(sink.layers);
  }
  std::set<ObjectKey> seen;
  for (uint32_t i = 0; i < objects.size(); ++i) {
    const BrickedObject& o = objects[i];
    EXPECT_EQ(o.index, i);
    EXPECT_TRUE(seen.insert({o.input, o.source_id}).second) << "object listed twice";
    const SceneObject& ref = reference.at({o.input, o.source_id});
    EXPECT_EQ(o.name, ref.info.name);
    EXPECT_EQ(o.db_key, ref.info.db_key);
    EXPECT_EQ(scene.layers.at(o.layer).name, reference_layers[o.input].at(ref.info.layer).name);
  }
  // First appearance order: the plant's first object, the re-appearing id 8 once, OBJ last.
  EXPECT_EQ(objects[0].source_id, 100u);
  EXPECT_EQ(objects[0].db_key, "DB-100");
  EXPECT_EQ(objects[830].name, "stack");
  EXPECT_EQ(objects[831].name, "split-part");
  EXPECT_EQ(objects[832].name, "nurbs");
  EXPECT_EQ(objects.back().input, 1u);
  // Object bounds (relative to the origin) hold the split part's two pieces.
  glm::dvec3 world_min = glm::dvec3(objects[831].bounds_min) + scene.origin;
  glm::dvec3 world_max = glm::dvec3(objects[831].bounds_max) + scene.origin;
  EXPECT_NEAR(world_min.x, 512345.25 - 20.0, 1e-3);
  EXPECT_NEAR(world_max.y, 6712345.5 + 13.0, 1e-3);
}

TEST(SceneBricking, ParametricsComeBackUntessellated) {
  auto dir = test::scratchDir();
  Inputs in = makeInputs(dir);
  BrickedScene scene = brickScene(in.paths, surveyScene(in.paths), smallOptions(dir / "work"));
  ASSERT_EQ(scene.parametric_count, 7u);
  auto objects = allObjects(scene);
  std::vector<ParametricRecord> records;
  int batches = 0;
  forEachParametricBatch(scene, 3, [&](std::span<const ParametricRecord> batch) {
    EXPECT_LE(batch.size(), 3u);
    ++batches;
    records.insert(records.end(), batch.begin(), batch.end());
  });
  EXPECT_EQ(batches, 3);
  std::vector<SceneObject> primitives;
  referenceTriangles(in.paths, scene.origin, kDefaultChordalTolerance, &primitives);
  ASSERT_EQ(records.size(), primitives.size());
  for (size_t i = 0; i < records.size(); ++i) {
    const SceneObject& ref = primitives[i];
    EXPECT_EQ(objects.at(records[i].object).source_id, ref.info.id);
    EXPECT_EQ(records[i].transform.origin, ref.info.transform.origin);
    EXPECT_EQ(records[i].transform.linear, ref.info.transform.linear);
    const Primitive& want = std::get<Primitive>(ref.geometry);
    ASSERT_EQ(records[i].primitive.index(), want.index());
    // Equal tessellation means equal parameters, profiles included.
    TriangleMesh a, b;
    tessellatePrimitive(records[i].primitive, 0.01f, a);
    tessellatePrimitive(want, 0.01f, b);
    EXPECT_EQ(a.positions, b.positions) << "primitive " << i;
  }
  const auto& pipe = std::get<Cylinder>(records[0].primitive);
  EXPECT_EQ(pipe.radius, 0.1f);
  EXPECT_FALSE(pipe.capped);
  EXPECT_EQ(std::get<Revolution>(records[6].primitive).profile.size(), 4u);
}

std::vector<std::string> spillFiles(const BrickedScene& scene) {
  std::vector<std::string> files;
  for (const auto& b : scene.bricks) files.push_back(test::readFile(scene.work_dir / b.file));
  for (const auto* f : {&scene.objects_file, &scene.object_bounds_file, &scene.parametrics_file})
    files.push_back(test::readFile(scene.work_dir / *f));
  return files;
}

TEST(SceneBricking, IsDeterministic) {
  auto dir = test::scratchDir();
  Inputs in = makeInputs(dir);
  SceneSurvey survey = surveyScene(in.paths);
  BrickedScene a = brickScene(in.paths, survey, smallOptions(dir / "a"));
  BrickingOptions small_buffers = smallOptions(dir / "b");
  small_buffers.memory_budget_bytes = 1 << 16;  // different flush timing, same bytes
  BrickedScene b = brickScene(in.paths, survey, small_buffers);
  ASSERT_EQ(a.bricks.size(), b.bricks.size());
  for (size_t i = 0; i < a.bricks.size(); ++i) {
    EXPECT_EQ(a.bricks[i].file, b.bricks[i].file);
    EXPECT_EQ(a.bricks[i].triangle_count, b.bricks[i].triangle_count);
  }
  EXPECT_TRUE(spillFiles(a) == spillFiles(b));
  // Bricking again into the same work dir replaces the earlier files.
  BrickedScene c = brickScene(in.paths, survey, smallOptions(dir / "a"));
  EXPECT_TRUE(spillFiles(a) == spillFiles(c));
  size_t brick_files = 0;
  for (const auto& e : fs::directory_iterator(dir / "a"))
    brick_files += e.path().extension() == ".bin";
  EXPECT_EQ(brick_files, c.bricks.size() + 3);  // no stale cell files left behind
}

TEST(SceneBricking, BufferedBytesStayUnderTheCap) {
  auto dir = test::scratchDir();
  Inputs in = makeInputs(dir);
  BrickingOptions options = smallOptions(dir / "work", 2000);
  options.memory_budget_bytes = 256 * 1024;
  BrickedScene scene = brickScene(in.paths, surveyScene(in.paths), options);
  EXPECT_EQ(scene.stats.buffer_cap_bytes, 64u * 1024);  // budget / 8, at least 64 KiB
  EXPECT_LE(scene.stats.buffer_cap_bytes, options.memory_budget_bytes / 4);
  EXPECT_GT(scene.stats.peak_buffered_bytes, 0u);
  EXPECT_LE(scene.stats.peak_buffered_bytes, scene.stats.buffer_cap_bytes);
  EXPECT_GT(scene.stats.flushes, 10u);  // ~9K triangles * 40 bytes went through 64 KiB
  EXPECT_EQ(brickTriangles(scene).size(), scene.triangle_count);
}

TEST(SceneBricking, DerivesTheBrickLimitFromTheBudget) {
  BrickingOptions o;
  EXPECT_EQ(effectiveMaxBrickTriangles(o), 4u * 1024 * 1024);  // 2 GiB default: at the cap
  o.memory_budget_bytes = 1ull << 30;
  EXPECT_EQ(effectiveMaxBrickTriangles(o), (1ull << 30) / 400);
  o.memory_budget_bytes = 1 << 20;
  EXPECT_EQ(effectiveMaxBrickTriangles(o), 64u * 1024);
  o.memory_budget_bytes = 64ull << 30;
  EXPECT_EQ(effectiveMaxBrickTriangles(o), 4u * 1024 * 1024);
  o.max_brick_triangles = 123;
  EXPECT_EQ(effectiveMaxBrickTriangles(o), 123u);
}

class CancelAfter : public Progress {
 public:
  explicit CancelAfter(int polls) : polls_(polls) {}
  void beginStage(std::string_view, uint64_t) override {}
  void update(uint64_t) override {}
  void endStage() override {}
  bool cancelled() const override { return --polls_ < 0; }

 private:
  mutable int polls_;
};

TEST(SceneBricking, StopsWhenCancelled) {
  auto dir = test::scratchDir();
  Inputs in = makeInputs(dir);
  SceneSurvey survey = surveyScene(in.paths);
  CancelAfter cancel(100);
  BrickingOptions options = smallOptions(dir / "work");
  options.progress = &cancel;
  try {
    brickScene(in.paths, survey, options);
    ADD_FAILURE() << "not cancelled";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "cancelled");
  }
  CancelAfter at_once(0);
  EXPECT_THROW(surveyScene(in.paths, kDefaultChordalTolerance, &at_once), std::runtime_error);
}

TEST(SceneBricking, NoInputsGiveAnEmptyScene) {
  auto dir = test::scratchDir();
  BrickedScene scene = brickScene({}, surveyScene({}), smallOptions(dir / "work"));
  EXPECT_TRUE(scene.bricks.empty());
  EXPECT_EQ(scene.object_count, 0u);
  EXPECT_TRUE(verifyBrickedScene(scene, true));
  EXPECT_TRUE(allObjects(scene).empty());
  EXPECT_THROW(brickScene({dir / "missing.obj"}, surveyScene({}), smallOptions(dir / "work")),
               FormatError);
}

TEST(SceneBricking, DetectsTruncatedAndDamagedBrickFiles) {
  auto dir = test::scratchDir();
  Inputs in = makeInputs(dir);
  BrickedScene scene = brickScene(in.paths, surveyScene(in.paths), smallOptions(dir / "work"));
  ASSERT_TRUE(verifyBrickedScene(scene, true));
  const fs::path brick = scene.work_dir / scene.bricks[0].file;
  const std::string original = test::readFile(brick);

  // Truncated (a run killed mid-write): the trailer is missing.
  fs::resize_file(brick, original.size() - 7);
  EXPECT_FALSE(verifyBrickedScene(scene, false));
  try {
    loadBrick(scene, 0);
    ADD_FAILURE() << "truncated brick loaded";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find(scene.bricks[0].file), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("trailer"), std::string::npos) << e.what();
  }
  // Same size, one byte changed: only the checksum can tell.
  std::string damaged = original;
  damaged[100] = static_cast<char>(damaged[100] ^ 0x40);
  test::writeFile(brick, damaged);
  EXPECT_TRUE(verifyBrickedScene(scene, false));
  EXPECT_FALSE(verifyBrickedScene(scene, true));
  try {
    loadBrick(scene, 0);
    ADD_FAILURE() << "damaged brick loaded";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("checksum"), std::string::npos) << e.what();
  }
  EXPECT_THROW(loadBrick(scene, 9999), std::out_of_range);

  // Every truncation and random damage is rejected with a FormatError naming the file.
  BrickedScene copy = scene;
  int attempts = 0;
  int rejected =
      test::expectRobustToDamage(original, "brick.bin", [&](const fs::path& p, SceneSink&) {
        ++attempts;
        copy.work_dir = p.parent_path();
        copy.bricks[0].file = p.filename().string();
        loadBrick(copy, 0);
      });
  EXPECT_GE(rejected, attempts - 2);  // a corruption may rewrite a byte with its own value
}

TEST(SceneBricking, SideFilesAreRobustToDamage) {
  auto dir = test::scratchDir();
  Inputs in = makeInputs(dir);
  BrickedScene scene = brickScene(in.paths, surveyScene(in.paths), smallOptions(dir / "work"));
  const std::string objects = test::readFile(scene.work_dir / scene.objects_file);
  const std::string params = test::readFile(scene.work_dir / scene.parametrics_file);
  // The damage harness empties this test's scratch dir: keep the bytes, not the files.
  const std::string bounds = test::readFile(scene.work_dir / scene.object_bounds_file);
  BrickedScene copy = scene;
  auto read_objects = [&](const fs::path& p, SceneSink&) {
    copy.work_dir = p.parent_path();
    copy.objects_file = p.filename().string();
    copy.object_bounds_file = "bounds.bin";
    if (!fs::exists(p.parent_path() / "bounds.bin"))
      test::writeFile(p.parent_path() / "bounds.bin", bounds);
    forEachObject(copy, [](const BrickedObject&) {});
  };
  EXPECT_GT(test::expectRobustToDamage(objects, "objects.bin", read_objects, 100), 150);
  copy = scene;
  auto read_params = [&](const fs::path& p, SceneSink&) {
    copy.work_dir = p.parent_path();
    copy.parametrics_file = p.filename().string();
    forEachParametricBatch(copy, 4, [](std::span<const ParametricRecord>) {});
  };
  EXPECT_GT(test::expectRobustToDamage(params, "parametrics.bin", read_params, 100), 100);
}

TEST(SceneBricking, DescriptionRoundTripsAndRejectsDamage) {
  auto dir = test::scratchDir();
  Inputs in = makeInputs(dir);
  BrickedScene scene = brickScene(in.paths, surveyScene(in.paths), smallOptions(dir / "work"));
  auto bytes = serializeBrickedScene(scene);
  BrickedScene back = deserializeBrickedScene(bytes, scene.work_dir);
  EXPECT_EQ(back.origin, scene.origin);
  ASSERT_EQ(back.bricks.size(), scene.bricks.size());
  for (size_t i = 0; i < back.bricks.size(); ++i) {
    EXPECT_EQ(back.bricks[i].file, scene.bricks[i].file);
    EXPECT_EQ(back.bricks[i].triangle_count, scene.bricks[i].triangle_count);
    EXPECT_EQ(back.bricks[i].bounds_max, scene.bricks[i].bounds_max);
  }
  EXPECT_EQ(back.layers.size(), scene.layers.size());
  EXPECT_EQ(back.object_count, scene.object_count);
  EXPECT_EQ(back.parametric_count, scene.parametric_count);
  EXPECT_EQ(back.stats.peak_buffered_bytes, scene.stats.peak_buffered_bytes);
  EXPECT_EQ(serializeBrickedScene(back), bytes);

  std::vector<uint8_t> bad = bytes;
  bad[0] = 'X';
  try {
    deserializeBrickedScene(bad, dir, "desc");
    ADD_FAILURE();
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("bad magic"), std::string::npos) << e.what();
  }
  std::string as_text(bytes.begin(), bytes.end());
  test::expectRobustToDamage(as_text, "scene.desc", [&](const fs::path& p, SceneSink&) {
    std::string b = test::readFile(p);
    deserializeBrickedScene(std::span(reinterpret_cast<const uint8_t*>(b.data()), b.size()), dir,
                            p.string());
  });
}

TEST(BrickCache, RoundTripAndInvalidation) {
  auto dir = test::scratchDir();
  BrickCache cache(dir, 42);
  EXPECT_FALSE(cache.has(3));
  EXPECT_FALSE(cache.load(3).has_value());
  std::vector<uint8_t> blob(10000);
  for (size_t i = 0; i < blob.size(); ++i) blob[i] = uint8_t(i * 7);
  cache.store(3, blob);
  cache.store(4, {});
  EXPECT_TRUE(cache.has(3));
  EXPECT_EQ(cache.load(3), blob);
  EXPECT_EQ(cache.load(4), std::vector<uint8_t>{});
  // No temporary left behind.
  for (const auto& e : fs::directory_iterator(dir / "brick-cache"))
    EXPECT_EQ(e.path().extension(), ".blob") << e.path();

  // Another run (different inputs or options) sees nothing.
  BrickCache other(dir, 43);
  EXPECT_FALSE(other.has(3));
  // Overwriting replaces.
  blob[5] = 99;
  cache.store(3, blob);
  EXPECT_EQ(cache.load(3), blob);

  const fs::path path = cache.blobPath(3);
  const std::string good = test::readFile(path);
  fs::resize_file(path, good.size() - 1);
  EXPECT_FALSE(cache.has(3));
  fs::resize_file(path, 20);
  EXPECT_FALSE(cache.load(3).has_value());
  std::string corrupt = good;
  corrupt[good.size() / 2] = static_cast<char>(corrupt[good.size() / 2] ^ 1);
  test::writeFile(path, corrupt);
  EXPECT_FALSE(cache.has(3));
  // A blob copied under another key is not taken for it.
  test::writeFile(cache.blobPath(5), good);
  EXPECT_FALSE(cache.has(5));
  test::writeFile(path, good);
  EXPECT_TRUE(cache.has(3));

  cache.clear();
  EXPECT_FALSE(cache.has(3));
  EXPECT_FALSE(cache.has(4));
}

TEST(BrickCache, RunHashCoversInputsAndOptions) {
  auto dir = test::scratchDir();
  test::writeFile(dir / "a.obj", "v 0 0 0\n");
  auto hash = [&](float tolerance, uint64_t limit) {
    RunHash h;
    h.addFile(dir / "a.obj");
    BrickingOptions o;
    o.nurbs_tolerance = tolerance;
    o.max_brick_triangles = limit;
    h.addBrickingOptions(o);
    return h.digest();
  };
  const uint64_t base = hash(0.002f, 0);
  EXPECT_EQ(hash(0.002f, 0), base);
  EXPECT_NE(hash(0.001f, 0), base);
  EXPECT_NE(hash(0.002f, 1000), base);
  test::writeFile(dir / "a.obj", "v 0 0 0\nv 1 0 0\n");  // new size (and mtime)
  EXPECT_NE(hash(0.002f, 0), base);
  RunHash ab, a_b;
  ab.addString("ab"), ab.addString("c");
  a_b.addString("a"), a_b.addString("bc");
  EXPECT_NE(ab.digest(), a_b.digest());
}

TEST(BrickCache, BrickedSceneMarkerForResume) {
  auto dir = test::scratchDir();
  Inputs in = makeInputs(dir);
  const fs::path work = workDirFor(dir / "model.twk");
  EXPECT_EQ(work, dir / "model.twk.work");
  BrickedScene scene = brickScene(in.paths, surveyScene(in.paths), smallOptions(work));
  BrickCache cache(work, 7);
  EXPECT_FALSE(loadBrickedScene(cache, work).has_value());
  storeBrickedScene(cache, scene);
  auto back = loadBrickedScene(cache, work);
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(serializeBrickedScene(*back), serializeBrickedScene(scene));
  EXPECT_EQ(loadBrick(*back, 1).indices, loadBrick(scene, 1).indices);
  // A spill file cut short makes the marker worthless: bricking must be redone.
  const fs::path brick = work / scene.bricks.back().file;
  fs::resize_file(brick, fs::file_size(brick) - 1);
  EXPECT_FALSE(loadBrickedScene(cache, work).has_value());
  fs::remove(work / scene.objects_file);
  EXPECT_FALSE(loadBrickedScene(cache, work).has_value());
  EXPECT_TRUE(removeWorkDir(work));
  EXPECT_FALSE(fs::exists(work));
  EXPECT_TRUE(removeWorkDir(work));  // already gone is fine
}

TEST(SceneBricking, KicadModelKeepsEveryTriangleAndObject) {
  const fs::path kicad = test::sharedDataDir() / "kicad_dsub62.obj";
  if (!fs::exists(kicad)) GTEST_SKIP() << "no " << kicad;
  auto dir = test::scratchDir();
  SceneSurvey survey = surveyScene({kicad});
  EXPECT_EQ(survey.mesh_triangles, 94176u);
  EXPECT_EQ(survey.objects, 648u);
  BrickedScene scene = brickScene({kicad}, survey, smallOptions(dir / "work", 4000));
  EXPECT_EQ(scene.triangle_count, 94176u);
  EXPECT_EQ(scene.object_count, 648u);
  EXPECT_GE(scene.bricks.size(), 24u);
  uint64_t loaded = 0;
  std::vector<uint64_t> per_object(scene.object_count);
  for (uint32_t b = 0; b < scene.bricks.size(); ++b) {
    BrickMesh mesh = loadBrick(scene, b);
    EXPECT_LE(mesh.triangleCount(), 4000u);
    loaded += mesh.triangleCount();
    for (uint32_t id : mesh.triangle_object_ids) ++per_object.at(id);
  }
  EXPECT_EQ(loaded, 94176u);
  std::set<std::string> names;
  forEachObject(scene, [&](const BrickedObject& o) {
    EXPECT_GT(per_object[o.index], 0u) << o.name;
    names.insert(o.name + "#" + std::to_string(o.source_id));
  });
  EXPECT_EQ(names.size(), 648u);
}

}  // namespace
}  // namespace tw
