// Encoding of one cluster's geometry for a package page, its safe decoder, and page compression.
//
// A cluster is encoded as an EncodedClusterHeader (package_format.h) plus three streams: quantized
// vertices (meshopt vertex codec), triangle indices (meshopt index codec, after vertex-cache and
// vertex-fetch optimisation) and per-triangle object ids as runs (triangles are sorted by object).
// Pages concatenate encoded clusters and are optionally zstd-compressed as a whole, which gives
// zstd enough context to help (a 256-triangle cluster alone is too small).
//
// Positions are quantized on a package-wide grid: a cluster uses cells of
// position_step_m * 2^shift with the smallest shift that fits its extent in 16 bits. Two clusters
// with the same shift quantize a shared border vertex to the same grid point, so locked borders
// stay crack-free after quantization; across different shifts a shared vertex differs by at most
// half the coarser cell. The error is at most half a cell per axis (quantizationErrorM).
//
// The decoder is safe on untrusted bytes: it checks every size and count, returns an error with
// the byte offset inside the blob, and allocates at most what kMaxCluster* allow.
#pragma once

#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <span>
#include <string>
#include <vector>

#include "package_format.h"

namespace tw {

// One cluster's triangles. Positions are metres relative to the package origin.
struct ClusterGeometryInput {
  std::span<const glm::vec3> positions;        // <= kMaxClusterVertices, finite
  std::span<const glm::vec3> normals;          // empty, or one unit vector per position
  std::span<const uint32_t> indices;           // 3 per triangle, each < positions.size()
  std::span<const uint32_t> triangle_objects;  // one object-table index per triangle
};

struct ClusterEncodeOptions {
  double position_step_m = pkg::kDefaultPositionStepM;  // the package's base step, > 0
  bool optimize = true;  // vertex-cache then vertex-fetch order (much smaller index stream)
  // Lower bound on the shift. Clusters that share a border decode it identically only when they
  // use the same shift; a packer can force one (e.g. the largest its neighbours need) here.
  uint32_t min_shift = 0;
};

// What the encoder produced, for the cluster record.
struct EncodedClusterInfo {
  uint32_t encoded_bytes = 0;  // bytes appended (excluding alignment padding)
  uint32_t vertex_count = 0;   // after dropping unused vertices
  uint32_t triangle_count = 0;
  uint32_t shift = 0;
  double cell_m = 0;  // position_step_m * 2^shift
  uint32_t object_min = 0;
  uint32_t object_max = 0;
  uint32_t object_runs = 0;  // distinct objects
  glm::vec3 aabb_min{0.0f};  // of the decoded (dequantized) positions
  glm::vec3 aabb_max{0.0f};
  glm::vec3 center{0.0f};  // sphere containing every decoded position
  float radius = 0.0f;
};

// Appends the encoded cluster to `out`. Throws std::invalid_argument when the input breaks the
// contract above (too many vertices or triangles, an index out of range, a non-finite position,
// a cluster too far from the origin for the int32 grid).
EncodedClusterInfo encodeCluster(const ClusterGeometryInput& input,
                                 const ClusterEncodeOptions& options, std::vector<uint8_t>& out);

// Half the cell diagonal: the largest distance between an input position and its decoded value
// (plus float rounding of the result), in metres.
double quantizationErrorM(double position_step_m, uint32_t shift);

// A decoded cluster. Positions are dequantized to metres relative to the package origin.
struct DecodedCluster {
  std::vector<pkg::EncodedVertex> vertices;  // as stored: quantized, for GPU upload
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;  // empty when the cluster stores none
  std::vector<uint32_t> indices;
  std::vector<uint32_t> triangle_objects;
  uint32_t shift = 0;
  glm::ivec3 grid_origin{0};
  double cell_m = 0;  // position_step_m * 2^shift
};

// Why decoding failed and where (byte offset within the blob); error == nullptr on success.
struct DecodeStatus {
  const char* error = nullptr;
  uint64_t offset = 0;
  bool ok() const { return error == nullptr; }
};

// Decodes one encoded cluster from `blob` (exactly its encoded bytes, or more: trailing bytes are
// ignored). Every object id must be < object_limit. On failure `out` holds unspecified data.
DecodeStatus decodeCluster(std::span<const uint8_t> blob, double position_step_m,
                           uint32_t object_limit, DecodedCluster& out);

// Octahedral snorm8 normal coding (exposed for the runtime's shaders and for tests).
void encodeOctahedral(const glm::vec3& normal, int8_t out[2]);
glm::vec3 decodeOctahedral(const int8_t oct[2]);

// Page compression. compressPage appends zstd-compressed `raw` to `out` at `level` and returns the
// bytes appended. decompressPage fills `raw` (resized to raw_bytes <= kMaxPageRawBytes) and
// returns a reason on failure (nullptr on success); the stored bytes must decompress to exactly
// raw_bytes.
size_t compressPage(std::span<const uint8_t> raw, int level, std::vector<uint8_t>& out);
const char* decompressPage(std::span<const uint8_t> stored, uint32_t raw_bytes,
                           std::vector<uint8_t>& raw);

}  // namespace tw
