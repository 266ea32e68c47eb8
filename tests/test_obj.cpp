// OBJ reader and writer: statement forms, object/layer rules, part splitting, real models,
// errors with line numbers, damaged input, and writer -> reader round trips.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>

#include "obj_reader.h"
#include "obj_writer.h"
#include "tessellate.h"
#include "test_support.h"

namespace tw {
namespace {

using test::CollectingSink;

const TriangleMesh& meshOf(const SceneObject& o) { return std::get<TriangleMesh>(o.geometry); }

CollectingSink readAll(const std::filesystem::path& path, const ReadOptions& options = {}) {
  CollectingSink sink;
  readObj(path, sink, options);
  return sink;
}

// The error for an OBJ whose text is `text`: file name, line and reason are checked by callers.
FormatError errorFor(const std::string& text, const std::string& file_name = "bad.obj") {
  auto path = test::scratchDir() / file_name;
  test::writeFile(path, text);
  try {
    test::NullSink sink;
    readObj(path, sink);
  } catch (const FormatError& e) {
    return e;
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return FormatError(file_name, "none");
}

void expectLineError(const std::string& text, uint64_t line, const std::string& reason_part) {
  FormatError e = errorFor(text);
  EXPECT_EQ(e.where(), FormatError::Where::Line) << e.what();
  EXPECT_EQ(e.position(), line) << e.what();
  EXPECT_NE(std::string(e.what()).find("bad.obj:" + std::to_string(line) + ":"), std::string::npos)
      << e.what();
  EXPECT_NE(e.reason().find(reason_part), std::string::npos) << e.what();
}

TEST(ObjReader, FixtureObjectsLayersAndFaceForms) {
  CollectingSink s = readAll(test::dataDir() / "fixtures" / "features.obj");

  ASSERT_EQ(s.layers.size(), 3u);
  EXPECT_EQ(s.layers[0].name, "default");
  EXPECT_EQ(s.layers[1].name, "steel");
  EXPECT_EQ(s.layers[1].color_rgba, 0xff808080u);  // Kd 0.5 0.5 0.5 from features.mtl
  EXPECT_EQ(s.layers[2].name, "paint");
  EXPECT_EQ(s.layers[2].color_rgba, 0x800080ffu);  // Kd 1 0.5 0, d 0.5

  ASSERT_EQ(s.objects.size(), 4u);
  const SceneObject& plate = s.objects[0];
  EXPECT_EQ(plate.info.id, 0u);
  EXPECT_EQ(plate.info.name, "Plate");
  EXPECT_EQ(plate.info.layer, 1u);
  const TriangleMesh& pm = meshOf(plate);
  EXPECT_EQ(pm.triangleCount(), 2u);  // quad as a fan
  EXPECT_EQ(pm.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
  ASSERT_EQ(pm.positions.size(), 4u);
  EXPECT_EQ(pm.positions[2], glm::vec3(1, 1, 0));
  ASSERT_EQ(pm.normals.size(), 4u);  // every corner had a normal
  EXPECT_EQ(pm.normals[3], glm::vec3(0, 0, 1));
  EXPECT_TRUE(pm.colors.empty());

  const SceneObject& bracket = s.objects[1];
  EXPECT_EQ(bracket.info.id, 1u);
  EXPECT_EQ(bracket.info.name, "Bracket Left");  // g with two names, joined
  EXPECT_EQ(bracket.info.layer, 1u);
  const TriangleMesh& bm = meshOf(bracket);
  EXPECT_EQ(bm.triangleCount(), 2u);
  ASSERT_EQ(bm.positions.size(), 3u);  // negative indices and 5/6/7 hit the same three vertices
  EXPECT_EQ(bm.positions[0], glm::vec3(0, 0, 1));
  EXPECT_TRUE(bm.normals.empty());  // the v/vt face has no normals
  EXPECT_EQ(bm.colors, (std::vector<uint32_t>{0xff0000ffu, 0xff00ff00u, 0xffff0000u}));

  const SceneObject& painted = s.objects[2];  // usemtl after faces: same name, new id
  EXPECT_EQ(painted.info.id, 2u);
  EXPECT_EQ(painted.info.name, "Bracket Left");
  EXPECT_EQ(painted.info.layer, 2u);
  const TriangleMesh& cm = meshOf(painted);
  EXPECT_EQ(cm.triangleCount(), 1u);
  EXPECT_EQ(cm.colors, (std::vector<uint32_t>{0xffffffffu, 0xffffffffu, 0xff0000ffu}));

  const SceneObject& pipe = s.objects[3];  // "o Empty" had no faces: renamed, not emitted
  EXPECT_EQ(pipe.info.id, 3u);
  EXPECT_EQ(pipe.info.name, "Pipe");
  EXPECT_EQ(pipe.info.layer, 1u);
  const TriangleMesh& fm = meshOf(pipe);
  EXPECT_EQ(fm.triangleCount(), 3u);  // pentagon fan
  EXPECT_EQ(fm.positions.size(), 5u);
  EXPECT_EQ(fm.positions[4], glm::vec3(2.5f, 1.5f, 0));
  EXPECT_EQ(fm.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 0, 3, 4}));
  EXPECT_EQ(s.triangles(), 8u);
}

TEST(ObjReader, FacesBeforeAnyObjectUseFileStemAndDefaultLayer) {
  auto path = test::scratchDir() / "loose.obj";
  // Windows line ends and a UTF-8 byte order mark before the first vertex.
  test::writeFile(path, "\xEF\xBB\xBFv 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n");
  CollectingSink s = readAll(path);
  ASSERT_EQ(s.objects.size(), 1u);
  EXPECT_EQ(s.objects[0].info.name, "loose");
  EXPECT_EQ(s.objects[0].info.layer, 0u);
  ASSERT_EQ(s.layers.size(), 1u);
  EXPECT_EQ(s.layers[0].name, "default");
}

TEST(ObjReader, MissingMaterialLibraryIsNotAnError) {
  auto path = test::scratchDir() / "nomtl.obj";
  test::writeFile(path, "mtllib nothere.mtl\nusemtl red\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  CollectingSink s = readAll(path);
  ASSERT_EQ(s.layers.size(), 2u);
  EXPECT_EQ(s.layers[1].name, "red");
  EXPECT_EQ(s.layers[1].color_rgba, Layer{}.color_rgba);
  EXPECT_EQ(s.objects.at(0).info.layer, 1u);
}

TEST(ObjReader, BadMaterialLibraryNamesBothFiles) {
  auto dir = test::scratchDir();
  test::writeFile(dir / "m.mtl", "newmtl red\nKd 1 zero 0\n");
  test::writeFile(dir / "m.obj", "# x\nmtllib m.mtl\n");
  test::NullSink sink;
  try {
    readObj(dir / "m.obj", sink);
    ADD_FAILURE() << "no error";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.position(), 2u);
    EXPECT_NE(std::string(e.what()).find("m.obj:2:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("m.mtl:2: bad Kd"), std::string::npos) << e.what();
  }
}

// Cancels at the first poll; the reader must stop early without throwing.
class CancellingProgress : public Progress {
 public:
  void beginStage(std::string_view, uint64_t total) override { total_ = total; }
  void update(uint64_t done) override {
    EXPECT_LE(done, total_);
    ++updates;
  }
  void endStage() override {}
  bool cancelled() const override { return updates > 0; }
  int updates = 0;

 private:
  uint64_t total_ = 0;
};

TEST(ObjReader, ProgressReportsAndCancels) {
  CancellingProgress progress;
  ReadOptions options;
  options.progress = &progress;
  CollectingSink s = readAll(test::sharedDataDir() / "kicad_dsub62.obj", options);
  EXPECT_EQ(progress.updates, 1);
  EXPECT_LT(s.objects.size(), 648u);
}

TEST(ObjReader, HardEdgeNormalsSplitVertices) {
  // Vertices 1 and 3 are used with two different normals: each becomes two part-local vertices.
  auto path = test::scratchDir() / "hard.obj";
  test::writeFile(path,
                  "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nvn 1 0 0\n"
                  "f 1//1 2//1 3//1\nf 1//2 3//2 4//2\n");
  CollectingSink s = readAll(path);
  const TriangleMesh& m = meshOf(s.objects.at(0));
  ASSERT_EQ(m.positions.size(), 6u);
  ASSERT_EQ(m.normals.size(), 6u);
  EXPECT_EQ(m.normals[m.indices[0]], glm::vec3(0, 0, 1));
  EXPECT_EQ(m.normals[m.indices[3]], glm::vec3(1, 0, 0));
  EXPECT_NE(m.indices[0], m.indices[3]);
  EXPECT_EQ(m.positions[m.indices[0]], m.positions[m.indices[3]]);
}

TEST(ObjReader, KicadConnectorObjectsAndTriangles) {
  CollectingSink s = readAll(test::sharedDataDir() / "kicad_dsub62.obj");
  EXPECT_EQ(s.objects.size(), 648u);
  std::set<uint32_t> ids;
  for (const auto& o : s.objects) ids.insert(o.info.id);
  EXPECT_EQ(ids.size(), 648u);
  EXPECT_EQ(*ids.rbegin(), 647u);
  EXPECT_EQ(s.triangles(), 94176u);
  EXPECT_EQ(s.objects.front().info.name, "shape0");
  for (const auto& o : s.objects) {
    const TriangleMesh& m = meshOf(o);
    for (uint32_t i : m.indices) ASSERT_LT(i, m.positions.size());
  }
}

// Past ReadOptions::vertex_memory_bytes the vertex and normal pools spill to a file in the spill
// folder: the parts handed to the sink are the same as with the pools in memory, and the folder
// holds nothing afterwards (the file is unlinked at once).
TEST(ObjReader, VertexPoolsOverTheirLimitSpillAndGiveTheSameParts) {
  const auto path = test::sharedDataDir() / "kicad_dsub62.obj";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "missing " << path;
  const std::filesystem::path spill = test::scratchDir() / "obj-spill";
  std::filesystem::remove_all(spill);
  ReadOptions options;
  options.vertex_memory_bytes = 32 * 1024;  // of about 1.6 MB of positions and normals
  options.spill_dir = spill;
  options.max_part_triangles = 100;
  ReadOptions in_memory;
  in_memory.max_part_triangles = 100;
  const CollectingSink spilled = readAll(path, options), whole = readAll(path, in_memory);
  ASSERT_EQ(spilled.objects.size(), whole.objects.size());
  ASSERT_GT(whole.objects.size(), 648u) << "parts of large objects, so parts end mid-object";
  for (size_t i = 0; i < whole.objects.size(); ++i) {
    const TriangleMesh &a = meshOf(spilled.objects[i]), &b = meshOf(whole.objects[i]);
    ASSERT_EQ(spilled.objects[i].info.id, whole.objects[i].info.id) << i;
    ASSERT_EQ(a.indices, b.indices) << i;
    ASSERT_EQ(a.positions, b.positions) << i;
    ASSERT_EQ(a.normals, b.normals) << i;
  }
  EXPECT_TRUE(std::filesystem::is_directory(spill)) << "the pools did spill";
  EXPECT_TRUE(std::filesystem::is_empty(spill));
}

TEST(ObjReader, BunnyIsOneObject) {
  CollectingSink s = readAll(test::sharedDataDir() / "stanford-bunny.obj");
  // 69,451 triangles exceed the default part size of 65,536: two parts of one object.
  ASSERT_EQ(s.objects.size(), 2u);
  for (const auto& o : s.objects) {
    EXPECT_EQ(o.info.id, 0u);
    EXPECT_EQ(o.info.name, "stanford-bunny");
  }
  EXPECT_EQ(meshOf(s.objects[0]).triangleCount(), 65536u);
  EXPECT_EQ(s.triangles(), 69451u);
}

TEST(ObjReader, PartSplittingKeepsTotalsAndIds) {
  ReadOptions options;
  options.max_part_triangles = 1000;
  CollectingSink bunny = readAll(test::sharedDataDir() / "stanford-bunny.obj", options);
  EXPECT_EQ(bunny.objects.size(), 70u);  // ceil(69451 / 1000)
  EXPECT_EQ(bunny.triangles(), 69451u);
  for (const auto& o : bunny.objects) {
    EXPECT_EQ(o.info.id, 0u);
    const TriangleMesh& m = meshOf(o);
    EXPECT_LE(m.triangleCount(), 1000u);
    // A part carries only the vertices its triangles use.
    std::vector<bool> used(m.positions.size(), false);
    for (uint32_t i : m.indices) {
      ASSERT_LT(i, m.positions.size());
      used[i] = true;
    }
    EXPECT_TRUE(std::all_of(used.begin(), used.end(), [](bool b) { return b; }));
  }

  options.max_part_triangles = 100;
  CollectingSink kicad = readAll(test::sharedDataDir() / "kicad_dsub62.obj", options);
  EXPECT_GT(kicad.objects.size(), 648u);
  EXPECT_EQ(kicad.triangles(), 94176u);
  std::set<uint32_t> ids;
  uint32_t previous = 0;
  for (size_t i = 0; i < kicad.objects.size(); ++i) {
    uint32_t id = kicad.objects[i].info.id;
    if (i > 0) {
      EXPECT_TRUE(id == previous || id == previous + 1) << "parts must be consecutive";
    }
    previous = id;
    ids.insert(id);
    EXPECT_LE(meshOf(kicad.objects[i]).triangleCount(), 100u);
  }
  EXPECT_EQ(ids.size(), 648u);

  // One triangle per part: a polygon straddles part boundaries.
  options.max_part_triangles = 1;
  CollectingSink one = readAll(test::dataDir() / "fixtures" / "features.obj", options);
  EXPECT_EQ(one.objects.size(), 8u);
  EXPECT_EQ(one.triangles(), 8u);
  EXPECT_EQ(one.objects.back().info.id, 3u);
  EXPECT_EQ(meshOf(one.objects.back()).positions.size(), 3u);
}

TEST(ObjReader, ErrorsNameFileLineAndReason) {
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  expectLineError(tri + "f 1 2 0\n", 4, "index 0");
  expectLineError(tri + "f 1 2 4\n", 4, "vertex index 4 out of range (3 defined so far)");
  // 2^64 + 3 wrapped to index 3 once (a valid vertex): now refused at its line.
  expectLineError(tri + "f 1 2 18446744073709551619\n", 4, "bad face: expected vertex indices");
  expectLineError(tri + "f -1 -2 -4\n", 4, "vertex index -4 out of range");
  expectLineError(tri + "f 1 2\n", 4, "face with 2 vertices");
  expectLineError(tri + "f 1 2 x\n", 4, "bad face");
  expectLineError("v 0 0 zero\n", 1, "bad vertex");
  expectLineError("v 0 0 0 1 1\n", 1, "bad vertex");
  expectLineError("# comment\nvn 0 0\n", 2, "bad normal");
  expectLineError(tri + "vt 0 0\nf 1/2 2/1 3/1\n", 5, "texture coordinate index 2 out of range");
  expectLineError(tri + "f 1//1 2//1 3//1\n", 4, "normal index 1 out of range");
  expectLineError(tri + "vt 0 0\nvn 0 0 1\nf 1/1/1/1 2 3\n", 6, "too many '/'");
  expectLineError(tri + "f 1 2 \\\n 3\n", 4, "line continuation");
  expectLineError(tri + "f\n", 4, "without data");
}

TEST(ObjReader, MissingFileIsAFormatError) {
  test::NullSink sink;
  EXPECT_THROW(readObj(test::scratchDir() / "absent.obj", sink), FormatError);
}

TEST(ObjReader, RobustToDamage) {
  std::string original = test::readFile(test::dataDir() / "fixtures" / "features.obj");
  ASSERT_FALSE(original.empty());
  int rejected = test::expectRobustToDamage(
      original, "features.obj",
      [](const std::filesystem::path& p, SceneSink& sink) { readObj(p, sink); });
  EXPECT_GT(rejected, 0);
}

// ---------------------------------------------------------------- writer

SceneObject meshObject(uint32_t id, const std::string& name, uint32_t layer) {
  SceneObject o;
  o.info.id = id;
  o.info.name = name;
  o.info.layer = layer;
  TriangleMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0.5f}};
  m.indices = {0, 1, 2, 0, 2, 3};
  o.geometry = m;
  return o;
}

void expectClose(const glm::dvec3& a, const glm::dvec3& b) {
  double scale = std::max({1.0, glm::length(a), glm::length(b)});
  EXPECT_LE(glm::length(a - b) / scale, 1e-5) << a.x << " " << a.y << " " << a.z << " vs " << b.x
                                               << " " << b.y << " " << b.z;
}

// For every triangle corner, the world-space position, in triangle order.
std::vector<glm::dvec3> worldCorners(const SceneObject& o) {
  std::vector<glm::dvec3> out;
  const TriangleMesh& m = meshOf(o);
  for (uint32_t i : m.indices) out.push_back(o.info.transform.apply(m.positions[i]));
  return out;
}

TEST(ObjWriter, RoundTripKeepsNamesLayersCountsAndWorldPositions) {
  auto path = test::scratchDir() / "out.obj";
  std::vector<SceneObject> written;
  {
    ObjWriter writer(path, kDefaultChordalTolerance);
    writer.onLayer(0, Layer{"default"});
    writer.onLayer(1, Layer{"pipes", 0x80336699u});
    SceneObject far = meshObject(0, "far away", 1);
    far.info.transform.origin = glm::dvec3(123456.789, -2000.5, 30.25);  // km offsets
    far.info.transform.linear = glm::mat3(0, 2, 0, -2, 0, 0, 0, 0, 2);   // rotate 90 deg, scale 2
    far.info.db_key = "P-101";
    written.push_back(far);
    written.push_back(meshObject(1, "near", 0));
    SceneObject part2 = meshObject(1, "near", 0);  // a second part of object 1
    std::get<TriangleMesh>(part2.geometry).normals.assign(4, glm::vec3(0, 0, 1));
    written.push_back(part2);
    for (const auto& o : written) writer.onObject(o);
    writer.finish();
  }
  EXPECT_FALSE(std::filesystem::exists(path.string() + ".tmp"));
  std::string text = test::readFile(path);
  EXPECT_NE(text.find("# layer pipes key P-101\no far away\nusemtl pipes\n"), std::string::npos);

  CollectingSink back = readAll(path);
  ASSERT_EQ(back.objects.size(), 2u);  // the two parts of "near" merge under one "o"
  EXPECT_EQ(back.objects[0].info.name, "far away");
  EXPECT_EQ(back.layers.at(back.objects[0].info.layer).name, "pipes");
  EXPECT_EQ(back.layers.at(back.objects[0].info.layer).color_rgba, 0x80336699u);  // via out.mtl
  EXPECT_TRUE(std::filesystem::exists(path.parent_path() / "out.mtl"));
  EXPECT_EQ(back.objects[1].info.name, "near");
  EXPECT_EQ(back.layers.at(back.objects[1].info.layer).name, "default");
  EXPECT_EQ(meshOf(back.objects[0]).triangleCount(), 2u);
  EXPECT_EQ(meshOf(back.objects[1]).triangleCount(), 4u);
  EXPECT_TRUE(back.objects[0].info.transform.isIdentity());

  auto expected = worldCorners(written[0]);
  auto got = worldCorners(back.objects[0]);
  ASSERT_EQ(got.size(), expected.size());
  for (size_t i = 0; i < got.size(); ++i) expectClose(got[i], expected[i]);
  // 9 significant digits keep sub-millimetre accuracy 123 km from the origin.
  EXPECT_NEAR(got[1].x, 123456.789, 1e-3);
  EXPECT_NEAR(got[1].y, -2000.5 + 2.0, 1e-3);
}

TEST(ObjWriter, RoundTripOfKicadConnector) {
  CollectingSink original = readAll(test::sharedDataDir() / "kicad_dsub62.obj");
  auto path = test::scratchDir() / "kicad.obj";
  {
    ObjWriter writer(path, kDefaultChordalTolerance);
    for (size_t i = 0; i < original.layers.size(); ++i)
      writer.onLayer(static_cast<uint32_t>(i), original.layers[i]);
    for (const auto& o : original.objects) writer.onObject(o);
    writer.finish();
  }
  CollectingSink back = readAll(path);
  ASSERT_EQ(back.objects.size(), original.objects.size());
  EXPECT_EQ(back.triangles(), 94176u);
  for (size_t i = 0; i < back.objects.size(); ++i) {
    ASSERT_EQ(back.objects[i].info.name, original.objects[i].info.name);
    auto a = worldCorners(original.objects[i]);
    auto b = worldCorners(back.objects[i]);
    ASSERT_EQ(a.size(), b.size());
    for (size_t k = 0; k < a.size(); ++k) {
      double scale = std::max(1.0, glm::length(a[k]));
      ASSERT_LE(glm::length(a[k] - b[k]) / scale, 1e-5);
    }
  }
}

TEST(ObjWriter, TessellatesPrimitives) {
  auto path = test::scratchDir() / "box.obj";
  SceneObject box;
  box.info.id = 7;
  box.info.name = "box";
  box.info.transform.origin = glm::dvec3(5, 0, 0);
  box.geometry = Primitive{Box{glm::vec3(1, 2, 3)}};
  {
    ObjWriter writer(path, kDefaultChordalTolerance);
    writer.onLayer(0, Layer{"default"});
    writer.onObject(box);
    writer.finish();
  }
  CollectingSink back = readAll(path);
  ASSERT_EQ(back.objects.size(), 1u);
  EXPECT_EQ(meshOf(back.objects[0]).triangleCount(),
            triangleCount(box.geometry, kDefaultChordalTolerance));
  EXPECT_GT(back.triangles(), 0u);
  for (const glm::vec3& p : meshOf(back.objects[0]).positions) {
    EXPECT_NEAR(std::fabs(p.x - 5.0f), 1.0f, 1e-4f);  // every box corner lies at x = 5 +- 1
  }
}

TEST(ObjWriter, NoFileUntilFinishAndTempRemovedOnAbandon) {
  auto path = test::scratchDir() / "abandoned.obj";
  {
    ObjWriter writer(path, kDefaultChordalTolerance);
    writer.onLayer(0, Layer{"default"});
    writer.onObject(meshObject(0, "a", 0));
    EXPECT_FALSE(std::filesystem::exists(path));
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_FALSE(std::filesystem::exists(path.string() + ".tmp"));
  EXPECT_FALSE(std::filesystem::exists(path.parent_path() / "abandoned.mtl"));
}

TEST(ObjWriter, UnwritableDestinationThrowsNamingTheFile) {
  auto path = test::scratchDir() / "no" / "such" / "dir" / "x.obj";
  try {
    ObjWriter writer(path, kDefaultChordalTolerance);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("x.obj"), std::string::npos) << e.what();
  }
}

// An OBJ written with lone CR line ends (classic Mac OS) reads as the same mesh, not as empty.
TEST(ObjReader, CrOnlyLineEndsReadLikeLf) {
  const std::string lf = "o tri\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";
  std::string cr = lf;
  std::replace(cr.begin(), cr.end(), '\n', '\r');
  auto dir = test::scratchDir();
  test::writeFile(dir / "lf.obj", lf);
  test::writeFile(dir / "cr.obj", cr);
  test::CollectingSink a, b;
  readObj(dir / "lf.obj", a);
  readObj(dir / "cr.obj", b);
  ASSERT_EQ(b.objects.size(), 1u);
  const auto& mesh = std::get<TriangleMesh>(b.objects[0].geometry);
  EXPECT_EQ(mesh.triangleCount(), 2u);
  EXPECT_EQ(mesh.indices, std::get<TriangleMesh>(a.objects[0].geometry).indices);
  EXPECT_EQ(b.objects[0].info.name, "tri");
}

}  // namespace
}  // namespace tw
