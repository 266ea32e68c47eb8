// readTws: chunk by chunk, each payload read whole into one reused buffer, checksummed, then parsed
// with a bounds-checked cursor (docs/scene-format.md).
//
// Order of checks per chunk: the header fits in the file; the payload fits in the file and under
// the reader's limit (before anything is allocated); the checksum matches (before anything is
// parsed); then every count is checked against the payload bytes left before it is used.
#include "tws_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include <xxhash.h>

#include "file_reader.h"
#include "nurbs.h"
#include "tws_format.h"

namespace tw {
namespace {

std::string chunkName(uint32_t type) {
  std::string name;
  for (int i = 0; i < 4; ++i) {
    char c = static_cast<char>((type >> (8 * i)) & 0xff);
    if (c < 0x20 || c > 0x7e) {
      char hex[16];
      std::snprintf(hex, sizeof hex, "0x%08x", type);
      return hex;
    }
    name += c;
  }
  return "'" + name + "'";
}

std::string hex64(uint64_t value) {
  char text[24];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
  return text;
}

// Bounds-checked reads from one chunk payload; errors carry the absolute file offset.
class Cursor {
 public:
  Cursor(const std::string& file, uint64_t base, const char* data, uint64_t size)
      : file_(file), base_(base), data_(data), size_(size) {}

  uint64_t pos() const { return pos_; }
  uint64_t left() const { return size_ - pos_; }
  const char* at(uint64_t pos) const { return data_ + pos; }

  [[noreturn]] void failAt(uint64_t pos, const std::string& reason) const {
    throw FormatError::atByte(file_, base_ + pos, reason);
  }
  [[noreturn]] void fail(const std::string& reason) const { failAt(pos_, reason); }

  void need(uint64_t bytes, const std::string& what) const {
    if (bytes > left())
      fail(what + " needs " + std::to_string(bytes) + " bytes but the chunk has " +
           std::to_string(left()) + " left");
  }
  template <typename T>
  T take(const char* what) {
    need(sizeof(T), what);
    T value;
    std::memcpy(&value, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  const char* takeBytes(uint64_t bytes, const std::string& what) {
    need(bytes, what);
    const char* p = data_ + pos_;
    pos_ += bytes;
    return p;
  }
  // Moves forward to `pos` (relative to the payload start), which must lie inside the payload.
  void skipTo(uint64_t pos, const char* what) {
    if (pos < pos_) fail(std::string(what) + " overlaps what precedes it");
    need(pos - pos_, what);
    pos_ = pos;
  }
  void alignTo(uint64_t alignment, const char* what) { skipTo(tws::alignUp(pos_, alignment), what); }
  void expectEnd(const char* what) const {
    if (left() != 0) fail(std::to_string(left()) + " unexpected bytes after " + what);
  }

 private:
  const std::string& file_;
  uint64_t base_;
  const char* data_;
  uint64_t size_;
  uint64_t pos_ = 0;
};

// Index of the first non-finite float in [f, f + n), or n. Branch-free scan first: the common
// case is "all finite", and that loop vectorizes.
uint64_t firstNonFinite(const float* f, uint64_t n) {
  uint32_t bad = 0;
  for (uint64_t i = 0; i < n; ++i) bad |= !tws::isFiniteBits(f[i]);
  if (!bad) return n;
  for (uint64_t i = 0; i < n; ++i)
    if (!tws::isFiniteBits(f[i])) return i;
  return n;
}

class TwsReader {
 public:
  TwsReader(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options)
      : in_(path), sink_(sink), options_(options) {}

  uint64_t fileBytes() const { return in_.size(); }
  void run();

 private:
  void readHeader();
  void readPayload(uint64_t bytes);
  void parseLayer(Cursor& c);
  void parseObject(Cursor& c);
  void parseMesh(Cursor& c);
  void parsePrimitive(Cursor& c);
  void parseNurbs(Cursor& c);
  void parseEnd(Cursor& c, uint64_t chunk_offset);
  void emitObject();

  FileReader in_;
  SceneSink& sink_;
  const ReadOptions& options_;

  std::unique_ptr<char[]> payload_;  // reused across chunks; grows to the largest payload
  uint64_t payload_capacity_ = 0;

  uint64_t chunk_count_ = 0;
  uint64_t object_chunk_count_ = 0;
  uint64_t object_count_ = 0;
  uint32_t layer_count_ = 0;
  bool have_last_id_ = false;
  uint32_t last_id_ = 0;

  SceneObject object_;             // reused so that strings and arrays keep their capacity
  TriangleMesh mesh_;              // the current mesh, moved in and out of object_
  TriangleMesh part_;              // scratch for splitting by max_part_triangles
  std::vector<uint32_t> remap_;
};

void TwsReader::readHeader() {
  if (in_.size() < sizeof(tws::FileHeader)) {
    if (in_.size() >= 8) {
      char magic[8];
      in_.read(magic, 8);
      if (std::memcmp(magic, tws::kMagic, 8) != 0) in_.failAt(0, "not a .tws file (bad magic)");
    }
    in_.failAt(in_.size(), "file too short for a .tws header (" + std::to_string(in_.size()) +
                               " bytes; truncated?)");
  }
  auto header = in_.readValue<tws::FileHeader>();
  if (std::memcmp(header.magic, tws::kMagic, sizeof header.magic) != 0)
    in_.failAt(0, "not a .tws file (bad magic)");
  if (header.version == 0 || header.version > tws::kVersion)
    in_.failAt(offsetof(tws::FileHeader, version),
               "unsupported .tws version " + std::to_string(header.version) +
                   " (this reader supports up to " + std::to_string(tws::kVersion) + ")");
  if (header.header_bytes < sizeof header || header.header_bytes % tws::kAlignment != 0)
    in_.failAt(offsetof(tws::FileHeader, header_bytes),
               "bad header size " + std::to_string(header.header_bytes) +
                   " (must be a multiple of 8, at least 32)");
  if (header.flags != 0)
    in_.failAt(offsetof(tws::FileHeader, flags),
               "unsupported header flags 0x" + hex64(header.flags) + " (needs a newer reader)");
  in_.skip(header.header_bytes - sizeof header);
}

void TwsReader::readPayload(uint64_t bytes) {
  if (bytes > payload_capacity_) {
    uint64_t capacity = std::max<uint64_t>(bytes, std::min<uint64_t>(payload_capacity_ * 2,
                                                                      tws::kReaderMaxPayloadBytes));
    payload_.reset();  // release first: peak memory is one buffer, not two
    payload_ = std::make_unique_for_overwrite<char[]>(capacity);
    payload_capacity_ = capacity;
  }
  in_.read(payload_.get(), bytes);
}

void TwsReader::run() {
  readHeader();
  while (true) {
    const uint64_t chunk_offset = in_.offset();
    if (in_.atEnd()) in_.fail("missing end chunk (file truncated?)");
    if (in_.remaining() < sizeof(tws::ChunkHeader))
      in_.fail("truncated chunk header (" + std::to_string(in_.remaining()) +
               " bytes left; file truncated?)");
    auto header = in_.readValue<tws::ChunkHeader>();
    const std::string name = chunkName(header.type);
    const uint64_t padded = tws::alignUp(header.payload_bytes);
    if (header.payload_bytes > in_.remaining() || padded > in_.remaining())
      in_.failAt(chunk_offset + offsetof(tws::ChunkHeader, payload_bytes),
                 "chunk " + name + " payload of " + std::to_string(header.payload_bytes) +
                     " bytes runs past the end of the file (" + std::to_string(in_.remaining()) +
                     " bytes left; truncated?)");
    const bool known = header.type == tws::kChunkLayer || header.type == tws::kChunkObject ||
                       header.type == tws::kChunkEnd;
    if (!known) {
      if (header.flags & tws::kChunkRequired)
        in_.failAt(chunk_offset, "unknown required chunk type " + name + " (needs a newer reader)");
      in_.skip(padded);  // an optional addition from a newer writer
      ++chunk_count_;
      updateProgress(options_.progress, in_.offset());
      continue;
    }
    if (header.payload_bytes > tws::kReaderMaxPayloadBytes)
      in_.failAt(chunk_offset + offsetof(tws::ChunkHeader, payload_bytes),
                 "chunk " + name + " payload of " + std::to_string(header.payload_bytes) +
                     " bytes exceeds the reader's limit of " +
                     std::to_string(tws::kReaderMaxPayloadBytes) + " bytes");
    const uint64_t payload_offset = in_.offset();
    readPayload(header.payload_bytes);
    const uint64_t checksum = XXH3_64bits(payload_.get(), header.payload_bytes);
    if (checksum != header.checksum)
      in_.failAt(chunk_offset, "chunk " + name + " checksum mismatch (stored " +
                                   hex64(header.checksum) + ", computed " + hex64(checksum) +
                                   "; file corrupt)");
    in_.skip(padded - header.payload_bytes);

    Cursor c(in_.name(), payload_offset, payload_.get(), header.payload_bytes);
    if (header.type == tws::kChunkEnd) {
      parseEnd(c, chunk_offset);
      return;
    }
    if (header.type == tws::kChunkLayer) {
      parseLayer(c);
    } else {
      parseObject(c);
    }
    ++chunk_count_;
    updateProgress(options_.progress, in_.offset());
  }
}

void TwsReader::parseLayer(Cursor& c) {
  auto record = c.take<tws::LayerRecord>("layer record");
  if (record.record_bytes < sizeof record || record.record_bytes % 4 != 0)
    c.failAt(offsetof(tws::LayerRecord, record_bytes),
             "bad layer record size " + std::to_string(record.record_bytes));
  if (record.index != layer_count_)
    c.failAt(offsetof(tws::LayerRecord, index),
             "layer " + std::to_string(record.index) + " declared out of order (expected " +
                 std::to_string(layer_count_) + ")");
  if (record.name_bytes > tws::kMaxStringBytes)
    c.failAt(offsetof(tws::LayerRecord, name_bytes),
             "layer name of " + std::to_string(record.name_bytes) + " bytes is too long");
  c.skipTo(record.record_bytes, "layer record");
  Layer layer;
  layer.color_rgba = record.color_rgba;
  layer.name.assign(c.takeBytes(record.name_bytes, "layer name"), record.name_bytes);
  c.expectEnd("the layer name");
  sink_.onLayer(layer_count_, layer);
  ++layer_count_;
}

void TwsReader::parseObject(Cursor& c) {
  auto record = c.take<tws::ObjectRecord>("object record");
  if (record.record_bytes < sizeof record || record.record_bytes % tws::kAlignment != 0)
    c.failAt(offsetof(tws::ObjectRecord, record_bytes),
             "bad object record size " + std::to_string(record.record_bytes));
  const std::string what = "object " + std::to_string(record.id);
  if (record.layer >= layer_count_)
    c.failAt(offsetof(tws::ObjectRecord, layer),
             what + " uses layer " + std::to_string(record.layer) + " but only " +
                 std::to_string(layer_count_) + " layers were declared before it");
  if (record.name_bytes > tws::kMaxStringBytes || record.db_key_bytes > tws::kMaxStringBytes)
    c.failAt(offsetof(tws::ObjectRecord, name_bytes), what + ": name or key is too long");
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(record.origin[i]))
      c.failAt(offsetof(tws::ObjectRecord, origin) + 8 * i, what + ": origin is not finite");
  if (uint64_t bad = firstNonFinite(record.linear, 9); bad < 9)
    c.failAt(offsetof(tws::ObjectRecord, linear) + 4 * bad, what + ": transform is not finite");
  c.skipTo(record.record_bytes, "object record");

  ObjectInfo& info = object_.info;
  info.id = record.id;
  info.layer = record.layer;
  info.color_rgba = record.color_rgba;
  info.name.assign(c.takeBytes(record.name_bytes, what + " name"), record.name_bytes);
  info.db_key.assign(c.takeBytes(record.db_key_bytes, what + " key"), record.db_key_bytes);
  info.transform.origin = glm::dvec3(record.origin[0], record.origin[1], record.origin[2]);
  std::memcpy(&info.transform.linear[0][0], record.linear, sizeof record.linear);
  c.alignTo(tws::kAlignment, "object strings padding");

  switch (record.geometry) {
    case static_cast<uint32_t>(tws::GeometryCode::Mesh): parseMesh(c); break;
    case static_cast<uint32_t>(tws::GeometryCode::Primitive): parsePrimitive(c); break;
    case static_cast<uint32_t>(tws::GeometryCode::Nurbs): parseNurbs(c); break;
    default:
      c.failAt(offsetof(tws::ObjectRecord, geometry),
               what + ": unknown geometry kind " + std::to_string(record.geometry));
  }

  ++object_chunk_count_;
  if (!have_last_id_ || last_id_ != record.id) ++object_count_;
  have_last_id_ = true;
  last_id_ = record.id;
}

void TwsReader::parseMesh(Cursor& c) {
  const uint64_t record_pos = c.pos();
  auto record = c.take<tws::MeshRecord>("mesh record");
  const uint32_t known = tws::kMeshHasNormals | tws::kMeshHasColors;
  if (record.attributes & ~known)
    c.failAt(record_pos + offsetof(tws::MeshRecord, attributes),
             "unknown mesh attribute bits 0x" + hex64(record.attributes & ~known));
  if (record.index_count % 3 != 0)
    c.failAt(record_pos + offsetof(tws::MeshRecord, index_count),
             "mesh index count " + std::to_string(record.index_count) +
                 " is not a multiple of 3");
  const uint64_t vertices = record.vertex_count;
  const uint64_t indices = record.index_count;
  const bool has_normals = record.attributes & tws::kMeshHasNormals;
  const bool has_colors = record.attributes & tws::kMeshHasColors;
  const uint64_t array_bytes =
      vertices * (12 + (has_normals ? 12 : 0) + (has_colors ? 4 : 0)) + indices * 4;
  c.need(array_bytes, "mesh arrays (" + std::to_string(vertices) + " vertices, " +
                          std::to_string(indices) + " indices)");

  // Validate in the payload, then copy each array with one memcpy.
  const uint64_t positions_pos = c.pos();
  const char* positions = c.takeBytes(vertices * 12, "positions");
  if (uint64_t bad = firstNonFinite(reinterpret_cast<const float*>(positions), vertices * 3);
      bad < vertices * 3)
    c.failAt(positions_pos + 4 * bad, "mesh position is not finite");
  const char* normals = nullptr;
  if (has_normals) {
    const uint64_t normals_pos = c.pos();
    normals = c.takeBytes(vertices * 12, "normals");
    if (uint64_t bad = firstNonFinite(reinterpret_cast<const float*>(normals), vertices * 3);
        bad < vertices * 3)
      c.failAt(normals_pos + 4 * bad, "mesh normal is not finite");
  }
  const char* colors = has_colors ? c.takeBytes(vertices * 4, "colours") : nullptr;
  const uint64_t indices_pos = c.pos();
  const char* index_bytes = c.takeBytes(indices * 4, "indices");
  c.expectEnd("the mesh indices");

  mesh_.positions.resize(vertices);
  mesh_.normals.resize(has_normals ? vertices : 0);
  mesh_.colors.resize(has_colors ? vertices : 0);
  mesh_.indices.resize(indices);
  if (vertices) std::memcpy(mesh_.positions.data(), positions, vertices * 12);
  if (has_normals && vertices) std::memcpy(mesh_.normals.data(), normals, vertices * 12);
  if (has_colors && vertices) std::memcpy(mesh_.colors.data(), colors, vertices * 4);
  if (indices) std::memcpy(mesh_.indices.data(), index_bytes, indices * 4);
  uint32_t max_index = 0;
  for (uint32_t index : mesh_.indices) max_index = std::max(max_index, index);
  if (indices && max_index >= vertices) {
    uint64_t i = 0;
    while (mesh_.indices[i] < vertices) ++i;
    c.failAt(indices_pos + 4 * i, "mesh index " + std::to_string(mesh_.indices[i]) +
                                      " out of range (" + std::to_string(vertices) +
                                      " vertices)");
  }

  const uint64_t triangles = mesh_.triangleCount();
  const uint64_t max_part = options_.max_part_triangles;
  if (max_part == 0 || triangles <= max_part) {
    object_.geometry = std::move(mesh_);
    emitObject();
    mesh_ = std::move(std::get<TriangleMesh>(object_.geometry));
    return;
  }
  for (uint64_t first = 0; first < triangles; first += max_part) {
    tws::extractMeshPart(mesh_, first, std::min(max_part, triangles - first), remap_, part_);
    object_.geometry = std::move(part_);
    emitObject();
    part_ = std::move(std::get<TriangleMesh>(object_.geometry));
  }
}

void TwsReader::parsePrimitive(Cursor& c) {
  const uint64_t record_pos = c.pos();
  auto record = c.take<tws::PrimitiveRecord>("primitive record");
  const bool capped = record.flags & tws::kPrimitiveCapped;
  const float* p = record.params;
  const bool has_profile = record.type == static_cast<uint32_t>(tws::PrimitiveCode::Extrusion) ||
                           record.type == static_cast<uint32_t>(tws::PrimitiveCode::Revolution);
  if (!has_profile && record.profile_count != 0)
    c.failAt(record_pos + offsetof(tws::PrimitiveRecord, profile_count),
             "primitive type " + std::to_string(record.type) + " has no profile");
  std::vector<glm::vec2> profile;
  if (has_profile) {
    const uint64_t count = record.profile_count;
    const char* data = c.takeBytes(count * 8, "profile of " + std::to_string(count) + " points");
    profile.resize(count);
    if (count) std::memcpy(profile.data(), data, count * 8);
  }
  c.expectEnd("the primitive");

  Primitive primitive;
  switch (static_cast<tws::PrimitiveCode>(record.type)) {
    case tws::PrimitiveCode::Cylinder: primitive = Cylinder{p[0], p[1], capped}; break;
    case tws::PrimitiveCode::Cone: primitive = Cone{p[0], p[1], p[2], capped}; break;
    case tws::PrimitiveCode::Sphere: primitive = Sphere{p[0]}; break;
    case tws::PrimitiveCode::TorusSegment: primitive = TorusSegment{p[0], p[1], p[2]}; break;
    case tws::PrimitiveCode::Box: primitive = Box{glm::vec3(p[0], p[1], p[2])}; break;
    case tws::PrimitiveCode::Extrusion: primitive = Extrusion{std::move(profile), p[0]}; break;
    case tws::PrimitiveCode::Revolution: primitive = Revolution{std::move(profile), p[0]}; break;
    default:
      c.failAt(record_pos + offsetof(tws::PrimitiveRecord, type),
               "unknown primitive type " + std::to_string(record.type));
  }
  std::string problem = tws::primitiveProblem(primitive);
  if (!problem.empty()) c.failAt(record_pos + offsetof(tws::PrimitiveRecord, params), problem);
  object_.geometry = std::move(primitive);
  emitObject();
}

void TwsReader::parseNurbs(Cursor& c) {
  auto set_record = c.take<tws::NurbsSetRecord>("NURBS set record");
  // Each patch takes at least its record, so the count is bounded by the bytes left.
  if (set_record.patch_count > c.left() / sizeof(tws::NurbsPatchRecord))
    c.failAt(c.pos() - sizeof set_record, std::to_string(set_record.patch_count) +
                                              " NURBS patches cannot fit in the " +
                                              std::to_string(c.left()) + " bytes left");
  // Patches are appended as they are parsed and validated (a valid one takes at least 112 bytes
  // of payload), so memory follows the bytes actually present, not the count.
  NurbsPatchSet set;
  for (uint32_t i = 0; i < set_record.patch_count; ++i) {
    const uint64_t patch_pos = c.pos();
    const std::string what = "NURBS patch " + std::to_string(i);
    auto record = c.take<tws::NurbsPatchRecord>("NURBS patch record");
    NurbsPatch& patch = set.patches.emplace_back();
    patch.degree_u = record.degree_u;
    patch.degree_v = record.degree_v;
    patch.count_u = record.count_u;
    patch.count_v = record.count_v;
    const uint64_t knots_u = uint64_t{record.count_u} + record.degree_u + 1;
    const uint64_t knots_v = uint64_t{record.count_v} + record.degree_v + 1;
    const uint64_t points = uint64_t{record.count_u} * record.count_v;  // < 2^64
    if (points > c.left() / 16) c.failAt(patch_pos, what + ": control points exceed the chunk");
    const uint64_t bytes = 4 * (knots_u + knots_v) + 16 * points;
    const char* data = c.takeBytes(bytes, what);
    patch.knots_u.resize(knots_u);
    patch.knots_v.resize(knots_v);
    patch.control_points.resize(points);
    std::memcpy(patch.knots_u.data(), data, knots_u * 4);
    std::memcpy(patch.knots_v.data(), data + knots_u * 4, knots_v * 4);
    if (points) std::memcpy(patch.control_points.data(), data + (knots_u + knots_v) * 4, points * 16);
    std::string problem = validateNurbsPatch(patch);
    if (!problem.empty()) c.failAt(patch_pos, what + ": " + problem);
  }
  c.expectEnd("the NURBS patches");
  object_.geometry = std::move(set);
  emitObject();
}

void TwsReader::parseEnd(Cursor& c, uint64_t chunk_offset) {
  auto record = c.take<tws::EndRecord>("end record");  // longer END payloads: newer fields
  auto check = [&](uint64_t stored, uint64_t seen, const char* what) {
    if (stored != seen)
      in_.failAt(chunk_offset, "end chunk counts " + std::to_string(stored) + " " + what +
                                   " but the file has " + std::to_string(seen) +
                                   " (chunks lost or damaged)");
  };
  check(record.chunk_count, chunk_count_, "chunks");
  check(record.object_chunk_count, object_chunk_count_, "object chunks");
  check(record.object_count, object_count_, "objects");
  check(record.layer_count, layer_count_, "layers");
  if (!in_.atEnd())
    in_.fail(std::to_string(in_.remaining()) + " unexpected bytes after the end chunk");
  updateProgress(options_.progress, in_.offset());
}

void TwsReader::emitObject() { sink_.onObject(object_); }

// Ends the progress stage however reading ends.
struct StageGuard {
  Progress* progress;
  ~StageGuard() { endStage(progress); }
};

}  // namespace

void readTws(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options) {
  TwsReader reader(path, sink, options);
  beginStage(options.progress, "read", reader.fileBytes());
  StageGuard guard{options.progress};
  reader.run();
}

}  // namespace tw
