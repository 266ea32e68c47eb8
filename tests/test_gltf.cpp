// glTF / GLB reader: node hierarchy and transforms, primitives, materials, part splitting, and
// rejection of damaged or inconsistent files with clear errors.
#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include <nlohmann/json.hpp>

#include "gltf_reader.h"
#include "scene_io.h"
#include "test_support.h"

namespace tw {
namespace {

using test::CollectingSink;
using Json = nlohmann::json;

const TriangleMesh& meshOf(const SceneObject& o) { return std::get<TriangleMesh>(o.geometry); }

std::filesystem::path fixture(const char* name) { return test::dataDir() / "fixtures" / name; }

CollectingSink readAll(const std::filesystem::path& path, const ReadOptions& options = {}) {
  CollectingSink sink;
  readGltf(path, sink, options);
  return sink;
}

void expectNear(const glm::dvec3& a, const glm::dvec3& b) {
  EXPECT_NEAR(a.x, b.x, 1e-6);
  EXPECT_NEAR(a.y, b.y, 1e-6);
  EXPECT_NEAR(a.z, b.z, 1e-6);
}

// The fixture: node "Frame" (translation 10 20 30, 90 degrees about +Z) holds mesh "Square";
// node "Holder" (translation 100 0 0, scale 2) has an unnamed child (translation 0 0 5) holding
// mesh "Tetra".
void expectFixtureScene(const CollectingSink& s) {
  ASSERT_EQ(s.layers.size(), 1u);
  ASSERT_EQ(s.objects.size(), 2u);

  const SceneObject& frame = s.objects[0];
  EXPECT_EQ(frame.info.id, 0u);
  EXPECT_EQ(frame.info.name, "Frame");
  EXPECT_EQ(frame.info.color_rgba, 0xff0000ffu);  // red base colour
  const TriangleMesh& square = meshOf(frame);
  EXPECT_EQ(square.triangleCount(), 2u);
  ASSERT_EQ(square.positions.size(), 4u);
  ASSERT_EQ(square.normals.size(), 4u);
  EXPECT_TRUE(square.colors.empty());
  EXPECT_EQ(square.positions[1], glm::vec3(1, 0, 0));  // local, untransformed
  expectNear(frame.info.transform.origin, {10, 20, 30});
  expectNear(frame.info.transform.apply(square.positions[1]), {10, 21, 30});
  expectNear(frame.info.transform.apply(square.positions[2]), {9, 21, 30});
  expectNear(glm::dvec3(frame.info.transform.linear * square.normals[0]), {0, 0, 1});

  const SceneObject& tetra = s.objects[1];
  EXPECT_EQ(tetra.info.id, 1u);
  EXPECT_EQ(tetra.info.name, "Tetra");  // unnamed node: the mesh's name
  EXPECT_EQ(tetra.info.color_rgba, 0xff008000u);
  const TriangleMesh& tm = meshOf(tetra);
  EXPECT_EQ(tm.triangleCount(), 4u);
  ASSERT_EQ(tm.positions.size(), 4u);
  EXPECT_EQ(tm.normals.size(), 4u);
  // Holder (T 100 0 0, S 2) * child (T 0 0 5): local (1, 0, 0) -> (102, 0, 10).
  expectNear(tetra.info.transform.origin, {100, 0, 10});
  expectNear(tetra.info.transform.apply(glm::vec3(1, 0, 0)), {102, 0, 10});
  expectNear(tetra.info.transform.apply(glm::vec3(0, 0, 1)), {100, 0, 12});
}

// glTF is Y up by its specification: readScene turns it Z up with no option, (x, y, z) ->
// (x, -z, y), and --up z keeps the file's frame.
TEST(GltfReader, ReadSceneTurnsTheYUpFileZUp) {
  CollectingSink turned, kept;
  readScene(fixture("two_nodes.gltf"), turned);
  ReadOptions z_up;
  z_up.up = UpAxis::Z;
  readScene(fixture("two_nodes.gltf"), kept, z_up);
  ASSERT_EQ(turned.objects.size(), 2u);
  ASSERT_EQ(kept.objects.size(), 2u);
  const SceneObject& frame = turned.objects[0];
  const TriangleMesh& square = meshOf(frame);
  EXPECT_EQ(square.positions[1], glm::vec3(1, 0, 0)) << "local frames stay";
  expectNear(frame.info.transform.origin, {10, -30, 20});
  expectNear(frame.info.transform.apply(square.positions[1]), {10, -30, 21});
  // The Square's normal is +Z in the file (along the file's depth): -Y after the turn.
  expectNear(glm::dvec3(frame.info.transform.linear * square.normals[0]), {0, -1, 0});
  expectNear(kept.objects[0].info.transform.origin, {10, 20, 30});
  // Handedness is kept: the turn is a rotation.
  EXPECT_NEAR(glm::determinant(glm::dmat3(frame.info.transform.linear)),
              glm::determinant(glm::dmat3(kept.objects[0].info.transform.linear)), 1e-6);
}

TEST(GltfReader, EmbeddedBufferFixture) { expectFixtureScene(readAll(fixture("two_nodes.gltf"))); }

TEST(GltfReader, BinaryFixture) { expectFixtureScene(readAll(fixture("two_nodes.glb"))); }

TEST(GltfReader, PartSplittingKeepsIdsAndTotals) {
  ReadOptions options;
  options.max_part_triangles = 1;
  CollectingSink s = readAll(fixture("two_nodes.glb"), options);
  ASSERT_EQ(s.objects.size(), 6u);
  EXPECT_EQ(s.triangles(), 6u);
  for (size_t i = 0; i < s.objects.size(); ++i) {
    EXPECT_EQ(s.objects[i].info.id, i < 2 ? 0u : 1u);
    EXPECT_EQ(meshOf(s.objects[i]).positions.size(), 3u);  // only the vertices it uses
  }
}

// Writes `doc` (the .gltf fixture, edited) and returns the error reading it.
std::string errorFor(const Json& doc) {
  auto path = test::scratchDir() / "edited.gltf";
  test::writeFile(path, doc.dump());
  try {
    test::NullSink sink;
    readGltf(path, sink);
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("edited.gltf"), std::string::npos) << e.what();
    return e.reason();
  }
  ADD_FAILURE() << "no error";
  return {};
}

Json fixtureJson() { return Json::parse(test::readFile(fixture("two_nodes.gltf"))); }

TEST(GltfReader, InconsistentFilesGiveClearErrors) {
  {
    Json doc = fixtureJson();
    doc["accessors"][0]["count"] = 4000;  // positions past the end of their buffer view
    EXPECT_NE(errorFor(doc).find("overrun buffer view"), std::string::npos);
  }
  {
    Json doc = fixtureJson();
    doc["bufferViews"][0]["byteLength"] = 1u << 20;  // view larger than the buffer
    EXPECT_NE(errorFor(doc).find("lies outside buffer"), std::string::npos);
  }
  {
    Json doc = fixtureJson();
    doc["accessors"][0]["componentType"] = 5123;  // POSITION as unsigned short
    EXPECT_NE(errorFor(doc).find("must be float VEC3"), std::string::npos);
  }
  {
    Json doc = fixtureJson();
    doc["accessors"][3]["count"] = 3;  // Tetra keeps 3 of its 4 vertices: index 3 is out of range
    doc["accessors"][4]["count"] = 3;
    EXPECT_NE(errorFor(doc).find("out of range"), std::string::npos);
  }
  {
    Json doc = fixtureJson();
    doc["nodes"][2]["children"] = Json::array({1});  // a cycle
    EXPECT_NE(errorFor(doc).find("reached twice"), std::string::npos);
  }
  {
    Json doc = fixtureJson();
    doc["nodes"][0]["mesh"] = 9;
    EXPECT_NE(errorFor(doc).find("invalid mesh 9"), std::string::npos);
  }
  {
    Json doc = fixtureJson();
    doc["scene"] = 3;
    std::string reason = errorFor(doc);
    EXPECT_FALSE(reason.empty());
  }
  {
    Json doc = fixtureJson();
    doc["accessors"][2]["count"] = 5;  // 5 indices: not whole triangles
    EXPECT_NE(errorFor(doc).find("not a multiple of 3"), std::string::npos);
  }
  {
    auto path = test::scratchDir() / "broken.gltf";
    test::writeFile(path, "{ \"asset\": { \"version\": \"2.0\" }, ");
    test::NullSink sink;
    try {
      readGltf(path, sink);
      ADD_FAILURE() << "no error";
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find("broken.gltf: glTF"), std::string::npos) << e.what();
    }
  }
}

// What a hostile file tries: a buffer outside the model's folder, offsets that tinygltf would
// read as 0, a required extension that changes the geometry, a data URI of 200 KB quoted whole
// into the error. Each is a short error naming the file and the field.
TEST(GltfReader, HostileFieldsAreRefusedNamingTheField) {
  const auto scratch = test::scratchDir();
  const auto dir = scratch / "model";
  std::filesystem::create_directories(dir);
  test::writeFile(scratch / "secret.bin", std::string(1024, 's'));
  auto errorIn = [&](const Json& doc) {
    test::writeFile(dir / "hostile.gltf", doc.dump());
    test::NullSink sink;
    try {
      readGltf(dir / "hostile.gltf", sink);
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find("hostile.gltf"), std::string::npos) << e.what();
      EXPECT_LT(std::string(e.what()).size(), 1500u) << "one short line";
      return std::string(e.what());
    }
    return std::string();
  };
  {
    Json doc = fixtureJson();
    doc["buffers"][0]["uri"] = "../secret.bin";
    EXPECT_NE(errorIn(doc).find("lies outside the model's folder"), std::string::npos);
    // tinygltf looks an absolute uri up under the model's folder, where it is not.
    doc["buffers"][0]["uri"] = (scratch / "secret.bin").string();
    EXPECT_NE(errorIn(doc), "");
  }
  for (const Json& bad : {Json(-4), Json(1e20), Json(0.5)}) {
    Json doc = fixtureJson();
    doc["bufferViews"][0]["byteOffset"] = bad;
    EXPECT_NE(errorIn(doc).find("bufferViews[0].byteOffset is " + bad.dump()), std::string::npos) << bad;
  }
  {
    Json doc = fixtureJson();
    doc["accessors"][1]["count"] = -1;
    EXPECT_NE(errorIn(doc).find("accessors[1].count is -1"), std::string::npos);
  }
  {
    Json doc = fixtureJson();
    doc["extensionsUsed"] = Json::array({"KHR_draco_mesh_compression"});
    doc["extensionsRequired"] = Json::array({"KHR_draco_mesh_compression"});
    EXPECT_NE(errorIn(doc).find("requires the glTF extension KHR_draco_mesh_compression"),
              std::string::npos);
    doc["extensionsUsed"] = Json::array({"KHR_materials_unlit"});
    doc["extensionsRequired"] = Json::array({"KHR_materials_unlit"});
    EXPECT_EQ(errorIn(doc), "") << "a material extension does not change the geometry";
  }
  {
    Json doc = fixtureJson();
    doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + std::string(200000, '!');
    EXPECT_NE(errorIn(doc), "");
  }
}

TEST(GltfReader, DeeplyNestedJsonIsRejectedNotRecursedInto) {
  auto path = test::scratchDir() / "deep.gltf";
  const size_t depth = 100000;
  test::writeFile(path, "{\"asset\":{\"version\":\"2.0\"},\"extras\":" + std::string(depth, '[') +
                            std::string(depth, ']') + "}");
  test::NullSink sink;
  try {
    readGltf(path, sink);
    ADD_FAILURE() << "no error";
  } catch (const FormatError& e) {
    EXPECT_NE(e.reason().find("nested deeper"), std::string::npos) << e.what();
  }
}

TEST(GltfReader, ExternalBufferNextToTheFile) {
  // The .glb's BIN chunk is exactly the embedded buffer: reuse it as an external .bin.
  std::string glb = test::readFile(fixture("two_nodes.glb"));
  uint32_t json_bytes;
  std::memcpy(&json_bytes, glb.data() + 12, 4);
  std::string bin = glb.substr(20 + json_bytes + 8);
  Json doc = fixtureJson();
  ASSERT_EQ(doc["buffers"][0]["byteLength"].get<size_t>(), bin.size());
  doc["buffers"][0]["uri"] = "geometry.bin";
  auto dir = test::scratchDir();
  test::writeFile(dir / "external.gltf", doc.dump());
  test::NullSink sink;
  try {
    readGltf(dir / "external.gltf", sink);
    ADD_FAILURE() << "no error for a missing .bin";
  } catch (const FormatError& e) {
    EXPECT_NE(e.reason().find("geometry.bin"), std::string::npos) << e.what();
  }
  test::writeFile(dir / "geometry.bin", bin);
  expectFixtureScene(readAll(dir / "external.gltf"));
}

TEST(GltfReader, NoScenesMeansAllRootNodes) {
  Json doc = fixtureJson();
  doc.erase("scenes");
  doc.erase("scene");
  auto path = test::scratchDir() / "noscene.gltf";
  test::writeFile(path, doc.dump());
  CollectingSink s = readAll(path);
  ASSERT_EQ(s.objects.size(), 2u);
  EXPECT_EQ(s.objects[1].info.name, "Tetra");
  expectNear(s.objects[1].info.transform.origin, {100, 0, 10});
}

TEST(GltfReader, GlbContainerErrorsCarryByteOffsets) {
  std::string glb = test::readFile(fixture("two_nodes.glb"));
  ASSERT_GT(glb.size(), 20u);
  auto path = test::scratchDir() / "cut.glb";
  test::writeFile(path, glb.substr(0, glb.size() - 10));
  test::NullSink sink;
  try {
    readGltf(path, sink);
    ADD_FAILURE() << "no error";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.where(), FormatError::Where::Byte);
    EXPECT_EQ(e.position(), 8u);  // the header's length field
    EXPECT_NE(e.reason().find("GLB header says"), std::string::npos) << e.what();
  }
  std::string bad_version = glb;
  bad_version[4] = 1;
  test::writeFile(path, bad_version);
  EXPECT_THROW(readGltf(path, sink), FormatError);
}

TEST(GltfReader, MissingFileIsAFormatError) {
  test::NullSink sink;
  EXPECT_THROW(readGltf(test::scratchDir() / "absent.glb", sink), FormatError);
}

TEST(GltfReader, RobustToDamageText) {
  int rejected = test::expectRobustToDamage(
      test::readFile(fixture("two_nodes.gltf")), "two_nodes.gltf",
      [](const std::filesystem::path& p, SceneSink& sink) { readGltf(p, sink); });
  EXPECT_GT(rejected, 0);
}

TEST(GltfReader, RobustToDamageBinary) {
  int rejected = test::expectRobustToDamage(
      test::readFile(fixture("two_nodes.glb")), "two_nodes.glb",
      [](const std::filesystem::path& p, SceneSink& sink) { readGltf(p, sink); });
  EXPECT_GT(rejected, 0);
}

}  // namespace
}  // namespace tw
