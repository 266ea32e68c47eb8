// STL reader: binary detection by size, ASCII solids as objects, parts, errors, damaged fixtures.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "stl_reader.h"
#include "test_support.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

fs::path fixture(const std::string& name) { return test::dataDir() / "fixtures" / name; }

test::CollectingSink read(const fs::path& path, uint32_t max_part_triangles = 1u << 16) {
  test::CollectingSink sink;
  ReadOptions options;
  options.max_part_triangles = max_part_triangles;
  readStl(path, sink, options);
  return sink;
}

// Triangle corners in order, across all parts.
std::vector<glm::vec3> corners(const test::CollectingSink& sink) {
  std::vector<glm::vec3> out;
  for (const SceneObject& o : sink.objects) {
    const auto& m = std::get<TriangleMesh>(o.geometry);
    for (uint32_t i : m.indices) out.push_back(m.positions.at(i));
  }
  return out;
}

std::string binaryStl(const std::string& header80, const std::vector<glm::vec3>& corners) {
  std::string bytes = header80;
  bytes.resize(80, ' ');
  uint32_t count = static_cast<uint32_t>(corners.size() / 3);
  bytes.append(reinterpret_cast<const char*>(&count), 4);
  for (size_t t = 0; t < count; ++t) {
    bytes.append(12, '\0');  // normal
    bytes.append(reinterpret_cast<const char*>(&corners[3 * t]), 36);
    bytes.append(2, '\0');
  }
  return bytes;
}

TEST(StlReader, AsciiSolidsBecomeObjects) {
  auto sink = read(fixture("two_solids.stl"));
  ASSERT_EQ(sink.layers.size(), 1u);
  EXPECT_EQ(sink.layers[0].name, "default");
  ASSERT_EQ(sink.objects.size(), 2u);
  EXPECT_EQ(sink.objects[0].info.id, 0u);
  EXPECT_EQ(sink.objects[0].info.name, "first part");
  EXPECT_EQ(std::get<TriangleMesh>(sink.objects[0].geometry).triangleCount(), 2u);
  EXPECT_EQ(sink.objects[1].info.id, 1u);
  EXPECT_EQ(sink.objects[1].info.name, "two_solids");  // unnamed solid: the file stem
  const auto& m = std::get<TriangleMesh>(sink.objects[1].geometry);
  ASSERT_EQ(m.triangleCount(), 1u);
  EXPECT_EQ(m.positions.at(m.indices[2]), glm::vec3(5.0f, 6.0f, 5.5f));
}

TEST(StlReader, BinaryStartingWithSolidIsReadAsBinary) {
  std::string bytes = test::readFile(fixture("cube_binary.stl"));
  ASSERT_EQ(bytes.rfind("solid", 0), 0u);
  auto binary = read(fixture("cube_binary.stl"));
  ASSERT_EQ(binary.objects.size(), 1u);
  EXPECT_EQ(binary.objects[0].info.name, "cube_binary");
  EXPECT_EQ(binary.objects[0].info.id, 0u);
  const auto& m = std::get<TriangleMesh>(binary.objects[0].geometry);
  EXPECT_EQ(m.triangleCount(), 12u);
  EXPECT_EQ(m.positions.size(), 36u);  // not welded
  // Same triangles as the ASCII cube.
  auto ascii = read(fixture("cube_ascii.stl"));
  ASSERT_EQ(ascii.objects.size(), 1u);
  EXPECT_EQ(ascii.objects[0].info.name, "cube");
  EXPECT_EQ(corners(binary), corners(ascii));
}

TEST(StlReader, TrianglesArriveInParts) {
  for (const char* name : {"cube_binary.stl", "cube_ascii.stl"}) {
    auto sink = read(fixture(name), 5);
    ASSERT_EQ(sink.objects.size(), 3u) << name;  // 5 + 5 + 2
    EXPECT_EQ(std::get<TriangleMesh>(sink.objects[2].geometry).triangleCount(), 2u);
    for (const SceneObject& o : sink.objects) {
      EXPECT_EQ(o.info.id, 0u);
      EXPECT_EQ(std::get<TriangleMesh>(o.geometry).positions.size(),
                std::get<TriangleMesh>(o.geometry).indices.size());
    }
    EXPECT_EQ(corners(sink), corners(read(fixture(name))));
  }
}

TEST(StlReader, UnnamedSolidOnTheFirstLine) {
  auto path = test::scratchDir() / "plain.stl";
  test::writeFile(path,
                  "solid\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                  "vertex 0 1 0\nendloop\nendfacet\nendsolid\n");
  auto sink = read(path);
  ASSERT_EQ(sink.objects.size(), 1u);
  EXPECT_EQ(sink.objects[0].info.name, "plain");
  EXPECT_EQ(sink.triangles(), 1u);
}

TEST(StlReader, AsciiQuadLoopsAndUppercaseKeywords) {
  auto path = test::scratchDir() / "quad.stl";
  test::writeFile(path,
                  "SOLID Plate\r\nFACET NORMAL 0 0 1\r\nOUTER LOOP\r\nVERTEX 0 0 0\r\n"
                  "VERTEX 1 0 0\r\nVERTEX 1 1 0\r\nVERTEX 0 1 0\r\nENDLOOP\r\nENDFACET\r\n"
                  "ENDSOLID Plate\r\n");
  auto sink = read(path);
  ASSERT_EQ(sink.objects.size(), 1u);
  EXPECT_EQ(sink.objects[0].info.name, "Plate");
  auto got = corners(sink);
  std::vector<glm::vec3> expected = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0},
                                     {0, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  EXPECT_EQ(got, expected);
}

TEST(StlReader, LargeBinaryAcrossBufferBoundaries) {
  std::vector<glm::vec3> expected;
  for (int i = 0; i < 300000; ++i)  // 15 MB: several reader buffers
    expected.insert(expected.end(), {{float(i), 0, 0}, {0, float(i), 0}, {0, 0, float(i) * 0.5f}});
  auto path = test::scratchDir() / "big.stl";
  test::writeFile(path, binaryStl("binary", expected));
  auto sink = read(path);
  EXPECT_EQ(sink.objects.size(), 5u);  // parts of 65536
  EXPECT_EQ(corners(sink), expected);
  fs::remove(path);  // 15 MB in a memory-backed scratch directory
}

FormatError errorFor(const std::string& bytes, const std::string& name = "bad.stl") {
  auto path = test::scratchDir() / name;
  test::writeFile(path, bytes);
  test::NullSink sink;
  try {
    readStl(path, sink);
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    return e;
  }
  ADD_FAILURE() << "no error for " << name;
  return FormatError(name, "none");
}

TEST(StlReader, ErrorsNameTheLineOrByte) {
  auto e = errorFor("solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0\n");
  EXPECT_EQ(e.where(), FormatError::Where::Line);
  EXPECT_EQ(e.position(), 5u);
  EXPECT_NE(e.reason().find("three numbers"), std::string::npos) << e.what();

  // Trailing text after a vertex's numbers is an error, not ignored.
  e = errorFor("solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0 junk\n");
  EXPECT_EQ(e.position(), 4u);
  EXPECT_NE(e.reason().find("unexpected 'junk' after the vertex's three numbers"), std::string::npos)
      << e.what();

  e = errorFor("solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\n");
  EXPECT_EQ(e.position(), 6u);
  EXPECT_NE(e.reason().find("at least 3"), std::string::npos) << e.what();

  e = errorFor("solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n");
  EXPECT_NE(e.reason().find("endsolid"), std::string::npos) << e.what();

  e = errorFor("solid a\nendsolid a\nsolid b\nfacet\nloop\n");
  EXPECT_EQ(e.position(), 5u);
  EXPECT_NE(e.reason().find("'outer loop'"), std::string::npos) << e.what();

  // A truncated binary file: its size no longer matches the count, and it is not ASCII.
  std::string binary = binaryStl(std::string("\0\1\2", 3), {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  e = errorFor(binary.substr(0, binary.size() - 1));
  EXPECT_EQ(e.where(), FormatError::Where::Byte);
  EXPECT_NE(e.reason().find("not a binary STL"), std::string::npos) << e.what();
  EXPECT_NE(e.reason().find("count of 1 needs 134"), std::string::npos) << e.what();  // 84 + 50

  // A binary file whose header says "solid" but whose size is wrong falls to ASCII parsing,
  // which fails on the binary bytes with a line number.
  binary = binaryStl("solid x", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  e = errorFor(binary + "!");
  EXPECT_EQ(e.where(), FormatError::Where::Line);

  std::vector<glm::vec3> bad = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {1, 0, 0}, {0, 0, 0}};
  bad[4].y = std::nanf("");
  e = errorFor(binaryStl("", bad));
  EXPECT_EQ(e.position(), 84u + 50u);
  EXPECT_NE(e.reason().find("non-finite"), std::string::npos) << e.what();
}

TEST(StlReader, DamagedFixturesGiveCleanErrors) {
  for (const char* name : {"two_solids.stl", "cube_ascii.stl", "cube_binary.stl"}) {
    std::string bytes = test::readFile(fixture(name));
    ASSERT_FALSE(bytes.empty()) << name;
    int rejected = test::expectRobustToDamage(
        bytes, name, [](const fs::path& p, SceneSink& s) { readStl(p, s); });
    EXPECT_GT(rejected, static_cast<int>(bytes.size() / 2)) << name;
  }
}

}  // namespace
}  // namespace tw
