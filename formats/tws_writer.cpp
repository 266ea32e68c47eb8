// TwsWriter: appends one checksummed chunk per layer and per object part (docs/scene-format.md).
//
// Each payload is described as a list of byte ranges that point into the caller's data. The
// checksum is computed over those ranges first (the header precedes the payload), then each range
// goes out with one fwrite, so no array is ever copied into a staging buffer.
#include "tws_writer.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <system_error>

#include <xxhash.h>

#include "nurbs.h"
#include "tws_format.h"

namespace tw {
namespace {

constexpr size_t kIoBufferBytes = size_t{4} << 20;
constexpr char kZeros[tws::kAlignment] = {};

struct Piece {
  const void* data;
  uint64_t bytes;
};

// Branch-free over the whole array so that it vectorizes.
bool allFinite(const std::vector<glm::vec3>& values) {
  const float* f = reinterpret_cast<const float*>(values.data());
  uint32_t bad = 0;
  for (size_t i = 0; i < values.size() * 3; ++i) bad |= !tws::isFiniteBits(f[i]);
  return bad == 0;
}

uint64_t meshVertexBytes(const TriangleMesh& mesh) {
  return 12 + (mesh.normals.empty() ? 0 : 12) + (mesh.colors.empty() ? 0 : 4);
}

}  // namespace

struct TwsWriter::State {
  std::filesystem::path path;
  std::filesystem::path temp_path;
  std::FILE* file = nullptr;
  std::vector<char> io_buffer;
  uint64_t bytes_written = 0;
  bool finished = false;

  // Totals for the END chunk.
  uint64_t chunk_count = 0;
  uint64_t object_chunk_count = 0;
  uint64_t object_count = 0;
  uint32_t layer_count = 0;
  bool have_last_id = false;
  uint32_t last_id = 0;

  XXH3_state_t* hash = nullptr;
  std::vector<Piece> pieces;
  std::vector<uint32_t> remap;        // scratch for splitting meshes into parts
  TriangleMesh part;                  // scratch part
  std::vector<tws::NurbsPatchRecord> patch_records;

  ~State() {
    if (hash) XXH3_freeState(hash);
    if (file) std::fclose(file);
  }

  [[noreturn]] void ioFail(const std::string& what) const {
    throw std::runtime_error(path.string() + ": " + what + " (" + temp_path.string() +
                             "): " + std::strerror(errno));
  }

  void writeBytes(const void* data, uint64_t bytes) {
    if (bytes == 0) return;
    if (std::fwrite(data, 1, bytes, file) != bytes) ioFail("cannot write");
    bytes_written += bytes;
  }

  // Writes one chunk whose payload is the concatenation of `pieces`.
  void writeChunk(uint32_t type) {
    uint64_t payload_bytes = 0;
    for (const Piece& p : pieces) payload_bytes += p.bytes;
    tws::ChunkHeader header{};
    header.type = type;
    header.flags = 0;
    header.payload_bytes = payload_bytes;
    if (XXH3_64bits_reset(hash) != XXH_OK) throw std::runtime_error("XXH3 reset failed");
    for (const Piece& p : pieces)
      if (p.bytes) XXH3_64bits_update(hash, p.data, p.bytes);
    header.checksum = XXH3_64bits_digest(hash);
    writeBytes(&header, sizeof header);
    for (const Piece& p : pieces) writeBytes(p.data, p.bytes);
    writeBytes(kZeros, tws::alignUp(payload_bytes) - payload_bytes);
    ++chunk_count;
  }

  void checkOpen(const char* what) const {
    if (finished) throw std::logic_error(path.string() + ": " + what + " after finish()");
    if (!file) throw std::logic_error(path.string() + ": " + what + " after a failed write");
  }

  // The head every object chunk starts with: the object record, its name and key, padding.
  struct ObjectHead {
    tws::ObjectRecord record{};
    const ObjectInfo* info = nullptr;
    uint64_t head_bytes = 0;
    std::string where;  // "<file>: object <id>: ", for errors
    [[noreturn]] void reject(const std::string& why) const {
      throw std::invalid_argument(where + why);
    }
  };

  // Refuses anything the reader would reject, so a written file always reads back.
  ObjectHead objectHead(const SceneObject& object) const {
    ObjectHead head;
    const ObjectInfo& info = object.info;
    head.info = &info;
    head.where = path.string() + ": object " + std::to_string(info.id) + ": ";
    if (info.layer >= layer_count)
      head.reject("uses layer " + std::to_string(info.layer) + " but only " +
                  std::to_string(layer_count) + " layers were declared");
    if (info.name.size() > tws::kMaxStringBytes || info.db_key.size() > tws::kMaxStringBytes)
      head.reject("name or database key longer than 65535 bytes");
    tws::ObjectRecord& record = head.record;
    record.record_bytes = sizeof record;
    record.id = info.id;
    record.layer = info.layer;
    record.color_rgba = info.color_rgba;
    record.geometry = static_cast<uint32_t>(object.geometry.index());
    record.name_bytes = static_cast<uint32_t>(info.name.size());
    record.db_key_bytes = static_cast<uint32_t>(info.db_key.size());
    for (int i = 0; i < 3; ++i) record.origin[i] = info.transform.origin[i];
    std::memcpy(record.linear, &info.transform.linear[0][0], sizeof record.linear);
    for (double d : record.origin)
      if (!std::isfinite(d)) head.reject("transform origin is not finite");
    for (float f : record.linear)
      if (!tws::isFiniteBits(f)) head.reject("transform is not finite");
    head.head_bytes = tws::alignUp(sizeof record + info.name.size() + info.db_key.size());
    return head;
  }

  void beginObjectChunk(const ObjectHead& head) {
    const ObjectInfo& info = *head.info;
    const uint64_t strings_bytes = info.name.size() + info.db_key.size();
    pieces.assign({{&head.record, sizeof head.record},
                   {info.name.data(), info.name.size()},
                   {info.db_key.data(), info.db_key.size()},
                   {kZeros, head.head_bytes - sizeof head.record - strings_bytes}});
  }

  // Parts of one object (a mesh split over chunks) count as one object.
  void countObjectChunk(const ObjectHead& head) {
    if (!have_last_id || last_id != head.info->id) ++object_count;
    have_last_id = true;
    last_id = head.info->id;
    ++object_chunk_count;
  }

  // A mesh in one chunk, or split into parts that each fit the writer's payload bound.
  void writeMeshObject(const ObjectHead& head, const TriangleMesh& mesh) {
    const uint64_t vertex_count = mesh.positions.size();
    if (!mesh.normals.empty() && mesh.normals.size() != vertex_count)
      head.reject("mesh has " + std::to_string(mesh.normals.size()) + " normals for " +
                  std::to_string(vertex_count) + " positions");
    if (!mesh.colors.empty() && mesh.colors.size() != vertex_count)
      head.reject("mesh has " + std::to_string(mesh.colors.size()) + " colours for " +
                  std::to_string(vertex_count) + " positions");
    if (mesh.indices.size() % 3 != 0) head.reject("mesh index count is not a multiple of 3");
    if (vertex_count > UINT32_MAX) head.reject("mesh has more than 2^32 - 1 vertices");
    uint32_t max_index = 0;
    for (uint32_t index : mesh.indices) max_index = std::max(max_index, index);
    if (!mesh.indices.empty() && max_index >= vertex_count)
      head.reject("mesh index " + std::to_string(max_index) + " out of range");
    if (!allFinite(mesh.positions)) head.reject("mesh position is not finite");
    if (!allFinite(mesh.normals)) head.reject("mesh normal is not finite");

    tws::MeshRecord mesh_record{};
    auto writeMesh = [&](const TriangleMesh& m) {
      mesh_record.vertex_count = static_cast<uint32_t>(m.positions.size());
      mesh_record.index_count = static_cast<uint32_t>(m.indices.size());
      mesh_record.attributes = (m.normals.empty() ? 0 : tws::kMeshHasNormals) |
                               (m.colors.empty() ? 0 : tws::kMeshHasColors);
      beginObjectChunk(head);
      pieces.push_back({&mesh_record, sizeof mesh_record});
      pieces.push_back({m.positions.data(), m.positions.size() * sizeof(glm::vec3)});
      pieces.push_back({m.normals.data(), m.normals.size() * sizeof(glm::vec3)});
      pieces.push_back({m.colors.data(), m.colors.size() * sizeof(uint32_t)});
      pieces.push_back({m.indices.data(), m.indices.size() * sizeof(uint32_t)});
      writeChunk(tws::kChunkObject);
      countObjectChunk(head);
    };

    const uint64_t fixed_bytes = head.head_bytes + sizeof mesh_record;
    const uint64_t whole_bytes =
        fixed_bytes + vertex_count * meshVertexBytes(mesh) + mesh.indices.size() * 4;
    const uint64_t triangles = mesh.triangleCount();
    if (whole_bytes <= tws::kWriterMaxPayloadBytes ||
        (triangles == 0 && whole_bytes <= tws::kReaderMaxPayloadBytes)) {
      if (mesh.indices.size() > UINT32_MAX) head.reject("mesh has too many indices");
      writeMesh(mesh);
      return;
    }
    if (triangles == 0) head.reject("mesh without triangles is too large for one chunk");
    // Split greedily: each part takes triangles in order until the next one (its indices plus
    // the vertices it adds) would break the bound, so parts come out nearly full.
    const uint64_t budget = tws::kWriterMaxPayloadBytes - fixed_bytes;
    const uint64_t vertex_bytes = meshVertexBytes(mesh);
    const uint32_t* idx = mesh.indices.data();
    remap.assign(vertex_count, ~0u);
    for (uint64_t first = 0; first < triangles;) {
      uint64_t bytes = 0;
      uint64_t end = first;
      for (; end < triangles; ++end) {
        uint64_t add = 12;
        for (int k = 0; k < 3; ++k) {
          uint32_t& mark = remap[idx[end * 3 + k]];
          if (mark == ~0u) {
            mark = 0;
            add += vertex_bytes;
          }
        }
        if (bytes + add > budget && end > first) break;
        bytes += add;
      }
      const uint64_t last = std::min(end + 1, triangles);  // the refused triangle was marked too
      for (uint64_t i = first * 3; i < last * 3; ++i) remap[idx[i]] = ~0u;
      tws::extractMeshPart(mesh, first, end - first, remap, part);
      writeMesh(part);
      first = end;
    }
  }

  void writePrimitiveObject(const ObjectHead& head, const Primitive& primitive) {
    std::string problem = tws::primitiveProblem(primitive);
    if (!problem.empty()) head.reject(problem);
    tws::PrimitiveRecord prim{};
    prim.type = static_cast<uint32_t>(primitive.index());
    const std::vector<glm::vec2>* profile = nullptr;
    if (const auto* c = std::get_if<Cylinder>(&primitive)) {
      prim.flags = c->capped ? tws::kPrimitiveCapped : 0;
      prim.params[0] = c->radius;
      prim.params[1] = c->height;
    } else if (const auto* k = std::get_if<Cone>(&primitive)) {
      prim.flags = k->capped ? tws::kPrimitiveCapped : 0;
      prim.params[0] = k->radius_bottom;
      prim.params[1] = k->radius_top;
      prim.params[2] = k->height;
    } else if (const auto* sp = std::get_if<Sphere>(&primitive)) {
      prim.params[0] = sp->radius;
    } else if (const auto* t = std::get_if<TorusSegment>(&primitive)) {
      prim.params[0] = t->major_radius;
      prim.params[1] = t->minor_radius;
      prim.params[2] = t->sweep_rad;
    } else if (const auto* b = std::get_if<Box>(&primitive)) {
      prim.params[0] = b->half_extents.x;
      prim.params[1] = b->half_extents.y;
      prim.params[2] = b->half_extents.z;
    } else if (const auto* e = std::get_if<Extrusion>(&primitive)) {
      prim.params[0] = e->height;
      profile = &e->profile;
    } else if (const auto* r = std::get_if<Revolution>(&primitive)) {
      prim.params[0] = r->sweep_rad;
      profile = &r->profile;
    }
    if (profile) {
      if (head.head_bytes + sizeof prim + profile->size() * 8 > tws::kReaderMaxPayloadBytes)
        head.reject("profile too large for one chunk");
      prim.profile_count = static_cast<uint32_t>(profile->size());
    }
    beginObjectChunk(head);
    pieces.push_back({&prim, sizeof prim});
    if (profile) pieces.push_back({profile->data(), profile->size() * sizeof(glm::vec2)});
    writeChunk(tws::kChunkObject);
    countObjectChunk(head);
  }

  // A NURBS set in one chunk: its record, then each patch's record, knots and control points.
  void writeNurbsObject(const ObjectHead& head, const NurbsPatchSet& set) {
    uint64_t total = head.head_bytes + sizeof(tws::NurbsSetRecord);
    patch_records.resize(set.patches.size());
    for (size_t i = 0; i < set.patches.size(); ++i) {
      const NurbsPatch& patch = set.patches[i];
      std::string problem = validateNurbsPatch(patch);
      if (!problem.empty()) head.reject("NURBS patch " + std::to_string(i) + ": " + problem);
      patch_records[i] = {patch.degree_u, patch.degree_v, patch.count_u, patch.count_v};
      total += sizeof(tws::NurbsPatchRecord) +
               4 * (patch.knots_u.size() + patch.knots_v.size() + 4 * patch.control_points.size());
    }
    if (total > tws::kReaderMaxPayloadBytes) head.reject("NURBS patch set too large for one chunk");
    tws::NurbsSetRecord set_record{};
    set_record.patch_count = static_cast<uint32_t>(set.patches.size());
    beginObjectChunk(head);
    pieces.push_back({&set_record, sizeof set_record});
    for (size_t i = 0; i < set.patches.size(); ++i) {
      const NurbsPatch& patch = set.patches[i];
      pieces.push_back({&patch_records[i], sizeof(tws::NurbsPatchRecord)});
      pieces.push_back({patch.knots_u.data(), patch.knots_u.size() * sizeof(float)});
      pieces.push_back({patch.knots_v.data(), patch.knots_v.size() * sizeof(float)});
      pieces.push_back(
          {patch.control_points.data(), patch.control_points.size() * sizeof(glm::vec4)});
    }
    writeChunk(tws::kChunkObject);
    countObjectChunk(head);
  }
};

TwsWriter::TwsWriter(const std::filesystem::path& path) : state_(std::make_unique<State>()) {
  State& s = *state_;
  s.path = path;
  s.temp_path = path;
  s.temp_path += ".tmp";
  s.hash = XXH3_createState();
  if (!s.hash) throw std::bad_alloc();
  s.file = std::fopen(s.temp_path.string().c_str(), "wb");
  if (!s.file) s.ioFail("cannot create");
  s.io_buffer.resize(kIoBufferBytes);
  std::setvbuf(s.file, s.io_buffer.data(), _IOFBF, s.io_buffer.size());

  tws::FileHeader header{};
  std::memcpy(header.magic, tws::kMagic, sizeof header.magic);
  header.version = tws::kVersion;
  header.minor_version = tws::kMinorVersion;
  header.header_bytes = sizeof(tws::FileHeader);
  s.writeBytes(&header, sizeof header);
}

TwsWriter::~TwsWriter() {
  State& s = *state_;
  if (!s.finished) {
    if (s.file) std::fclose(s.file);
    s.file = nullptr;
    std::error_code ec;
    std::filesystem::remove(s.temp_path, ec);
  }
}

uint64_t TwsWriter::bytesWritten() const { return state_->bytes_written; }

void TwsWriter::onLayer(uint32_t index, const Layer& layer) {
  State& s = *state_;
  s.checkOpen("onLayer");
  if (index != s.layer_count)
    throw std::invalid_argument(s.path.string() + ": layer " + std::to_string(index) +
                                " declared out of order (expected " +
                                std::to_string(s.layer_count) + ")");
  if (layer.name.size() > tws::kMaxStringBytes)
    throw std::invalid_argument(s.path.string() + ": layer name longer than 65535 bytes");
  tws::LayerRecord record{};
  record.record_bytes = sizeof record;
  record.index = index;
  record.color_rgba = layer.color_rgba;
  record.name_bytes = static_cast<uint32_t>(layer.name.size());
  s.pieces.assign({{&record, sizeof record}, {layer.name.data(), layer.name.size()}});
  s.writeChunk(tws::kChunkLayer);
  ++s.layer_count;
}

void TwsWriter::onObject(const SceneObject& object) {
  State& s = *state_;
  s.checkOpen("onObject");
  const State::ObjectHead head = s.objectHead(object);
  if (const auto* mesh = std::get_if<TriangleMesh>(&object.geometry))
    s.writeMeshObject(head, *mesh);
  else if (const auto* primitive = std::get_if<Primitive>(&object.geometry))
    s.writePrimitiveObject(head, *primitive);
  else
    s.writeNurbsObject(head, std::get<NurbsPatchSet>(object.geometry));
}

void TwsWriter::finish() {
  State& s = *state_;
  s.checkOpen("finish");
  tws::EndRecord end{};
  end.chunk_count = s.chunk_count;
  end.object_chunk_count = s.object_chunk_count;
  end.object_count = s.object_count;
  end.layer_count = s.layer_count;
  s.pieces.assign({{&end, sizeof end}});
  s.writeChunk(tws::kChunkEnd);
  if (std::fflush(s.file) != 0) s.ioFail("cannot write");
  std::FILE* f = s.file;
  s.file = nullptr;
  if (std::fclose(f) != 0) s.ioFail("cannot close");
  std::error_code ec;
  std::filesystem::rename(s.temp_path, s.path, ec);
  if (ec)
    throw std::runtime_error(s.path.string() + ": cannot rename " + s.temp_path.string() +
                             " into place: " + ec.message());
  s.finished = true;
}

}  // namespace tw
