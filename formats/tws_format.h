// On-disk layout of TeraWalk's native scene format (.tws), shared by its writer and reader.
//
// docs/scene-format.md is the normative spec; this header mirrors it field for field. All structs
// are plain, fixed-width, little-endian and static_asserted for size and offsets, so the bytes a
// writer memcpy's out are exactly the bytes the spec describes.
//
// Version history (kVersion.kMinorVersion):
//   1.0 (2026-11) first version: LAYR, OBJT and END chunks; mesh, primitive and NURBS geometry.
#pragma once

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "scene.h"

namespace tw::tws {

static_assert(std::endian::native == std::endian::little,
              ".tws is little-endian; the writer and reader copy structs as they are");

// Bumped for incompatible changes; a reader rejects a file whose version is greater than its own.
inline constexpr uint32_t kVersion = 1;
// Bumped for compatible additions (new optional chunk types, longer records); informational.
inline constexpr uint32_t kMinorVersion = 0;

inline constexpr char kMagic[8] = {'T', 'W', 'S', 'C', 'E', 'N', 'E', '\0'};

// Chunk headers, payloads and records that hold doubles start at multiples of this.
inline constexpr uint64_t kAlignment = 8;
inline constexpr uint64_t alignUp(uint64_t value, uint64_t alignment = kAlignment) {
  return (value + alignment - 1) / alignment * alignment;
}

// Writers split meshes into parts so that no payload exceeds this (reader memory stays small).
inline constexpr uint64_t kWriterMaxPayloadBytes = uint64_t{64} << 20;
// Readers accept payloads up to this and reject larger ones before allocating anything.
inline constexpr uint64_t kReaderMaxPayloadBytes = uint64_t{1} << 30;
// Longest object name, database key or layer name, in bytes of UTF-8.
inline constexpr uint32_t kMaxStringBytes = 65535;

// Chunk types are four ASCII characters, so a hex dump shows them as text.
constexpr uint32_t fourCc(char a, char b, char c, char d) {
  return uint32_t(uint8_t(a)) | uint32_t(uint8_t(b)) << 8 | uint32_t(uint8_t(c)) << 16 |
         uint32_t(uint8_t(d)) << 24;
}
inline constexpr uint32_t kChunkLayer = fourCc('L', 'A', 'Y', 'R');
inline constexpr uint32_t kChunkObject = fourCc('O', 'B', 'J', 'T');
inline constexpr uint32_t kChunkEnd = fourCc('E', 'N', 'D', ' ');

// Chunk flag: a reader that does not know this chunk type must reject the file rather than skip.
inline constexpr uint32_t kChunkRequired = 1u << 0;

// The first 32 bytes of every file.
struct FileHeader {
  char magic[8];            // kMagic
  uint32_t version;         // kVersion
  uint32_t minor_version;   // kMinorVersion of the writer
  uint32_t header_bytes;    // 32 in 1.0; readers skip to this offset (multiple of 8, >= 32)
  uint32_t flags;           // 0; a reader rejects bits it does not know
  uint64_t reserved;        // 0; readers ignore
};
static_assert(sizeof(FileHeader) == 32);

// Precedes every payload. The payload is followed by zero padding up to a multiple of 8 bytes
// (not counted in payload_bytes, not covered by the checksum).
struct ChunkHeader {
  uint32_t type;            // kChunk*
  uint32_t flags;           // kChunkRequired or 0
  uint64_t payload_bytes;   // unpadded payload length
  uint64_t checksum;        // XXH3_64bits(payload, payload_bytes), seed 0
};
static_assert(sizeof(ChunkHeader) == 24);

// LAYR payload: this record, then name_bytes of UTF-8 (no terminator).
struct LayerRecord {
  uint32_t record_bytes;    // 16 in 1.0; the name starts at this offset (multiple of 4, >= 16)
  uint32_t index;           // equals the number of layers declared before it
  uint32_t color_rgba;      // 0xAABBGGRR
  uint32_t name_bytes;      // <= kMaxStringBytes
};
static_assert(sizeof(LayerRecord) == 16);

enum class GeometryCode : uint32_t { Mesh = 0, Primitive = 1, Nurbs = 2 };

// OBJT payload: this record; name; database key; zero padding to a multiple of 8 (relative to the
// payload start); then the geometry block selected by geometry.
struct ObjectRecord {
  uint32_t record_bytes;    // 96 in 1.0; the name starts at this offset (multiple of 8, >= 96)
  uint32_t id;
  uint32_t layer;           // < number of layers declared so far
  uint32_t color_rgba;      // 0xAABBGGRR; 0 means "use the layer's colour"
  uint32_t geometry;        // GeometryCode
  uint32_t name_bytes;      // <= kMaxStringBytes
  uint32_t db_key_bytes;    // <= kMaxStringBytes
  uint32_t reserved0;       // 0
  double origin[3];         // finite
  float linear[9];          // column-major 3x3, finite
  uint32_t reserved1;       // 0
};
static_assert(sizeof(ObjectRecord) == 96);
static_assert(offsetof(ObjectRecord, origin) == 32 && offsetof(ObjectRecord, linear) == 56);

// Mesh block attribute bits. A reader rejects bits it does not know (it could not size the arrays).
inline constexpr uint32_t kMeshHasNormals = 1u << 0;
inline constexpr uint32_t kMeshHasColors = 1u << 1;

// Mesh block: this record, then float positions[3 * vertex_count], float normals[3 * vertex_count]
// (if kMeshHasNormals), uint32 colors[vertex_count] (if kMeshHasColors), uint32
// indices[index_count]. Every array is 4-byte aligned; nothing follows the indices.
struct MeshRecord {
  uint32_t vertex_count;
  uint32_t index_count;     // multiple of 3; each index < vertex_count
  uint32_t attributes;      // kMesh* bits
  uint32_t reserved;        // 0
};
static_assert(sizeof(MeshRecord) == 16);

// Primitive types: the index of the alternative in tw::Primitive.
enum class PrimitiveCode : uint32_t {
  Cylinder = 0,
  Cone = 1,
  Sphere = 2,
  TorusSegment = 3,
  Box = 4,
  Extrusion = 5,
  Revolution = 6,
};
inline constexpr uint32_t kPrimitiveCapped = 1u << 0;  // Cylinder and Cone only

// Primitive block: this record, then float profile[2 * profile_count]. params by type (unused = 0):
//   Cylinder     radius, height                 Cone       radius_bottom, radius_top, height
//   Sphere       radius                         Torus      major_radius, minor_radius, sweep_rad
//   Box          half_extents x, y, z           Extrusion  height (profile: >= 3 points)
//   Revolution   sweep_rad (profile: >= 2 (radius, z) points)
struct PrimitiveRecord {
  uint32_t type;            // PrimitiveCode
  uint32_t flags;           // kPrimitiveCapped
  float params[6];
  uint32_t profile_count;   // 0 except for Extrusion and Revolution
  uint32_t reserved;        // 0
};
static_assert(sizeof(PrimitiveRecord) == 40);

// NURBS block: this record, then patch_count patches, each a NurbsPatchRecord followed by float
// knots_u[count_u + degree_u + 1], float knots_v[count_v + degree_v + 1] and float
// control_points[4 * count_u * count_v] (x, y, z, w; u fastest).
struct NurbsSetRecord {
  uint32_t patch_count;
  uint32_t reserved;        // 0
};
static_assert(sizeof(NurbsSetRecord) == 8);
struct NurbsPatchRecord {
  uint32_t degree_u;
  uint32_t degree_v;
  uint32_t count_u;
  uint32_t count_v;
};
static_assert(sizeof(NurbsPatchRecord) == 16);

// END payload: totals over the whole file, so a reader can tell a complete file from a truncated
// one. It is the last chunk; nothing follows its padding.
struct EndRecord {
  uint64_t chunk_count;         // chunks before this one, of every type (unknown ones included)
  uint64_t object_chunk_count;  // OBJT chunks (object parts)
  uint64_t object_count;        // OBJT chunks whose id differs from the previous OBJT chunk's
  uint32_t layer_count;         // LAYR chunks
  uint32_t reserved;            // 0
};
static_assert(sizeof(EndRecord) == 32);

// True when the float is neither infinite nor NaN (bit test: safe under -ffast-math, vectorizes).
inline bool isFiniteBits(float value) {
  return (std::bit_cast<uint32_t>(value) & 0x7f800000u) != 0x7f800000u;
}

// Largest sweep accepted for tori and revolutions: float(2 pi), rounded up.
inline constexpr float kMaxSweepRad = 6.2831855f;

namespace detail {
inline bool badLength(float v) { return !isFiniteBits(v) || v < 0.0f; }
inline bool badSweep(float v) { return !isFiniteBits(v) || v < 0.0f || v > kMaxSweepRad; }
struct PrimitiveCheck {
  std::string operator()(const Cylinder& c) const {
    return badLength(c.radius) || badLength(c.height)
               ? "cylinder radius or height is negative or not finite" : "";
  }
  std::string operator()(const Cone& c) const {
    return badLength(c.radius_bottom) || badLength(c.radius_top) || badLength(c.height)
               ? "cone radius or height is negative or not finite" : "";
  }
  std::string operator()(const Sphere& s) const {
    return badLength(s.radius) ? "sphere radius is negative or not finite" : "";
  }
  std::string operator()(const TorusSegment& t) const {
    if (badLength(t.major_radius) || badLength(t.minor_radius))
      return "torus radius is negative or not finite";
    return badSweep(t.sweep_rad) ? "torus sweep is not in [0, 2 pi]" : "";
  }
  std::string operator()(const Box& b) const {
    return badLength(b.half_extents.x) || badLength(b.half_extents.y) ||
                   badLength(b.half_extents.z)
               ? "box half extent is negative or not finite" : "";
  }
  std::string operator()(const Extrusion& e) const {
    if (badLength(e.height)) return "extrusion height is negative or not finite";
    if (e.profile.size() < 3) return "extrusion profile has fewer than 3 points";
    for (const glm::vec2& p : e.profile)
      if (!isFiniteBits(p.x) || !isFiniteBits(p.y)) return "extrusion profile is not finite";
    return "";
  }
  std::string operator()(const Revolution& r) const {
    if (badSweep(r.sweep_rad)) return "revolution sweep is not in [0, 2 pi]";
    if (r.profile.size() < 2) return "revolution profile has fewer than 2 points";
    for (const glm::vec2& p : r.profile)
      if (badLength(p.x) || !isFiniteBits(p.y))
        return "revolution profile has a negative radius or is not finite";
    return "";
  }
};
}  // namespace detail

// Returns an empty string when `primitive` obeys the format's constraints (finite parameters;
// non-negative lengths; sweeps in [0, 2 pi]; profiles of >= 3 (extrusion) or >= 2 (revolution)
// finite points with non-negative radius for revolutions), otherwise the reason it does not.
// The writer refuses what the reader would reject.
inline std::string primitiveProblem(const Primitive& primitive) {
  return std::visit(detail::PrimitiveCheck{}, primitive);
}

// Copies triangles [first_triangle, first_triangle + triangle_count) of `mesh` into `part`
// (replacing its contents) with only the vertices they use, renumbered in first-use order.
// `remap` is caller-owned scratch: on entry it is empty or holds mesh.positions.size() entries of
// ~0u, and it is left that way. Indices must already be known to be < mesh.positions.size().
inline void extractMeshPart(const TriangleMesh& mesh, uint64_t first_triangle,
                            uint64_t triangle_count, std::vector<uint32_t>& remap,
                            TriangleMesh& part) {
  if (remap.size() != mesh.positions.size()) remap.assign(mesh.positions.size(), ~0u);
  const bool has_normals = !mesh.normals.empty();
  const bool has_colors = !mesh.colors.empty();
  part.positions.clear();
  part.normals.clear();
  part.colors.clear();
  part.indices.resize(triangle_count * 3);
  const uint32_t* src = mesh.indices.data() + first_triangle * 3;
  for (uint64_t i = 0; i < triangle_count * 3; ++i) {
    uint32_t v = src[i];
    uint32_t& slot = remap[v];
    if (slot == ~0u) {
      slot = static_cast<uint32_t>(part.positions.size());
      part.positions.push_back(mesh.positions[v]);
      if (has_normals) part.normals.push_back(mesh.normals[v]);
      if (has_colors) part.colors.push_back(mesh.colors[v]);
    }
    part.indices[i] = slot;
  }
  for (uint64_t i = 0; i < triangle_count * 3; ++i) remap[src[i]] = ~0u;
}

}  // namespace tw::tws
