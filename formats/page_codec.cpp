// Cluster encoder/decoder and page compression (see page_codec.h and docs/package-format.md).
#include "page_codec.h"

#include <meshoptimizer.h>
#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <string>

namespace tw {
namespace {

using pkg::EncodedClusterHeader;
using pkg::EncodedVertex;

constexpr uint32_t align4(uint32_t v) { return (v + 3u) & ~3u; }

uint32_t objectStreamBytes(uint32_t runs) { return align4(runs * 6u); }

// The index codec's format version 1 (decodable by meshoptimizer 0.14+) is noticeably smaller
// than 0; the setting is global, so it is set once and never changed.
void useIndexCodecVersion1() {
  static std::once_flag once;
  std::call_once(once, [] { meshopt_encodeIndexVersion(1); });
}

// The one dequantization formula, shared by the encoder (for bounds) and the decoder.
inline float dequantize(int32_t origin, uint16_t q, double cell_m) {
  return static_cast<float>((static_cast<double>(origin) + static_cast<double>(q)) * cell_m);
}

[[noreturn]] void badInput(const std::string& reason) {
  throw std::invalid_argument("encodeCluster: " + reason);
}

}  // namespace

double quantizationErrorM(double position_step_m, uint32_t shift) {
  double cell = std::ldexp(position_step_m, static_cast<int>(shift));
  // Half a cell per axis, plus a float ulp-scale allowance for the final float conversion.
  return 0.5 * cell * std::sqrt(3.0) + 1e-7 * cell;
}

void encodeOctahedral(const glm::vec3& normal, int8_t out[2]) {
  float sum = std::abs(normal.x) + std::abs(normal.y) + std::abs(normal.z);
  if (!(sum > 1e-20f) || !std::isfinite(sum)) {
    out[0] = out[1] = 0;
    return;
  }
  float x = normal.x / sum, y = normal.y / sum;
  if (normal.z < 0.0f) {
    float fx = (1.0f - std::abs(y)) * (x >= 0.0f ? 1.0f : -1.0f);
    float fy = (1.0f - std::abs(x)) * (y >= 0.0f ? 1.0f : -1.0f);
    x = fx;
    y = fy;
  }
  out[0] = static_cast<int8_t>(std::lround(std::clamp(x, -1.0f, 1.0f) * 127.0f));
  out[1] = static_cast<int8_t>(std::lround(std::clamp(y, -1.0f, 1.0f) * 127.0f));
}

glm::vec3 decodeOctahedral(const int8_t oct[2]) {
  float x = std::max(static_cast<float>(oct[0]) / 127.0f, -1.0f);
  float y = std::max(static_cast<float>(oct[1]) / 127.0f, -1.0f);
  float z = 1.0f - std::abs(x) - std::abs(y);
  if (z < 0.0f) {
    float fx = (1.0f - std::abs(y)) * (x >= 0.0f ? 1.0f : -1.0f);
    float fy = (1.0f - std::abs(x)) * (y >= 0.0f ? 1.0f : -1.0f);
    x = fx;
    y = fy;
  }
  return glm::normalize(glm::vec3(x, y, z));
}

EncodedClusterInfo encodeCluster(const ClusterGeometryInput& input,
                                 const ClusterEncodeOptions& options, std::vector<uint8_t>& out) {
  const size_t vertex_count = input.positions.size();
  const size_t index_count = input.indices.size();
  const size_t triangle_count = index_count / 3;
  if (!(options.position_step_m >= pkg::kMinPositionStepM &&
        options.position_step_m <= pkg::kMaxPositionStepM))
    badInput("position step is outside [1e-9, 1] m");
  if (index_count % 3 != 0) badInput("index count is not a multiple of 3");
  if (triangle_count == 0) badInput("cluster has no triangles");
  if (triangle_count > pkg::kMaxClusterTriangles) badInput("too many triangles in a cluster");
  if (vertex_count > pkg::kMaxClusterVertices) badInput("too many vertices in a cluster");
  if (input.triangle_objects.size() != triangle_count)
    badInput("triangle_objects needs one entry per triangle");
  const bool has_normals = !input.normals.empty();
  if (has_normals && input.normals.size() != vertex_count)
    badInput("normals must be empty or one per position");
  for (uint32_t index : input.indices)
    if (index >= vertex_count) badInput("index out of range");

  // Smallest shift whose cells fit the cluster's extent in 16 bits.
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::numeric_limits<double>::max();
    hi[a] = -std::numeric_limits<double>::max();
  }
  for (const glm::vec3& p : input.positions)
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite(p[a])) badInput("position is not finite");
      lo[a] = std::min(lo[a], static_cast<double>(p[a]));
      hi[a] = std::max(hi[a], static_cast<double>(p[a]));
    }
  uint32_t shift = options.min_shift;
  double cell = options.position_step_m;
  int64_t grid_lo[3] = {};
  for (;; ++shift) {
    if (shift > pkg::kMaxPositionShift) badInput("cluster extent too large for the position grid");
    cell = std::ldexp(options.position_step_m, static_cast<int>(shift));
    bool fits = true;
    for (int a = 0; a < 3 && fits; ++a) {
      double glo = std::nearbyint(lo[a] / cell), ghi = std::nearbyint(hi[a] / cell);
      if (glo < -2147483648.0 || glo > 2147483647.0 || ghi - glo > 65535.0)
        fits = false;
      else
        grid_lo[a] = static_cast<int64_t>(glo);
    }
    if (fits) break;
  }

  // Quantize (nearbyint is monotone, so every vertex lands in [grid_lo, grid_lo + 65535]).
  std::vector<EncodedVertex> vertices(vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) {
    EncodedVertex& e = vertices[v];
    for (int a = 0; a < 3; ++a) {
      double g = std::nearbyint(static_cast<double>(input.positions[v][a]) / cell);
      e.q[a] = static_cast<uint16_t>(
          std::clamp<int64_t>(static_cast<int64_t>(g) - grid_lo[a], 0, 65535));
    }
    if (has_normals)
      encodeOctahedral(input.normals[v], e.oct);
    else
      e.oct[0] = e.oct[1] = 0;
  }

  // Sort triangles by object (stable), so ids become runs; then optimise each run for the
  // vertex cache. Runs rarely split a cluster much, so the cache loss is small.
  std::vector<uint32_t> order(triangle_count);
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return input.triangle_objects[a] < input.triangle_objects[b];
  });
  std::vector<uint32_t> sorted(index_count);
  std::vector<uint32_t> run_objects;
  std::vector<uint16_t> run_lengths;
  for (size_t t = 0; t < triangle_count; ++t) {
    for (int k = 0; k < 3; ++k) sorted[t * 3 + k] = input.indices[order[t] * 3 + k];
    uint32_t object = input.triangle_objects[order[t]];
    if (run_objects.empty() || run_objects.back() != object) {
      run_objects.push_back(object);
      run_lengths.push_back(0);
    }
    ++run_lengths.back();
  }
  std::vector<uint32_t> indices(index_count);
  std::vector<EncodedVertex> fetched;
  size_t used_vertices = vertex_count;
  if (options.optimize) {
    size_t first = 0;
    for (uint16_t length : run_lengths) {
      meshopt_optimizeVertexCache(indices.data() + first * 3, sorted.data() + first * 3,
                                  size_t{length} * 3, vertex_count);
      first += length;
    }
    fetched.resize(vertex_count);
    used_vertices =
        meshopt_optimizeVertexFetch(fetched.data(), indices.data(), index_count, vertices.data(),
                                    vertex_count, sizeof(EncodedVertex));
    fetched.resize(used_vertices);
    vertices.swap(fetched);
  } else {
    indices = sorted;
  }

  // Streams.
  useIndexCodecVersion1();
  std::vector<uint8_t> vstream(
      meshopt_encodeVertexBufferBound(used_vertices, sizeof(EncodedVertex)));
  vstream.resize(meshopt_encodeVertexBuffer(vstream.data(), vstream.size(), vertices.data(),
                                            used_vertices, sizeof(EncodedVertex)));
  std::vector<uint8_t> istream(meshopt_encodeIndexBufferBound(index_count, used_vertices));
  istream.resize(
      meshopt_encodeIndexBuffer(istream.data(), istream.size(), indices.data(), index_count));
  if (vstream.empty() || istream.empty()) badInput("meshopt encoder failed");
  const uint32_t runs = static_cast<uint32_t>(run_objects.size());

  EncodedClusterHeader header{};
  header.magic = pkg::kEncodedClusterMagic;
  header.vertex_count = static_cast<uint16_t>(used_vertices);
  header.triangle_count = static_cast<uint16_t>(triangle_count);
  header.flags = has_normals ? pkg::kEncodedHasNormals : 0;
  header.shift = static_cast<uint8_t>(shift);
  header.run_count = static_cast<uint16_t>(runs);
  for (int a = 0; a < 3; ++a) header.grid_origin[a] = static_cast<int32_t>(grid_lo[a]);
  header.vertex_stream_bytes = static_cast<uint32_t>(vstream.size());
  header.index_stream_bytes = static_cast<uint32_t>(istream.size());
  header.object_stream_bytes = objectStreamBytes(runs);

  const size_t start = out.size();
  const size_t total =
      sizeof(header) + vstream.size() + istream.size() + header.object_stream_bytes;
  out.resize(start + total, 0);
  uint8_t* dst = out.data() + start;
  std::memcpy(dst, &header, sizeof(header));
  dst += sizeof(header);
  std::memcpy(dst, vstream.data(), vstream.size());
  dst += vstream.size();
  std::memcpy(dst, istream.data(), istream.size());
  dst += istream.size();
  std::memcpy(dst, run_objects.data(), runs * 4u);
  std::memcpy(dst + runs * 4u, run_lengths.data(), runs * 2u);

  EncodedClusterInfo info;
  info.encoded_bytes = static_cast<uint32_t>(total);
  info.vertex_count = static_cast<uint32_t>(used_vertices);
  info.triangle_count = static_cast<uint32_t>(triangle_count);
  info.shift = shift;
  info.cell_m = cell;
  info.object_min = run_objects.front();
  info.object_max = run_objects.back();
  info.object_runs = runs;
  // Bounds of what the decoder will produce, so they are conservative for the rendered geometry.
  glm::vec3 bmin(std::numeric_limits<float>::max()), bmax(-std::numeric_limits<float>::max());
  for (const EncodedVertex& e : vertices) {
    glm::vec3 p;
    for (int a = 0; a < 3; ++a) p[a] = dequantize(header.grid_origin[a], e.q[a], cell);
    bmin = glm::min(bmin, p);
    bmax = glm::max(bmax, p);
  }
  info.aabb_min = bmin;
  info.aabb_max = bmax;
  glm::dvec3 center = (glm::dvec3(bmin) + glm::dvec3(bmax)) * 0.5;
  double radius = 0.0;
  for (const EncodedVertex& e : vertices) {
    glm::dvec3 p;
    for (int a = 0; a < 3; ++a) p[a] = dequantize(header.grid_origin[a], e.q[a], cell);
    radius = std::max(radius, glm::length(p - center));
  }
  info.center = glm::vec3(center);
  // The float centre moved by at most half an ulp per axis; widen the radius to cover that.
  double slack = glm::length(glm::dvec3(info.center) - center);
  info.radius =
      std::nextafter(static_cast<float>(radius + slack), std::numeric_limits<float>::infinity());
  return info;
}

DecodeStatus decodeCluster(std::span<const uint8_t> blob, double position_step_m,
                           uint32_t object_limit, DecodedCluster& out) {
  auto fail = [](const char* reason, uint64_t offset) { return DecodeStatus{reason, offset}; };
  if (blob.size() < sizeof(EncodedClusterHeader))
    return fail("encoded cluster header is truncated", blob.size());
  EncodedClusterHeader h;
  std::memcpy(&h, blob.data(), sizeof(h));
  if (h.magic != pkg::kEncodedClusterMagic)
    return fail("encoded cluster has a bad magic number", offsetof(EncodedClusterHeader, magic));
  if (h.flags & ~pkg::kEncodedHasNormals)
    return fail("encoded cluster has unknown flags", offsetof(EncodedClusterHeader, flags));
  if (h.shift > pkg::kMaxPositionShift)
    return fail("encoded cluster position shift is too large",
                offsetof(EncodedClusterHeader, shift));
  if (h.reserved[0] | h.reserved[1] | h.reserved[2])
    return fail("encoded cluster reserved fields are not zero",
                offsetof(EncodedClusterHeader, reserved));
  if (h.triangle_count == 0 || h.vertex_count == 0)
    return fail("encoded cluster is empty", offsetof(EncodedClusterHeader, vertex_count));
  if (h.run_count == 0 || h.run_count > h.triangle_count)
    return fail("encoded cluster object run count is out of range",
                offsetof(EncodedClusterHeader, run_count));
  if (h.object_stream_bytes != objectStreamBytes(h.run_count))
    return fail("encoded cluster object stream size does not match its run count",
                offsetof(EncodedClusterHeader, object_stream_bytes));
  if (!(position_step_m >= pkg::kMinPositionStepM && position_step_m <= pkg::kMaxPositionStepM))
    return fail("package position step is out of range", 0);
  const uint64_t vstart = sizeof(EncodedClusterHeader);
  const uint64_t istart = vstart + h.vertex_stream_bytes;
  const uint64_t ostart = istart + h.index_stream_bytes;
  const uint64_t end = ostart + h.object_stream_bytes;
  if (end > blob.size()) return fail("encoded cluster streams run past its end", blob.size());

  out.vertices.resize(h.vertex_count);
  if (meshopt_decodeVertexBuffer(out.vertices.data(), h.vertex_count, sizeof(pkg::EncodedVertex),
                                 blob.data() + vstart, h.vertex_stream_bytes) != 0)
    return fail("vertex stream is corrupt", vstart);
  const size_t index_count = size_t{h.triangle_count} * 3;
  out.indices.resize(index_count);
  if (meshopt_decodeIndexBuffer(out.indices.data(), index_count, sizeof(uint32_t),
                                blob.data() + istart, h.index_stream_bytes) != 0)
    return fail("index stream is corrupt", istart);
  for (uint32_t index : out.indices)
    if (index >= h.vertex_count) return fail("index stream refers past the last vertex", istart);

  const uint8_t* objects = blob.data() + ostart;
  const uint8_t* lengths = objects + size_t{h.run_count} * 4;
  out.triangle_objects.clear();
  out.triangle_objects.reserve(h.triangle_count);
  for (uint32_t r = 0; r < h.run_count; ++r) {
    uint32_t object;
    uint16_t length;
    std::memcpy(&object, objects + r * 4, 4);
    std::memcpy(&length, lengths + r * 2, 2);
    if (object >= object_limit) return fail("object index out of range", ostart + r * 4);
    if (r > 0 && object <= out.triangle_objects.back())
      return fail("object runs are not in increasing order", ostart + r * 4);
    if (length == 0 || length > h.triangle_count - out.triangle_objects.size())
      return fail("object run lengths do not add up to the triangle count",
                  ostart + h.run_count * 4u + r * 2);
    out.triangle_objects.insert(out.triangle_objects.end(), length, object);
  }
  if (out.triangle_objects.size() != h.triangle_count)
    return fail("object run lengths do not add up to the triangle count",
                ostart + h.run_count * 4u);

  out.shift = h.shift;
  out.grid_origin = glm::ivec3(h.grid_origin[0], h.grid_origin[1], h.grid_origin[2]);
  out.cell_m = std::ldexp(position_step_m, h.shift);
  out.positions.resize(h.vertex_count);
  const bool has_normals = (h.flags & pkg::kEncodedHasNormals) != 0;
  out.normals.resize(has_normals ? h.vertex_count : 0);
  for (uint32_t v = 0; v < h.vertex_count; ++v) {
    const pkg::EncodedVertex& e = out.vertices[v];
    for (int a = 0; a < 3; ++a)
      out.positions[v][a] = dequantize(h.grid_origin[a], e.q[a], out.cell_m);
    if (has_normals)
      out.normals[v] = decodeOctahedral(e.oct);
    else if (e.oct[0] != 0 || e.oct[1] != 0)
      return fail("normal bytes set in a cluster without normals", vstart);
  }
  return {};
}

size_t compressPage(std::span<const uint8_t> raw, int level, std::vector<uint8_t>& out) {
  const size_t start = out.size();
  out.resize(start + ZSTD_compressBound(raw.size()));
  size_t n = ZSTD_compress(out.data() + start, out.size() - start, raw.data(), raw.size(), level);
  if (ZSTD_isError(n)) {
    out.resize(start);
    throw std::runtime_error(std::string("zstd compression failed: ") + ZSTD_getErrorName(n));
  }
  out.resize(start + n);
  return n;
}

const char* decompressPage(std::span<const uint8_t> stored, uint32_t raw_bytes,
                           std::vector<uint8_t>& raw) {
  if (raw_bytes > pkg::kMaxPageRawBytes) return "page raw size is over the limit";
  unsigned long long content = ZSTD_getFrameContentSize(stored.data(), stored.size());
  if (content == ZSTD_CONTENTSIZE_ERROR || content == ZSTD_CONTENTSIZE_UNKNOWN)
    return "page is not a valid zstd frame";
  if (content != raw_bytes) return "zstd frame size does not match the page's raw size";
  raw.resize(raw_bytes);
  size_t n = ZSTD_decompress(raw.data(), raw.size(), stored.data(), stored.size());
  if (ZSTD_isError(n)) return "page zstd data is corrupt";
  if (n != raw_bytes) return "page decompressed to the wrong size";
  return nullptr;
}

}  // namespace tw
