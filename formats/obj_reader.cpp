// Streaming Wavefront OBJ reader.
//
// OBJ indices are global to the file, so the position, normal and colour pools are kept for the
// whole read (16-20 bytes per vertex, plus 8 for the remap slot). Faces are not: they go into the
// current object part, which is handed to the sink as soon as it is full or the object ends.
// A part holds only the vertices its faces use; the global -> local remap is a stamped array
// indexed by global vertex, so the per-corner hot path does one array access and no hashing.
//
// Object rules (see docs/readers-obj-gltf.md):
//  - "o NAME" and "g NAME..." start a new object, but only if the current one has faces; a run of
//    o/g statements with no faces between them just renames the pending object.
//  - "usemtl NAME" selects layer NAME (declared on first use; layer 0 is "default"). A change of
//    layer after faces starts a new object with the same name and a new id, so that every object
//    lies on exactly one layer.
//  - Ids count from 0 in order of the first face of each object; empty objects get no id.
#include "obj_reader.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "file_reader.h"
#include "part_vertex_map.h"
#include "spilled_array.h"
#include "text_scan.h"

namespace tw {
namespace {

// Eighths of ReadOptions::vertex_memory_bytes a pool keeps before it spills: positions 4,
// normals 3, colours 1.
uint64_t share(const ReadOptions& options, uint64_t eighths) {
  if (options.vertex_memory_bytes == 0) return 0;
  return std::max<uint64_t>(1, options.vertex_memory_bytes / 8 * eighths);
}

constexpr uint32_t kNone = 0xffffffffu;
constexpr uint64_t kLinesPerProgressCheck = 1u << 16;

uint8_t toByte(float v) {
  v = std::clamp(v, 0.0f, 1.0f);
  return static_cast<uint8_t>(std::lround(v * 255.0f));
}

uint32_t packColor(float r, float g, float b, float a = 1.0f) {
  return uint32_t{toByte(r)} | uint32_t{toByte(g)} << 8 | uint32_t{toByte(b)} << 16 |
         uint32_t{toByte(a)} << 24;
}

std::string_view trimmed(std::string_view s) {
  text::skipBlanks(s);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

// Material colours from a .mtl file: Kd (diffuse) and d (opacity) of each newmtl.
void readMaterialLibrary(const std::filesystem::path& path,
                         std::unordered_map<std::string, uint32_t>& colors) {
  FileReader in(path);
  std::string current;
  float rgb[3] = {0.69f, 0.69f, 0.69f};
  float alpha = 1.0f;
  bool have_material = false;
  auto store = [&] {
    if (have_material) colors.emplace(current, packColor(rgb[0], rgb[1], rgb[2], alpha));
  };
  std::string_view line;
  while (in.readLine(line)) {
    std::string_view keyword = text::nextToken(line);
    if (keyword == "newmtl") {
      store();
      current = std::string(trimmed(line));
      rgb[0] = rgb[1] = rgb[2] = 0.69f;
      alpha = 1.0f;
      have_material = true;
    } else if (keyword == "Kd") {
      if (!text::parseFloat(line, rgb[0]) || !text::parseFloat(line, rgb[1]) ||
          !text::parseFloat(line, rgb[2]))
        in.failAtLine("bad Kd colour: expected three numbers");
    } else if (keyword == "d") {
      if (!text::parseFloat(line, alpha)) in.failAtLine("bad d (opacity): expected a number");
    }
  }
  store();
}

class ObjParser {
 public:
  ObjParser(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options)
      : in_(path),
        sink_(sink),
        options_(options),
        directory_(path.parent_path()),
        stem_(path.stem().string()),
        max_part_triangles_(std::max<uint32_t>(1, options.max_part_triangles)),
        positions_(share(options, 4), options.spill_dir),
        normals_(share(options, 3), options.spill_dir),
        colors_(share(options, 1), options.spill_dir),
        // A part never holds more distinct vertices than the file has references ("1 " at
        // least), so a small file gets a small table, not one sized for a million triangles.
        remap_(std::min<uint64_t>(uint64_t{max_part_triangles_} * 3, in_.size() / 2 + 16)) {
    part_.geometry = TriangleMesh{};
    mesh_ = &std::get<TriangleMesh>(part_.geometry);
    object_name_ = stem_;
  }

  void run() {
    sink_.onLayer(0, Layer{"default"});
    layer_names_.emplace("default", 0);
    beginStage(options_.progress, "read OBJ", in_.size());
    std::string_view line;
    uint64_t next_check = kLinesPerProgressCheck;
    if (in_.readLine(line)) {
      if (line.substr(0, 3) == "\xEF\xBB\xBF") line.remove_prefix(3);  // UTF-8 byte order mark
      statement(line);
    }
    while (in_.readLine(line)) {
      if (in_.line() >= next_check) {
        next_check += kLinesPerProgressCheck;
        updateProgress(options_.progress, in_.offset());
        if (options_.progress && options_.progress->cancelled()) return;
      }
      statement(line);
    }
    flushPart();
    updateProgress(options_.progress, in_.size());
    endStage(options_.progress);
  }

 private:
  struct Corner {
    uint32_t v;
    uint32_t vn;
  };

  void statement(std::string_view line) {
    text::skipBlanks(line);
    if (line.empty() || line[0] == '#') return;
    if (line.back() == '\\') in_.failAtLine("line continuation '\\' is not supported");
    // The common statements are dispatched on their first bytes without building a token.
    if (line.size() >= 2 && (line[1] == ' ' || line[1] == '\t')) {
      std::string_view rest = line.substr(2);
      switch (line[0]) {
        case 'v': return parseVertex(rest);
        case 'f': return parseFace(rest);
        case 'o': return startObject(trimmed(rest));
        case 'g': return startObject(groupName(rest));
        default: return;  // s, l, p and others: ignored
      }
    }
    std::string_view keyword = text::nextToken(line);
    if (keyword == "vn") return parseNormal(line);
    if (keyword == "vt") return parseTexCoord(line);
    if (keyword == "usemtl") return useMaterial(trimmed(line));
    if (keyword == "mtllib") return loadMaterials(trimmed(line));
    if (keyword == "o") return startObject({});
    if (keyword == "g") return startObject({});
    if (keyword == "f") in_.failAtLine("'f' without data");
    if (keyword == "v") in_.failAtLine("'v' without data");
    // Anything else (s, l, p, vp, curv, surf, ...) is ignored on purpose.
  }

  static std::string groupName(std::string_view rest) {
    std::string name;
    for (std::string_view t = text::nextToken(rest); !t.empty(); t = text::nextToken(rest)) {
      if (!name.empty()) name += ' ';
      name += t;
    }
    return name;
  }

  void parseVertex(std::string_view rest) {
    float p[3];
    if (!text::parseFloat(rest, p[0]) || !text::parseFloat(rest, p[1]) ||
        !text::parseFloat(rest, p[2]))
      in_.failAtLine("bad vertex: expected numbers x y z");
    float extra[4];
    int extras = 0;
    text::skipBlanks(rest);
    while (!rest.empty()) {
      if (extras == 4 || !text::parseFloat(rest, extra[extras]))
        in_.failAtLine("bad vertex: expected x y z [w] or x y z r g b");
      ++extras;
      text::skipBlanks(rest);
    }
    if (extras == 2 || extras == 4) in_.failAtLine("bad vertex: expected x y z [w] or x y z r g b");
    if (positions_.size() >= kNone - 1) in_.failAtLine("more than 4 billion vertices");
    positions_.push_back(glm::vec3(p[0], p[1], p[2]));
    if (extras == 3) {
      // Colours are rare: the pool is only created at the first coloured vertex.
      while (colors_.size() + 1 < positions_.size()) colors_.push_back(0);
      colors_.push_back(packColor(extra[0], extra[1], extra[2]));
    } else if (!colors_.empty()) {
      colors_.push_back(0);  // 0 = no colour given (real colours always have alpha 255)
    }
  }

  void parseNormal(std::string_view rest) {
    float n[3];
    if (!text::parseFloat(rest, n[0]) || !text::parseFloat(rest, n[1]) ||
        !text::parseFloat(rest, n[2]))
      in_.failAtLine("bad normal: expected numbers x y z");
    if (normals_.size() >= kNone - 1) in_.failAtLine("more than 4 billion normals");
    normals_.push_back(glm::vec3(n[0], n[1], n[2]));
  }

  void parseTexCoord(std::string_view rest) {
    float t;
    if (!text::parseFloat(rest, t)) in_.failAtLine("bad texture coordinate: expected u [v [w]]");
    for (int i = 0; i < 2; ++i) {
      text::skipBlanks(rest);
      if (rest.empty()) break;
      if (!text::parseFloat(rest, t)) in_.failAtLine("bad texture coordinate: expected u [v [w]]");
    }
    text::skipBlanks(rest);
    if (!rest.empty()) in_.failAtLine("bad texture coordinate: expected u [v [w]]");
    ++texcoord_count_;
  }

  // 1-based or negative (relative) OBJ index -> 0-based index below `count`.
  uint32_t resolve(int64_t index, uint64_t count, const char* what) {
    if (index > 0 && static_cast<uint64_t>(index) <= count) return static_cast<uint32_t>(index - 1);
    if (index < 0 && static_cast<uint64_t>(-index) <= count)
      return static_cast<uint32_t>(static_cast<int64_t>(count) + index);
    if (index == 0) in_.failAtLine(std::string(what) + " index 0 (OBJ indices start at 1)");
    in_.failAtLine(std::string(what) + " index " + std::to_string(index) + " out of range (" +
                   std::to_string(count) + " defined so far)");
  }

  void parseFace(std::string_view rest) {
    corners_.clear();
    text::skipBlanks(rest);
    while (!rest.empty()) {
      int64_t index;
      if (!text::parseInt64(rest, index)) in_.failAtLine("bad face: expected vertex indices");
      Corner c{resolve(index, positions_.size(), "vertex"), kNone};
      if (!rest.empty() && rest[0] == '/') {
        rest.remove_prefix(1);
        if (!rest.empty() && rest[0] != '/') {
          if (!text::parseInt64(rest, index)) in_.failAtLine("bad face: bad texture index");
          resolve(index, texcoord_count_, "texture coordinate");
        }
        if (!rest.empty() && rest[0] == '/') {
          rest.remove_prefix(1);
          if (!text::parseInt64(rest, index)) in_.failAtLine("bad face: bad normal index");
          c.vn = resolve(index, normals_.size(), "normal");
        }
        if (!rest.empty() && rest[0] == '/') in_.failAtLine("bad face: too many '/' in a corner");
      }
      corners_.push_back(c);
      text::skipBlanks(rest);
    }
    if (corners_.size() < 3)
      in_.failAtLine("face with " + std::to_string(corners_.size()) + " vertices (at least 3 needed)");
    addPolygon();
  }

  void addPolygon() {
    if (!object_has_id_) {
      object_id_ = next_object_id_++;
      object_has_id_ = true;
    }
    const size_t n = corners_.size();
    const uint64_t triangles = n - 2;
    std::vector<uint32_t>& indices = mesh_->indices;
    if (mesh_->triangleCount() + triangles <= max_part_triangles_) {
      // Common case: the whole polygon fits; map each corner once.
      locals_.resize(n);
      for (size_t i = 0; i < n; ++i) locals_[i] = localVertex(corners_[i]);
      for (size_t i = 2; i < n; ++i) {
        indices.push_back(locals_[0]);
        indices.push_back(locals_[i - 1]);
        indices.push_back(locals_[i]);
      }
      return;
    }
    // A polygon straddling a part boundary: map per triangle, since each part has its own
    // local vertex numbering.
    for (size_t i = 2; i < n; ++i) {
      if (mesh_->triangleCount() >= max_part_triangles_) flushPart();
      uint32_t a = localVertex(corners_[0]);
      uint32_t b = localVertex(corners_[i - 1]);
      uint32_t c = localVertex(corners_[i]);
      indices.push_back(a);
      indices.push_back(b);
      indices.push_back(c);
    }
  }

  // The part-local vertex for a corner. A vertex used with two different normals in one part
  // (a hard edge) becomes two local vertices; those rare pairs go through a hash map.
  uint32_t localVertex(const Corner& c) {
    if (c.vn == kNone) part_missing_normal_ = true;
    const uint32_t local = remap_.find(c.v);
    if (local != PartVertexMap::kNone) {
      uint32_t vn = local_normal_[local];
      if (vn == c.vn || vn == kNone || c.vn == kNone) return local;
      uint64_t key = uint64_t{c.v} << 32 | c.vn;
      auto [it, inserted] = split_vertices_.try_emplace(key, 0);
      if (inserted) it->second = newLocal(c);
      return it->second;
    }
    return remap_.localOf(c.v, [&] { return newLocal(c); });
  }

  uint32_t newLocal(const Corner& c) {
    local_global_.push_back(c.v);
    local_normal_.push_back(c.vn);
    return static_cast<uint32_t>(local_global_.size() - 1);
  }

  // Hands the current part to the sink and starts an empty one for the same object.
  void flushPart() {
    if (mesh_->indices.empty()) return;
    const size_t n = local_global_.size();
    mesh_->positions.resize(n);
    for (size_t i = 0; i < n; ++i) mesh_->positions[i] = positions_[local_global_[i]];
    mesh_->normals.clear();
    if (!part_missing_normal_) {
      mesh_->normals.resize(n);
      for (size_t i = 0; i < n; ++i) mesh_->normals[i] = normals_[local_normal_[i]];
    }
    mesh_->colors.clear();
    if (!colors_.empty()) {
      bool any = false;
      for (size_t i = 0; i < n && !any; ++i)
        any = local_global_[i] < colors_.size() && colors_[local_global_[i]] != 0;
      if (any) {
        mesh_->colors.resize(n);
        for (size_t i = 0; i < n; ++i) {
          uint32_t c = local_global_[i] < colors_.size() ? colors_[local_global_[i]] : 0;
          mesh_->colors[i] = c ? c : 0xffffffffu;  // uncoloured vertices among coloured: white
        }
      }
    }
    part_.info.id = object_id_;
    part_.info.name = object_name_;
    part_.info.layer = layer_;
    sink_.onObject(part_);

    mesh_->positions.clear();
    mesh_->normals.clear();
    mesh_->colors.clear();
    mesh_->indices.clear();
    local_global_.clear();
    local_normal_.clear();
    split_vertices_.clear();
    part_missing_normal_ = false;
    remap_.clear();
  }

  // Ends the current object if it has faces; the next faces belong to a new one.
  void endObjectIfNotEmpty() {
    if (!object_has_id_) return;
    flushPart();
    object_has_id_ = false;
  }

  void startObject(std::string_view name) {
    endObjectIfNotEmpty();
    object_name_ = name.empty() ? stem_ : std::string(name);
  }

  void useMaterial(std::string_view name) {
    if (name.empty()) in_.failAtLine("usemtl without a material name");
    std::string key(name);
    auto it = layer_names_.find(key);
    uint32_t layer;
    if (it != layer_names_.end()) {
      layer = it->second;
    } else {
      layer = static_cast<uint32_t>(layer_names_.size());
      Layer declared{key};
      auto color = material_colors_.find(key);
      if (color != material_colors_.end()) declared.color_rgba = color->second;
      sink_.onLayer(layer, declared);
      layer_names_.emplace(std::move(key), layer);
    }
    if (layer == layer_) return;
    endObjectIfNotEmpty();
    layer_ = layer;
  }

  // mtllib takes one or more file names; a missing file is not an error (colours are optional).
  void loadMaterials(std::string_view names) {
    std::error_code ec;
    auto tryLoad = [&](std::string_view name) {
      std::filesystem::path p = directory_ / std::filesystem::path(std::string(name));
      if (!std::filesystem::is_regular_file(p, ec)) return false;
      try {
        readMaterialLibrary(p, material_colors_);
      } catch (const FormatError& e) {
        // Name the OBJ and its mtllib line as well as the material file's own position.
        in_.failAtLine("material library: " + std::string(e.what()));
      }
      return true;
    };
    if (names.empty() || tryLoad(names)) return;  // the whole rest may be one name with spaces
    for (std::string_view t = text::nextToken(names); !t.empty(); t = text::nextToken(names))
      tryLoad(t);
  }

  FileReader in_;
  SceneSink& sink_;
  const ReadOptions& options_;
  std::filesystem::path directory_;
  std::string stem_;
  uint32_t max_part_triangles_;

  // Global pools (the OBJ index space), spilled past ReadOptions::vertex_memory_bytes.
  SpilledArray<glm::vec3> positions_;
  SpilledArray<glm::vec3> normals_;
  SpilledArray<uint32_t> colors_;  // empty, or one per position (0 = none)
  PartVertexMap remap_;            // global position -> part-local vertex
  uint64_t texcoord_count_ = 0;

  // Current object and part.
  std::string object_name_;
  uint32_t object_id_ = 0;
  bool object_has_id_ = false;
  uint32_t next_object_id_ = 0;
  uint32_t layer_ = 0;
  SceneObject part_;
  TriangleMesh* mesh_ = nullptr;
  std::vector<uint32_t> local_global_;  // part-local vertex -> global position
  std::vector<uint32_t> local_normal_;  // part-local vertex -> global normal or kNone
  std::unordered_map<uint64_t, uint32_t> split_vertices_;
  bool part_missing_normal_ = false;

  // Scratch for one face.
  std::vector<Corner> corners_;
  std::vector<uint32_t> locals_;

  std::unordered_map<std::string, uint32_t> layer_names_;
  std::unordered_map<std::string, uint32_t> material_colors_;
};

}  // namespace

void readObj(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options) {
  ObjParser(path, sink, options).run();
}

}  // namespace tw
