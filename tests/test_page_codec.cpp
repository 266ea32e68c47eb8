// Tests for the cluster codec and page compression: round trips within the documented
// quantization and normal errors, exact ids and triangles, and a decoder that rejects every
// truncation and survives random corruption (run under ASan/UBSan too).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "page_codec.h"

namespace tw {
namespace {

struct Mesh {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;
  std::vector<uint32_t> indices;
  std::vector<uint32_t> objects;  // per triangle

  ClusterGeometryInput input() const { return {positions, normals, indices, objects}; }
};

// A bumpy n x n grid patch of size `size_m` at `offset`, triangles split between `object_count`
// objects in interleaved stripes (so the encoder has to sort them into runs).
Mesh makePatch(int n, float size_m, glm::vec3 offset, uint32_t object_count) {
  Mesh m;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) {
      float u = float(x) / n, v = float(y) / n;
      float h = 0.1f * size_m * std::sin(6.0f * u) * std::cos(5.0f * v);
      m.positions.push_back(offset + glm::vec3(u * size_m, v * size_m, h));
      glm::vec3 du(1.0f, 0.0f, 0.6f * std::cos(6.0f * u) * std::cos(5.0f * v));
      glm::vec3 dv(0.0f, 1.0f, -0.5f * std::sin(6.0f * u) * std::sin(5.0f * v));
      m.normals.push_back(glm::normalize(glm::cross(du, dv)));
    }
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      uint32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
      uint32_t object = 7 + uint32_t(x % object_count) * 3;
      m.objects.insert(m.objects.end(), {object, object});
    }
  return m;
}

using TriangleKey = std::tuple<uint32_t, uint32_t, uint32_t, uint32_t>;  // object, rotated abc

TriangleKey key(uint32_t object, uint32_t a, uint32_t b, uint32_t c) {
  // Rotate so the smallest index comes first, keeping the winding.
  if (b < a && b < c) return {object, b, c, a};
  if (c < a && c < b) return {object, c, a, b};
  return {object, a, b, c};
}

// Checks `decoded` against `mesh` up to vertex and triangle order; returns the largest position
// error and the smallest normal dot product.
void expectSameCluster(const Mesh& mesh, const DecodedCluster& decoded, double max_error_m,
                       float* min_normal_dot = nullptr) {
  ASSERT_EQ(decoded.indices.size(), mesh.indices.size());
  ASSERT_EQ(decoded.triangle_objects.size(), mesh.objects.size());
  ASSERT_EQ(decoded.positions.size(), decoded.vertices.size());
  // Grid vertices are far apart compared with the error, so the nearest original is the source.
  std::vector<uint32_t> source(decoded.positions.size());
  float dot_min = 1.0f;
  for (size_t v = 0; v < decoded.positions.size(); ++v) {
    double best = 1e30;
    for (size_t o = 0; o < mesh.positions.size(); ++o) {
      double d = glm::length(glm::dvec3(decoded.positions[v]) - glm::dvec3(mesh.positions[o]));
      if (d < best) {
        best = d;
        source[v] = static_cast<uint32_t>(o);
      }
    }
    EXPECT_LE(best, max_error_m) << "vertex " << v;
    if (!mesh.normals.empty()) {
      ASSERT_EQ(decoded.normals.size(), decoded.positions.size());
      dot_min = std::min(dot_min, glm::dot(decoded.normals[v], mesh.normals[source[v]]));
    }
  }
  if (min_normal_dot) *min_normal_dot = dot_min;
  std::vector<TriangleKey> expected, actual;
  for (size_t t = 0; t < mesh.objects.size(); ++t) {
    expected.push_back(key(mesh.objects[t], mesh.indices[t * 3], mesh.indices[t * 3 + 1],
                           mesh.indices[t * 3 + 2]));
    actual.push_back(key(decoded.triangle_objects[t], source[decoded.indices[t * 3]],
                         source[decoded.indices[t * 3 + 1]], source[decoded.indices[t * 3 + 2]]));
  }
  std::sort(expected.begin(), expected.end());
  std::sort(actual.begin(), actual.end());
  EXPECT_EQ(expected, actual);
}

TEST(PageCodec, RoundTripWithinQuantizationAndNormalError) {
  Mesh mesh = makePatch(9, 0.5f, glm::vec3(3.0f, -2.0f, 1.0f), 3);
  for (bool optimize : {true, false}) {
    std::vector<uint8_t> blob;
    ClusterEncodeOptions options;
    options.optimize = optimize;
    EncodedClusterInfo info = encodeCluster(mesh.input(), options, blob);
    EXPECT_EQ(info.encoded_bytes, blob.size());
    EXPECT_EQ(info.triangle_count, mesh.objects.size());
    EXPECT_EQ(info.vertex_count, mesh.positions.size());
    EXPECT_EQ(info.object_min, 7u);
    EXPECT_EQ(info.object_max, 13u);
    EXPECT_EQ(info.object_runs, 3u);

    DecodedCluster decoded;
    DecodeStatus status = decodeCluster(blob, options.position_step_m, 100, decoded);
    ASSERT_TRUE(status.ok()) << status.error;
    EXPECT_EQ(decoded.shift, info.shift);
    float min_dot = 0.0f;
    expectSameCluster(mesh, decoded, quantizationErrorM(options.position_step_m, info.shift),
                      &min_dot);
    EXPECT_GE(min_dot, std::cos(glm::radians(1.5f)));  // snorm8 octahedral
    // Triangles come out sorted by object, as the id runs require.
    EXPECT_TRUE(std::is_sorted(decoded.triangle_objects.begin(), decoded.triangle_objects.end()));
    // The record bounds cover every decoded position.
    for (const glm::vec3& p : decoded.positions) {
      EXPECT_TRUE(glm::all(glm::greaterThanEqual(p, info.aabb_min)));
      EXPECT_TRUE(glm::all(glm::lessThanEqual(p, info.aabb_max)));
      EXPECT_LE(glm::length(p - info.center), info.radius);
    }
  }
}

TEST(PageCodec, LargeOrFarClustersUseCoarserCellsWithinTheRecordedError) {
  // 200 m wide at 1.5 km from the origin: 200 m / 15 um does not fit 16 bits, so shift > 0.
  Mesh mesh = makePatch(6, 200.0f, glm::vec3(1500.0f, -800.0f, 40.0f), 1);
  mesh.normals.clear();
  std::vector<uint8_t> blob;
  ClusterEncodeOptions options;
  EncodedClusterInfo info = encodeCluster(mesh.input(), options, blob);
  EXPECT_GT(info.shift, 0u);
  EXPECT_LE(200.0 / info.cell_m, 65535.0 * 1.01);
  DecodedCluster decoded;
  ASSERT_TRUE(decodeCluster(blob, options.position_step_m, 8, decoded).ok());
  EXPECT_TRUE(decoded.normals.empty());
  expectSameCluster(mesh, decoded, quantizationErrorM(options.position_step_m, info.shift));
  // The error bound is tight enough to matter: half a cell diagonal, not more.
  EXPECT_LT(quantizationErrorM(options.position_step_m, info.shift), info.cell_m);
}

TEST(PageCodec, SharedBorderVerticesQuantizeIdentically) {
  // Two clusters at the same shift sharing an edge must decode the edge to identical floats.
  Mesh left = makePatch(4, 0.3f, glm::vec3(10.1f, 0.0f, 0.0f), 1);
  Mesh right = makePatch(4, 0.3f, glm::vec3(10.4f, 0.0f, 0.0f), 1);
  for (int y = 0; y <= 4; ++y) right.positions[y * 5] = left.positions[y * 5 + 4];
  std::vector<uint8_t> a, b;
  EncodedClusterInfo ia = encodeCluster(left.input(), {}, a);
  EncodedClusterInfo ib = encodeCluster(right.input(), {}, b);
  ASSERT_EQ(ia.shift, ib.shift);
  DecodedCluster da, db;
  ASSERT_TRUE(decodeCluster(a, pkg::kDefaultPositionStepM, 8, da).ok());
  ASSERT_TRUE(decodeCluster(b, pkg::kDefaultPositionStepM, 8, db).ok());
  int shared = 0;
  for (const glm::vec3& p : da.positions)
    for (const glm::vec3& q : db.positions)
      if (glm::length(p - q) < 1e-4f) {
        EXPECT_EQ(p, q);
        ++shared;
      }
  EXPECT_EQ(shared, 5);

  // A forced coarser shift still decodes within its (larger) error.
  std::vector<uint8_t> c;
  ClusterEncodeOptions coarse;
  coarse.min_shift = ia.shift + 3;
  EncodedClusterInfo ic = encodeCluster(left.input(), coarse, c);
  EXPECT_EQ(ic.shift, ia.shift + 3);
  DecodedCluster dc;
  ASSERT_TRUE(decodeCluster(c, pkg::kDefaultPositionStepM, 8, dc).ok());
  expectSameCluster(left, dc, quantizationErrorM(pkg::kDefaultPositionStepM, ic.shift));
}

TEST(PageCodec, OctahedralErrorIsBounded) {
  std::mt19937 rng(7);
  std::normal_distribution<float> gauss;
  float min_dot = 1.0f;
  for (int i = 0; i < 20000; ++i) {
    glm::vec3 n = glm::normalize(glm::vec3(gauss(rng), gauss(rng), gauss(rng)));
    int8_t oct[2];
    encodeOctahedral(n, oct);
    min_dot = std::min(min_dot, glm::dot(n, decodeOctahedral(oct)));
  }
  EXPECT_GE(min_dot, std::cos(glm::radians(1.5f)));
  for (glm::vec3 axis :
       {glm::vec3(0, 0, 1), glm::vec3(0, 0, -1), glm::vec3(1, 0, 0), glm::vec3(0, -1, 0)}) {
    int8_t oct[2];
    encodeOctahedral(axis, oct);
    EXPECT_GT(glm::dot(axis, decodeOctahedral(oct)), 0.9999f);
  }
}

TEST(PageCodec, EncoderRejectsBadInput) {
  Mesh mesh = makePatch(2, 1.0f, glm::vec3(0.0f), 1);
  std::vector<uint8_t> blob;
  Mesh bad = mesh;
  bad.indices[4] = 99;
  EXPECT_THROW(encodeCluster(bad.input(), {}, blob), std::invalid_argument);
  bad = mesh;
  bad.positions[1].y = std::nanf("");
  EXPECT_THROW(encodeCluster(bad.input(), {}, blob), std::invalid_argument);
  bad = mesh;
  bad.objects.pop_back();
  EXPECT_THROW(encodeCluster(bad.input(), {}, blob), std::invalid_argument);
  bad = mesh;
  bad.normals.pop_back();
  EXPECT_THROW(encodeCluster(bad.input(), {}, blob), std::invalid_argument);
  bad = mesh;
  bad.indices.clear();
  bad.objects.clear();
  EXPECT_THROW(encodeCluster(bad.input(), {}, blob), std::invalid_argument);
  bad = mesh;
  bad.positions[0] = glm::vec3(1e30f);  // beyond the int32 grid at any shift
  EXPECT_THROW(encodeCluster(bad.input(), {}, blob), std::invalid_argument);
  EXPECT_TRUE(blob.empty());
}

TEST(PageCodec, DecoderChecksObjectLimitAndHeader) {
  Mesh mesh = makePatch(3, 1.0f, glm::vec3(0.0f), 2);
  std::vector<uint8_t> blob;
  encodeCluster(mesh.input(), {}, blob);
  DecodedCluster decoded;
  EXPECT_TRUE(decodeCluster(blob, pkg::kDefaultPositionStepM, 11, decoded).ok());
  DecodeStatus status = decodeCluster(blob, pkg::kDefaultPositionStepM, 10, decoded);
  ASSERT_FALSE(status.ok());
  EXPECT_STREQ(status.error, "object index out of range");
  std::vector<uint8_t> bad = blob;
  bad[0] ^= 1;
  status = decodeCluster(bad, pkg::kDefaultPositionStepM, 11, decoded);
  EXPECT_STREQ(status.error, "encoded cluster has a bad magic number");
  EXPECT_EQ(status.offset, 0u);
}

TEST(PageCodec, DecoderRejectsEveryTruncationAndSurvivesCorruption) {
  Mesh mesh = makePatch(5, 1.0f, glm::vec3(0.25f), 2);
  std::vector<uint8_t> blob;
  encodeCluster(mesh.input(), {}, blob);
  DecodedCluster decoded;
  for (size_t cut = 0; cut < blob.size(); ++cut) {
    std::vector<uint8_t> part(blob.begin(), blob.begin() + cut);  // own buffer: ASan sees overreads
    EXPECT_FALSE(decodeCluster(part, pkg::kDefaultPositionStepM, 20, decoded).ok()) << cut;
  }
  std::mt19937 rng(99);
  int rejected = 0;
  const int kRuns = 3000;
  for (int i = 0; i < kRuns; ++i) {
    std::vector<uint8_t> bytes = blob;
    int hits = 1 + int(rng() % 4);
    for (int h = 0; h < hits; ++h) bytes[rng() % bytes.size()] = uint8_t(rng());
    DecodeStatus status = decodeCluster(bytes, pkg::kDefaultPositionStepM, 20, decoded);
    if (!status.ok()) {
      ++rejected;
      EXPECT_LE(status.offset, bytes.size());
    } else {
      // Whatever decodes must still be internally consistent.
      for (uint32_t index : decoded.indices) ASSERT_LT(index, decoded.positions.size());
      for (uint32_t object : decoded.triangle_objects) ASSERT_LT(object, 20u);
    }
  }
  EXPECT_GT(rejected, kRuns / 4);
}

TEST(PageCodec, PageCompressionRoundTripAndDamage) {
  std::vector<uint8_t> raw;
  for (int c = 0; c < 6; ++c) {
    Mesh mesh = makePatch(8, 0.2f, glm::vec3(0.2f * c, 0.0f, 0.0f), 1);
    raw.resize(pkg::alignUp(raw.size(), pkg::kClusterAlignment), 0);
    encodeCluster(mesh.input(), {}, raw);
  }
  std::vector<uint8_t> stored;
  size_t n = compressPage(raw, 9, stored);
  EXPECT_EQ(n, stored.size());
  std::vector<uint8_t> back;
  ASSERT_EQ(decompressPage(stored, static_cast<uint32_t>(raw.size()), back), nullptr);
  EXPECT_EQ(back, raw);
  EXPECT_NE(decompressPage(stored, static_cast<uint32_t>(raw.size()) + 1, back), nullptr);
  EXPECT_NE(decompressPage(stored, pkg::kMaxPageRawBytes + 1, back), nullptr);
  for (size_t cut = 0; cut < stored.size(); ++cut) {
    std::vector<uint8_t> part(stored.begin(), stored.begin() + cut);
    EXPECT_NE(decompressPage(part, static_cast<uint32_t>(raw.size()), back), nullptr) << cut;
  }
  std::mt19937 rng(5);
  for (int i = 0; i < 500; ++i) {
    std::vector<uint8_t> bytes = stored;
    bytes[rng() % bytes.size()] = uint8_t(rng());
    decompressPage(bytes, static_cast<uint32_t>(raw.size()), back);  // must not crash
  }
}

}  // namespace
}  // namespace tw
