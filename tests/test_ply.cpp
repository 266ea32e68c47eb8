// PLY reader and writer: the three encodings read alike, polygons, attributes, skipped elements,
// parts, the writer round trip, specific error messages and damaged fixtures.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "ply_reader.h"
#include "ply_writer.h"
#include "tessellate.h"
#include "test_support.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

fs::path fixture(const std::string& name) { return test::dataDir() / "fixtures" / name; }

test::CollectingSink read(const fs::path& path, uint32_t max_part_triangles = 1u << 16) {
  test::CollectingSink sink;
  ReadOptions options;
  options.max_part_triangles = max_part_triangles;
  readPly(path, sink, options);
  return sink;
}

// One triangle corner with everything the reader delivers, independent of how parts split.
struct Corner {
  glm::vec3 position;
  glm::vec3 normal;
  uint32_t color;
  bool operator==(const Corner&) const = default;
};

std::vector<Corner> corners(const test::CollectingSink& sink) {
  std::vector<Corner> out;
  for (const SceneObject& o : sink.objects) {
    const auto& m = std::get<TriangleMesh>(o.geometry);
    for (uint32_t i : m.indices)
      out.push_back({m.positions.at(i), m.normals.empty() ? glm::vec3(0.0f) : m.normals.at(i),
                     m.colors.empty() ? 0u : m.colors.at(i)});
  }
  return out;
}

// Re-encodes an ASCII PLY as binary (the host is little-endian), so that one text states a test
// case in all three encodings.
std::string toBinary(const std::string& ascii, bool big_endian) {
  struct Prop {
    bool list;
    std::string count_type, type;
  };
  std::istringstream in(ascii);
  std::string line, out;
  std::vector<std::pair<uint64_t, std::vector<Prop>>> elements;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (key == "format") {
      out += big_endian ? "format binary_big_endian 1.0\n" : "format binary_little_endian 1.0\n";
      continue;
    }
    out += line + "\n";
    if (key == "element") {
      std::string name;
      uint64_t count = 0;
      words >> name >> count;
      elements.push_back({count, {}});
    } else if (key == "property") {
      Prop p{false, "", ""};
      words >> p.type;
      if (p.type == "list") {
        p.list = true;
        words >> p.count_type >> p.type;
      }
      elements.back().second.push_back(p);
    } else if (key == "end_header") {
      break;
    }
  }
  auto put = [&](const std::string& type, double v) {
    char b[8];
    size_t n = 4;
    auto store = [&](auto x) {
      n = sizeof(x);
      std::memcpy(b, &x, n);
    };
    if (type == "char" || type == "int8")
      store(static_cast<int8_t>(v));
    else if (type == "uchar" || type == "uint8")
      store(static_cast<uint8_t>(v));
    else if (type == "short" || type == "int16")
      store(static_cast<int16_t>(v));
    else if (type == "ushort" || type == "uint16")
      store(static_cast<uint16_t>(v));
    else if (type == "int" || type == "int32")
      store(static_cast<int32_t>(v));
    else if (type == "uint" || type == "uint32")
      store(static_cast<uint32_t>(v));
    else if (type == "float" || type == "float32")
      store(static_cast<float>(v));
    else
      store(v);
    if (big_endian) std::reverse(b, b + n);
    out.append(b, n);
  };
  for (auto& [count, props] : elements)
    for (uint64_t i = 0; i < count; ++i)
      for (const Prop& p : props) {
        double v = 0;
        in >> v;
        put(p.list ? p.count_type : p.type, v);
        for (int k = 0; p.list && k < static_cast<int>(v); ++k) {
          double item = 0;
          in >> item;
          put(p.type, item);
        }
      }
  return out;
}

// Reads `ascii` as written and re-encoded both ways; expects the same corners from all three.
std::vector<Corner> readAllEncodings(const std::string& ascii) {
  auto dir = test::scratchDir();
  test::writeFile(dir / "a.ply", ascii);
  test::writeFile(dir / "le.ply", toBinary(ascii, false));
  test::writeFile(dir / "be.ply", toBinary(ascii, true));
  auto a = corners(read(dir / "a.ply"));
  EXPECT_EQ(a, corners(read(dir / "le.ply")));
  EXPECT_EQ(a, corners(read(dir / "be.ply")));
  return a;
}

// Positions of the poly fixture (see data/fixtures/poly_ascii.ply).
const glm::vec3 kPolyPositions[] = {{0, 0, 0},    {1, 0, 0},           {1, 1, 0},
                                    {0, 1, 0},    {2, 0, 0},           {3, 0, 0},
                                    {2, 1, 0.5f}, {3.5f, 0.5f, 0.25f}, {3, 1, -0.75f}};

TEST(PlyReader, AsciiLittleAndBigEndianGiveIdenticalMeshes) {
  for (std::string family : {"poly", "tri"}) {
    auto ascii = read(fixture(family + "_ascii.ply"));
    auto le = read(fixture(family + "_le.ply"));
    auto be = read(fixture(family + "_be.ply"));
    ASSERT_EQ(ascii.objects.size(), 1u) << family;
    ASSERT_EQ(le.objects.size(), 1u);
    ASSERT_EQ(be.objects.size(), 1u);
    const auto& a = std::get<TriangleMesh>(ascii.objects[0].geometry);
    for (const auto* other : {&le, &be}) {
      const auto& b = std::get<TriangleMesh>(other->objects[0].geometry);
      EXPECT_EQ(a.positions, b.positions) << family;
      EXPECT_EQ(a.normals, b.normals) << family;
      EXPECT_EQ(a.colors, b.colors) << family;
      EXPECT_EQ(a.indices, b.indices) << family;
    }
    EXPECT_EQ(a.triangleCount(), family == "poly" ? 7u : 18u);
  }
}

TEST(PlyReader, ObjectIsNamedAfterFileOnDefaultLayer) {
  auto sink = read(fixture("tri_le.ply"));
  ASSERT_EQ(sink.layers.size(), 1u);
  EXPECT_EQ(sink.layers[0].name, "default");
  ASSERT_EQ(sink.objects.size(), 1u);
  EXPECT_EQ(sink.objects[0].info.id, 0u);
  EXPECT_EQ(sink.objects[0].info.name, "tri_le");
  EXPECT_EQ(sink.objects[0].info.layer, 0u);
  EXPECT_TRUE(sink.objects[0].info.transform.isIdentity());
}

TEST(PlyReader, PolygonsAreFanTriangulatedAndShortFacesSkipped) {
  auto got = corners(read(fixture("poly_le.ply")));
  // Quad 0 1 2 3, triangle 1 4 2, pentagon 4 5 7 8 6, two-index face (skipped), triangle 3 2 6.
  const int expected[][3] = {{0, 1, 2}, {0, 2, 3}, {1, 4, 2}, {4, 5, 7},
                             {4, 7, 8}, {4, 8, 6}, {3, 2, 6}};
  ASSERT_EQ(got.size(), 21u);
  for (int t = 0; t < 7; ++t)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(got[3 * t + k].position, kPolyPositions[expected[t][k]]) << t << " " << k;
}

TEST(PlyReader, NormalsAndColoursAreRead) {
  auto sink = read(fixture("poly_be.ply"));
  const auto& m = std::get<TriangleMesh>(sink.objects.at(0).geometry);
  ASSERT_EQ(m.normals.size(), m.positions.size());
  ASSERT_EQ(m.colors.size(), m.positions.size());
  for (size_t i = 0; i < m.positions.size(); ++i) {
    // The fixture numbers vertex v with normal (v/8, 0, 1) and colour (10v, 255-10v, v, 200+v).
    int v = -1;
    for (int j = 0; j < 9; ++j)
      if (kPolyPositions[j] == m.positions[i]) v = j;
    ASSERT_GE(v, 0);
    EXPECT_EQ(m.normals[i], glm::vec3(v * 0.125f, 0.0f, 1.0f));
    uint32_t rgba = uint32_t(10 * v) | uint32_t(255 - 10 * v) << 8 | uint32_t(v) << 16 |
                    uint32_t(200 + v) << 24;
    EXPECT_EQ(m.colors[i], rgba) << v;
  }
}

TEST(PlyReader, FloatColoursDoublePositionsAndOtherTypesInAllEncodings) {
  // double positions, float colours without alpha, ushort list counts, uint indices, int8 and
  // int16 extras, and a vertex list property (which takes the general binary vertex path).
  const std::string ascii =
      "ply\nformat ascii 1.0\n"
      "element vertex 4\n"
      "property float64 x\nproperty double y\nproperty double z\n"
      "property list uint8 int16 extra\n"
      "property float red\nproperty float green\nproperty float blue\nproperty int8 flag\n"
      "element face 1\n"
      "property int16 before\n"
      "property list ushort uint vertex_index\n"
      "end_header\n"
      "0.5 0 0 2 -3 4 1.0 0.0 0.5 -1\n"
      "1.5 0 0 0 0.0 1.0 0.0 2\n"
      "1.5 1 0 1 7 0.0 0.0 1.0 3\n"
      "0.5 1 1e3 0 0.2 0.2 0.2 4\n"
      "-5 4 0 1 2 3\n";
  auto got = readAllEncodings(ascii);
  ASSERT_EQ(got.size(), 6u);
  EXPECT_EQ(got[0].position, glm::vec3(0.5f, 0.0f, 0.0f));
  EXPECT_EQ(got[0].color, 0xff8000ffu);  // red 1, green 0, blue 0.5 -> 128, alpha 255
  EXPECT_EQ(got[1].color, 0xff00ff00u);
  EXPECT_EQ(got[5].position, glm::vec3(0.5f, 1.0f, 1000.0f));
  EXPECT_EQ(got[5].color, 0xff333333u);  // 0.2 * 255 = 51
}

TEST(PlyReader, SkipsUnknownElementsAndListPropertiesBeforeAndAfter) {
  const std::string ascii =
      "ply\nformat ascii 1.0\ncomment a comment\nobj_info some info\n"
      "element range_grid 2\nproperty list uchar int vertex_indices\n"
      "element camera 1\nproperty float view_px\nproperty list int double k\n"
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 2\nproperty list uchar int vertex_indices\n"
      "property list uint float texcoord\nproperty list uchar uchar empty\n"
      "element tristrips 1\nproperty list int int vertex_indices\n"
      "element material 1\nproperty uchar ambient_red\n"
      "end_header\n"
      "3 0 1 2\n0\n"
      "1.5 3 1 2 3\n"
      "0 0 0\n1 0 0\n0 1 0\n"
      "3 0 1 2 6 0 0 1 0 0 1 0\n"
      "3 2 1 0 0 2 9 9\n"
      "5 0 1 2 -1 0\n"
      "7\n";
  auto got = readAllEncodings(ascii);
  ASSERT_EQ(got.size(), 6u);
  EXPECT_EQ(got[1].position, glm::vec3(1, 0, 0));
  EXPECT_EQ(got[3].position, glm::vec3(0, 1, 0));
}

TEST(PlyReader, PartsCarryOnlyTheVerticesTheyUse) {
  auto whole = read(fixture("poly_le.ply"));
  auto split = read(fixture("poly_le.ply"), 2);
  ASSERT_EQ(split.objects.size(), 4u);  // 7 triangles in parts of 2
  for (const SceneObject& part : split.objects) {
    EXPECT_EQ(part.info.name, "poly_le");
    EXPECT_EQ(part.info.id, 0u);
    const auto& m = std::get<TriangleMesh>(part.geometry);
    EXPECT_LE(m.triangleCount(), 2u);
    std::vector<bool> used(m.positions.size(), false);
    for (uint32_t i : m.indices) used.at(i) = true;
    EXPECT_TRUE(std::all_of(used.begin(), used.end(), [](bool u) { return u; }));
    EXPECT_EQ(m.normals.size(), m.positions.size());
    EXPECT_EQ(m.colors.size(), m.positions.size());
  }
  EXPECT_EQ(corners(whole), corners(split));
}

// A grid large enough to cross the reader's 4 MiB buffer many times, with a quad now and then
// so that the fast triangle path hands over to the general one and back at odd offsets.
TEST(PlyReader, LargeBinaryGridAcrossBufferBoundaries) {
  constexpr uint32_t kSide = 600;
  std::string body;
  std::vector<glm::vec3> positions;
  for (uint32_t r = 0; r < kSide; ++r)
    for (uint32_t c = 0; c < kSide; ++c) {
      glm::vec3 p(float(c) * 0.25f, float(r) * 0.5f, float((r * 7 + c * 3) % 11));
      positions.push_back(p);
      body.append(reinterpret_cast<const char*>(&p), 12);
    }
  std::vector<uint32_t> expected;  // triangles as global indices
  uint64_t faces = 0;
  auto putFace = [&](std::initializer_list<uint32_t> ids) {
    body.push_back(static_cast<char>(ids.size()));
    for (uint32_t id : ids) body.append(reinterpret_cast<const char*>(&id), 4);
    ++faces;
  };
  for (uint32_t r = 0; r + 1 < kSide; ++r)
    for (uint32_t c = 0; c + 1 < kSide; ++c) {
      uint32_t a = r * kSide + c, b = a + 1, d = a + kSide, e = d + 1;
      if ((r * kSide + c) % 997 == 0) {
        putFace({a, b, e, d});
      } else {
        putFace({a, b, e});
        putFace({a, e, d});
      }
      expected.insert(expected.end(), {a, b, e, a, e, d});
    }
  std::string file = "ply\nformat binary_little_endian 1.0\nelement vertex " +
                     std::to_string(positions.size()) + "\nproperty float x\nproperty float y\n" +
                     "property float z\nelement face " + std::to_string(faces) +
                     "\nproperty list uchar uint vertex_indices\nend_header\n" + body;
  auto path = test::scratchDir() / "grid.ply";
  test::writeFile(path, file);
  auto sink = read(path, 100000);
  EXPECT_EQ(sink.objects.size(), (expected.size() / 3 + 99999) / 100000);
  size_t k = 0;
  for (const SceneObject& o : sink.objects) {
    const auto& m = std::get<TriangleMesh>(o.geometry);
    for (uint32_t i : m.indices) {
      ASSERT_LT(k, expected.size());
      ASSERT_EQ(m.positions[i], positions[expected[k]]) << "corner " << k;
      ++k;
    }
  }
  EXPECT_EQ(k, expected.size());
  fs::remove(path);  // 13 MB in a memory-backed scratch directory
}

// A vertex table over its memory limit spills to a file in the spill folder; faces in a random
// order read their vertices back through the block cache, and every corner is what the
// in-memory table gives.
TEST(PlyReader, AVertexTableOverItsLimitSpillsAndReadsTheSameCorners) {
  constexpr uint32_t kSide = 400;
  std::string body;
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> colour(0, 255);
  for (uint32_t r = 0; r < kSide; ++r)
    for (uint32_t c = 0; c < kSide; ++c) {
      glm::vec3 p(float(c) * 0.25f, float(r) * 0.5f, float((r * 7 + c * 3) % 11));
      body.append(reinterpret_cast<const char*>(&p), 12);
      for (int k = 0; k < 3; ++k) body.push_back(char(colour(rng)));
    }
  std::vector<std::array<uint32_t, 3>> faces;
  for (uint32_t r = 0; r + 1 < kSide; ++r)
    for (uint32_t c = 0; c + 1 < kSide; ++c) {
      uint32_t a = r * kSide + c, b = a + 1, d = a + kSide, e = d + 1;
      faces.push_back({a, b, e});
      faces.push_back({a, e, d});
    }
  std::shuffle(faces.begin(), faces.end(), rng);
  for (const auto& f : faces) {
    body.push_back(3);
    for (uint32_t id : f) body.append(reinterpret_cast<const char*>(&id), 4);
  }
  std::string file = "ply\nformat binary_little_endian 1.0\nelement vertex " +
                     std::to_string(kSide * kSide) +
                     "\nproperty float x\nproperty float y\nproperty float z\n"
                     "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                     "element face " + std::to_string(faces.size()) +
                     "\nproperty list uchar uint vertex_indices\nend_header\n" + body;
  const fs::path path = test::scratchDir() / "spill.ply";
  const fs::path spill = test::scratchDir() / "spill-dir";
  fs::create_directories(spill);
  test::writeFile(path, file);
  const test::CollectingSink whole = read(path);
  test::CollectingSink spilled;
  ReadOptions options;
  options.vertex_memory_bytes = 64 * 1024;  // of 2.5 MB of vertices
  options.spill_dir = spill;
  readPly(path, spilled, options);
  EXPECT_EQ(corners(spilled), corners(whole));
  EXPECT_EQ(corners(whole).size(), faces.size() * 3);
  EXPECT_TRUE(fs::is_empty(spill)) << "nothing is left in the spill folder";
  fs::remove(path);
}

class RecordingProgress : public Progress {
 public:
  void beginStage(std::string_view name, uint64_t expected) override {
    stage = name;
    total = expected;
  }
  void update(uint64_t done) override { last = done; }
  void endStage() override { ended = true; }
  std::string stage;
  uint64_t total = 0, last = 0;
  bool ended = false;
};

TEST(PlyReader, ReportsBytesAsProgress) {
  RecordingProgress progress;
  ReadOptions options;
  options.progress = &progress;
  test::NullSink sink;
  readPly(fixture("tri_le.ply"), sink, options);
  EXPECT_EQ(progress.stage, "read");
  EXPECT_EQ(progress.total, fs::file_size(fixture("tri_le.ply")));
  EXPECT_EQ(progress.last, progress.total);
  EXPECT_TRUE(progress.ended);
}

// ---- Errors -----------------------------------------------------------------------------------

// Reads `bytes` as file `name` and returns the FormatError (failing the test if there is none).
FormatError errorFor(const std::string& bytes, const std::string& name = "bad.ply") {
  auto path = test::scratchDir() / name;
  test::writeFile(path, bytes);
  test::NullSink sink;
  try {
    readPly(path, sink);
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    return e;
  }
  ADD_FAILURE() << "no error for " << name;
  return FormatError(name, "none");
}

const std::string kTriangleHeader =
    "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n";

TEST(PlyReader, IndexOutOfRangeNamesLineOrByte) {
  auto e = errorFor("ply\nformat ascii 1.0\n" + kTriangleHeader + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  EXPECT_EQ(e.where(), FormatError::Where::Line);
  EXPECT_EQ(e.position(), 13u);
  EXPECT_NE(e.reason().find("index 3 is out of range"), std::string::npos) << e.what();

  std::string header = "ply\nformat binary_little_endian 1.0\n" + kTriangleHeader;
  std::string binary = toBinary(
      "ply\nformat ascii 1.0\n" + kTriangleHeader + "0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", false);
  e = errorFor(binary);
  EXPECT_EQ(e.where(), FormatError::Where::Byte);
  EXPECT_EQ(e.position(), header.size() + 36 + 1 + 4);  // the second index of the face
  EXPECT_NE(e.reason().find("index -1 is out of range"), std::string::npos) << e.what();
  // A quad leaves the fast triangle path for the general one (here in a big-endian file).
  std::string ascii_general =
      "ply\nformat ascii 1.0\n" + kTriangleHeader + "0 0 0\n1 0 0\n0 1 0\n4 0 1 2 7\n";
  e = errorFor(toBinary(ascii_general, true));
  EXPECT_EQ(e.position(), header.size() - 3 + 36 + 1 + 12);  // "big" is 3 bytes shorter
  EXPECT_NE(e.reason().find("index 7"), std::string::npos) << e.what();
}

TEST(PlyReader, BadHeadersNameTheLine) {
  auto e = errorFor("ply\nformat ascii 2.0\nend_header\n");
  EXPECT_EQ(e.where(), FormatError::Where::Line);
  EXPECT_EQ(e.position(), 2u);
  EXPECT_NE(e.reason().find("version"), std::string::npos);

  e = errorFor("ply\nformat ascii 1.0\nelement vertex 1\nproperty float32 x\nproperty quad y\n");
  EXPECT_EQ(e.position(), 5u);
  EXPECT_NE(e.reason().find("unknown property type 'quad'"), std::string::npos) << e.what();

  // 2^64 + 8 wrapped to a count of 8 once: now refused on its line.
  e = errorFor("ply\nformat ascii 1.0\nelement vertex 18446744073709551624\nproperty float x\n"
               "property float y\nproperty float z\nend_header\n0 0 0\n");
  EXPECT_EQ(e.position(), 3u) << e.what();
  EXPECT_NE(e.reason().find("bad element declaration"), std::string::npos) << e.what();

  e = errorFor("PLY?\n");
  EXPECT_EQ(e.position(), 1u);
  EXPECT_NE(e.reason().find("not a PLY file"), std::string::npos);

  e = errorFor("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n");
  EXPECT_NE(e.reason().find("end_header"), std::string::npos);

  e = errorFor(
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "end_header\n1 2\n");
  EXPECT_EQ(e.position(), 3u);
  EXPECT_NE(e.reason().find("lacks x, y or z"), std::string::npos);

  e = errorFor("ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\n" +
               kTriangleHeader.substr(0, kTriangleHeader.find("element face")) +
               "end_header\n3 0 1 2\n0 0 0\n1 0 0\n0 1 0\n");
  EXPECT_EQ(e.position(), 3u);
  EXPECT_NE(e.reason().find("comes before the 'vertex' element"), std::string::npos) << e.what();
}

TEST(PlyReader, TruncatedVertexDataIsReported) {
  std::string full = toBinary(
      "ply\nformat ascii 1.0\n" + kTriangleHeader + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", false);
  auto e = errorFor(full.substr(0, full.size() - 20));  // cut inside the vertices
  EXPECT_NE(e.reason().find("truncated"), std::string::npos) << e.what();
  EXPECT_EQ(e.where(), FormatError::Where::Line);
  EXPECT_EQ(e.position(), 3u);  // the vertex element's declaration

  // ASCII: the count fits the bytes but the records run out.
  e = errorFor("ply\nformat ascii 1.0\n" + kTriangleHeader + "0 0 0\n1 0 0\n0 1 0 3 0 1 2\n\n\n\n");
  EXPECT_EQ(e.where(), FormatError::Where::Line);
  EXPECT_EQ(e.position(), 12u);
  EXPECT_NE(e.reason().find("extra values"), std::string::npos) << e.what();
}

TEST(PlyReader, NonFinitePositionIsRejected) {
  std::string file =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n";
  size_t at = file.size();
  float v[3] = {0.0f, std::nanf(""), 1.0f};
  file.append(reinterpret_cast<const char*>(v), 12);
  auto e = errorFor(file);
  EXPECT_EQ(e.position(), at);
  EXPECT_NE(e.reason().find("non-finite"), std::string::npos);
}

TEST(PlyReader, HostileCountFailsAtOnceWithoutAllocating) {
  for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    auto start = std::chrono::steady_clock::now();
    auto e = errorFor(std::string("ply\nformat ") + format +
                      " 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\n"
                      "property float z\nend_header\n0 0 0\n");
    auto elapsed = std::chrono::steady_clock::now() - start;
    EXPECT_LT(elapsed, std::chrono::milliseconds(500)) << format;
    EXPECT_EQ(e.position(), 3u);
    EXPECT_NE(e.reason().find("4000000000"), std::string::npos) << e.what();
  }
  // A list count that claims more items than the file holds.
  std::string file =
      "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\n"
      "property list uint int vertex_indices\nend_header\n";
  size_t at = file.size();
  uint32_t count = 1u << 30;
  file.append(reinterpret_cast<const char*>(&count), 4);
  auto e = errorFor(file);
  EXPECT_EQ(e.position(), at);
  EXPECT_NE(e.reason().find("runs past the end"), std::string::npos) << e.what();
}

TEST(PlyReader, DamagedFixturesGiveCleanErrors) {
  for (const char* name : {"poly_ascii.ply", "poly_le.ply", "poly_be.ply", "tri_ascii.ply",
                           "tri_le.ply", "tri_be.ply"}) {
    std::string bytes = test::readFile(fixture(name));
    ASSERT_FALSE(bytes.empty()) << name;
    int rejected = test::expectRobustToDamage(
        bytes, name, [](const fs::path& p, SceneSink& s) { readPly(p, s); });
    EXPECT_GT(rejected, static_cast<int>(bytes.size() / 2)) << name;
  }
}

// ---- Writer -------------------------------------------------------------------------------------

TEST(PlyWriter, MeshRoundTripInWorldCoordinatesWithColours) {
  auto dir = test::scratchDir();
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 2, 0}, {0, 2, 3}};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  SceneObject a;
  a.info.name = "a";
  a.info.layer = 1;
  a.info.transform.origin = {1000.0, -2000.0, 5.0};
  a.info.transform.linear = glm::mat3(0, 1, 0, -1, 0, 0, 0, 0, 1);  // 90 degrees about +Z
  a.geometry = mesh;
  SceneObject b;
  b.info.name = "b";
  b.info.color_rgba = 0xff0000ffu;  // red
  b.geometry = mesh;
  {
    PlyWriter writer(dir / "out.ply", kDefaultChordalTolerance);
    writer.onLayer(0, {"zero", 0xff00ff00u});
    writer.onLayer(1, {"one", 0xffff0000u});
    writer.onObject(a);
    writer.onObject(b);
    EXPECT_EQ(writer.vertexCount(), 8u);
    EXPECT_EQ(writer.triangleCount(), 4u);
    EXPECT_FALSE(fs::exists(dir / "out.ply"));
    writer.finish();
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
  auto got = corners(read(dir / "out.ply"));
  ASSERT_EQ(got.size(), 12u);
  for (size_t k = 0; k < 12; ++k) {
    const SceneObject& o = k < 6 ? a : b;
    glm::vec3 expected = glm::vec3(o.info.transform.apply(mesh.positions[mesh.indices[k % 6]]));
    EXPECT_EQ(got[k].position, expected) << k;
    EXPECT_EQ(got[k].color, k < 6 ? 0xffff0000u : 0xff0000ffu) << k;  // layer 1's, then b's own
  }
  // The header is plain PLY with exact counts.
  std::string bytes = test::readFile(dir / "out.ply");
  EXPECT_EQ(bytes.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
  EXPECT_NE(bytes.find("\nelement vertex 8\n"), std::string::npos);
  EXPECT_NE(bytes.find("\nelement face 4\n"), std::string::npos);
  EXPECT_EQ(bytes.size(), bytes.find("end_header\n") + 11 + 8 * 15 + 4 * 13);
}

TEST(PlyWriter, PrimitiveIsTessellated) {
  auto path = test::scratchDir() / "cylinder.ply";
  SceneObject object;
  object.info.transform.origin = {10.0, 0.0, 0.0};
  object.geometry = Primitive{Cylinder{0.05f, 2.0f, true}};
  {
    PlyWriter writer(path, kDefaultChordalTolerance);
    writer.onLayer(0, {"default", 0xff123456u});
    writer.onObject(object);
    writer.finish();
  }
  auto sink = read(path);
  uint64_t expected = triangleCount(object.geometry, kDefaultChordalTolerance);
  EXPECT_GT(expected, 0u);
  EXPECT_EQ(sink.triangles(), expected);
  for (const Corner& c : corners(sink)) {
    EXPECT_NEAR(c.position.x, 10.0f, 0.051f);
    EXPECT_GE(c.position.z, -1e-6f);
    EXPECT_EQ(c.color, 0xff123456u);
  }
}

TEST(PlyWriter, WithoutFinishLeavesNoFiles) {
  auto dir = test::scratchDir();
  {
    PlyWriter writer(dir / "never.ply", kDefaultChordalTolerance);
    SceneObject object;
    TriangleMesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    mesh.indices = {0, 1, 2};
    object.geometry = mesh;
    writer.onObject(object);
  }
  EXPECT_TRUE(fs::is_empty(dir));
}

// A full disk, imitated by a file-size limit (EFBIG instead of ENOSPC; the same write path).
TEST(PlyWriter, WriteFailureThrowsNamingTheFileAndCleansUp) {
  auto dir = test::scratchDir();
  rlimit old_limit{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  TriangleMesh mesh;
  for (int i = 0; i < 3000; ++i) {
    mesh.positions.push_back({float(i), 0.0f, 0.0f});
    mesh.indices.insert(mesh.indices.end(), {0u, 1u, uint32_t(i)});
  }
  SceneObject object;
  object.geometry = mesh;
  std::string message;
  {
    PlyWriter writer(dir / "full.ply", kDefaultChordalTolerance);
    rlimit small = old_limit;
    small.rlim_cur = 16 * 1024;
    setrlimit(RLIMIT_FSIZE, &small);
    try {
      writer.onObject(object);  // 45 KB of vertices
      writer.onObject(object);
      writer.finish();
    } catch (const std::runtime_error& e) {
      message = e.what();
    }
    setrlimit(RLIMIT_FSIZE, &old_limit);
  }
  std::signal(SIGXFSZ, old_handler);
  EXPECT_NE(message.find("full.ply"), std::string::npos) << message;
  EXPECT_NE(message.find("cannot write"), std::string::npos) << message;
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(PlyWriter, UnwritableDestinationThrowsNamingTheFile) {
  auto path = test::scratchDir() / "missing-dir" / "x.ply";
  try {
    PlyWriter writer(path, kDefaultChordalTolerance);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("x.ply"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tw
