// glTF 2.0 / GLB reader over Debian's shared tinygltf.
//
// tinygltf parses the JSON and loads buffers; everything it hands back is treated as untrusted:
// every accessor, buffer view and index is range-checked here before a byte is read, because
// tinygltf itself does not check accessor ranges. File access goes through our own callbacks
// (regular files only, no path expansion) and images are never decoded, since we only need
// geometry. The GLB container is validated before tinygltf sees it so that errors carry a byte
// offset.
#include "gltf_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <tiny_gltf.h>

#include "file_reader.h"

namespace tw {
namespace {

constexpr uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;
constexpr uint64_t kMaxFileBytes = 0xffffffffu;  // tinygltf takes unsigned int lengths
// tinygltf converts "extras" recursively, so hostile nesting could exhaust the stack; real files
// nest a handful of levels.
constexpr int kMaxJsonDepth = 256;

// --- File access for tinygltf: plain regular files inside the model's folder, nothing
// expanded, nothing written. A uri of ../../etc/hostname or /etc/hostname is not followed. ---

// Whether `path` lies inside `folder` (both made canonical, so links and .. are resolved).
bool insideFolder(const std::string& path, const std::filesystem::path& folder) {
  std::error_code ec;
  const std::filesystem::path resolved = std::filesystem::weakly_canonical(path, ec);
  if (ec) return false;
  auto [f, r] = std::mismatch(folder.begin(), folder.end(), resolved.begin(), resolved.end());
  return f == folder.end();
}

const std::filesystem::path& modelFolder(void* user_data) {
  return *static_cast<const std::filesystem::path*>(user_data);
}

// Existence is answered plainly; reading refuses what lies outside, with the reason.
bool fileExists(const std::string& path, void*) {
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec);
}

std::string expandFilePath(const std::string& path, void*) { return path; }

bool readWholeFile(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                   void* user_data) {
  std::error_code ec;
  if (!insideFolder(path, modelFolder(user_data))) {
    if (err) *err += path + " lies outside the model's folder " + modelFolder(user_data).string() + "; not read\n";
    return false;
  }
  if (!std::filesystem::is_regular_file(path, ec)) {
    if (err) *err += "not a regular file: " + path + "\n";
    return false;
  }
  uint64_t size = std::filesystem::file_size(path, ec);
  if (ec || size > kMaxFileBytes) {
    if (err) *err += "cannot read (or larger than 4 GiB): " + path + "\n";
    return false;
  }
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) {
    if (err) *err += "cannot open: " + path + "\n";
    return false;
  }
  out->resize(static_cast<size_t>(size));
  size_t got = size ? std::fread(out->data(), 1, out->size(), f) : 0;
  std::fclose(f);
  if (got != size) {
    if (err) *err += "read error: " + path + "\n";
    return false;
  }
  return true;
}

bool refuseWrite(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "writing is disabled\n";
  return false;
}

// Images are not needed for geometry; accept them without decoding.
bool skipImage(tinygltf::Image*, const int, std::string*, std::string*, int, int,
               const unsigned char*, int, void*) {
  return true;
}

// Deepest nesting of arrays and objects in JSON text (strings skipped), or -1 if it exceeds
// kMaxJsonDepth.
int jsonDepth(const unsigned char* text, size_t size) {
  int depth = 0, deepest = 0;
  bool in_string = false;
  for (size_t i = 0; i < size; ++i) {
    unsigned char c = text[i];
    if (in_string) {
      if (c == '\\') ++i;
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonDepth) return -1;
      deepest = std::max(deepest, depth);
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return deepest;
}

// tinygltf's messages, joined into one line, each cut at kMostMessageChars (a bad data URI is
// quoted whole in its message: hundreds of kilobytes).
constexpr size_t kMostMessageChars = 300;

std::string oneLine(const std::string& text) {
  std::string out;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string message = text.substr(start, end - start);
    while (!message.empty() && message.back() == ' ') message.pop_back();
    if (message.size() > kMostMessageChars)
      message = message.substr(0, kMostMessageChars) + "... (" +
                std::to_string(message.size() - kMostMessageChars) + " more characters)";
    if (!message.empty()) out += (out.empty() ? "" : "; ") + message;
    start = end + 1;
  }
  return out;
}

// The extensions a file may require and still be read for its geometry: they change materials,
// textures or lights, which TeraWalk does not take. Any other required extension (Draco or
// meshopt compression, quantized or instanced meshes) changes the geometry itself.
bool geometryUnchangedBy(const std::string& extension) {
  static const char* const kIgnorable[] = {"KHR_texture_transform", "KHR_texture_basisu",
                                           "EXT_texture_webp", "KHR_lights_punctual",
                                           "KHR_materials_"};
  for (const char* prefix : kIgnorable)
    if (extension.rfind(prefix, 0) == 0) return true;
  return false;
}

uint32_t readU32(const std::vector<unsigned char>& bytes, size_t at) {
  uint32_t v;
  std::memcpy(&v, bytes.data() + at, 4);
  return v;  // GLB is little-endian, as is every platform we build for
}

uint8_t toByte(double v) {
  if (!(v > 0.0)) return 0;
  if (v >= 1.0) return 255;
  return static_cast<uint8_t>(std::lround(v * 255.0));
}

uint32_t packColor(const glm::dvec4& c) {
  return uint32_t{toByte(c.r)} | uint32_t{toByte(c.g)} << 8 | uint32_t{toByte(c.b)} << 16 |
         uint32_t{toByte(c.a)} << 24;
}

class GltfParser {
 public:
  GltfParser(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options)
      : path_(path),
        name_(path.string()),
        sink_(sink),
        options_(options),
        max_part_triangles_(std::max<uint32_t>(1, options.max_part_triangles)) {}

  void run() {
    load();
    sink_.onLayer(0, Layer{"default"});
    traverse();
  }

 private:
  [[noreturn]] void fail(const std::string& reason) const { throw FormatError(name_, reason); }

  // ---------------------------------------------------------------- loading

  void load() {
    std::vector<unsigned char> bytes;
    {
      FileReader in(path_);
      if (in.size() > kMaxFileBytes) fail("files larger than 4 GiB are not supported");
      bytes.resize(static_cast<size_t>(in.size()));
      if (!bytes.empty()) in.read(bytes.data(), bytes.size());
    }
    bool binary = bytes.size() >= 4 && readU32(bytes, 0) == kGlbMagic;
    std::string ext = path_.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext == ".glb") binary = true;
    if (binary) checkGlbContainer(bytes);
    const size_t json_start = binary ? 20 : 0;
    const size_t json_size = binary ? readU32(bytes, 12) : bytes.size();
    if (jsonDepth(bytes.data() + json_start, json_size) < 0)
      fail("JSON nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");

    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(&skipImage, nullptr);
    std::string base_dir = path_.parent_path().string();
    if (base_dir.empty()) base_dir = ".";
    std::error_code ec;
    std::filesystem::path folder = std::filesystem::weakly_canonical(base_dir, ec);
    if (ec) folder = base_dir;
    loader.SetFsCallbacks(tinygltf::FsCallbacks{&fileExists, &expandFilePath, &readWholeFile,
                                                &refuseWrite, &folder});
    checkByteCounts(bytes.data() + json_start, json_size);
    std::string err, warn;
    bool ok = false;
    try {
      if (binary)
        ok = loader.LoadBinaryFromMemory(&model_, &err, &warn, bytes.data(),
                                         static_cast<unsigned int>(bytes.size()), base_dir);
      else
        ok = loader.LoadASCIIFromString(&model_, &err, &warn,
                                        reinterpret_cast<const char*>(bytes.data()),
                                        static_cast<unsigned int>(bytes.size()), base_dir);
    } catch (const std::exception& e) {
      fail(std::string("glTF parse error: ") + e.what());
    }
    if (!ok) {
      std::string reason = oneLine(err);
      std::string warnings = oneLine(warn);
      if (reason.empty()) reason = warnings;
      else if (!warnings.empty()) reason += " (warnings: " + warnings + ")";
      fail("glTF: " + (reason.empty() ? std::string("cannot be loaded") : reason));
    }
    for (const std::string& extension : model_.extensionsRequired)
      if (!geometryUnchangedBy(extension))
        fail("requires the glTF extension " + extension + ", which TeraWalk cannot read");
  }

  // Offsets, lengths and counts must be whole, non-negative numbers: tinygltf reads -4 or 1e20
  // as 0 and says nothing, so they are checked in the JSON first.
  void checkByteCounts(const unsigned char* json, size_t size) const {
    const nlohmann::json doc = nlohmann::json::parse(json, json + size, nullptr, false);
    if (doc.is_discarded() || !doc.is_object()) return;  // tinygltf reports the syntax error
    auto check = [&](const char* array, std::initializer_list<const char*> keys) {
      auto it = doc.find(array);
      if (it == doc.end() || !it->is_array()) return;
      for (size_t i = 0; i < it->size(); ++i) {
        const nlohmann::json& item = (*it)[i];
        if (!item.is_object()) continue;
        for (const char* key : keys) {
          auto v = item.find(key);
          if (v == item.end()) continue;
          const bool whole = v->is_number_unsigned() || (v->is_number_integer() && v->get<int64_t>() >= 0);
          if (!whole || v->get<uint64_t>() > (uint64_t(1) << 53))
            fail(std::string(array) + "[" + std::to_string(i) + "]." + key + " is " +
                 v->dump().substr(0, 40) + ", not a whole number of at most 2^53");
        }
      }
    };
    check("buffers", {"byteLength"});
    check("bufferViews", {"byteOffset", "byteLength", "byteStride"});
    check("accessors", {"byteOffset", "count"});
  }

  // GLB layout: 12-byte header (magic, version, length), then chunks of (length, type, data).
  void checkGlbContainer(const std::vector<unsigned char>& bytes) const {
    if (bytes.size() < 12) throw FormatError::atByte(name_, bytes.size(), "GLB header truncated");
    if (readU32(bytes, 0) != kGlbMagic) throw FormatError::atByte(name_, 0, "not a GLB file (bad magic)");
    uint32_t version = readU32(bytes, 4);
    if (version != 2)
      throw FormatError::atByte(name_, 4, "unsupported GLB version " + std::to_string(version));
    uint64_t length = readU32(bytes, 8);
    if (length > bytes.size())
      throw FormatError::atByte(name_, 8, "GLB header says " + std::to_string(length) +
                                              " bytes but the file has " + std::to_string(bytes.size()));
    if (length < 20) throw FormatError::atByte(name_, 8, "GLB too short for a JSON chunk");
    uint64_t json_length = readU32(bytes, 12);
    if (readU32(bytes, 16) != kChunkJson)
      throw FormatError::atByte(name_, 16, "first GLB chunk is not JSON");
    if (20 + json_length > length)
      throw FormatError::atByte(name_, 12, "JSON chunk of " + std::to_string(json_length) +
                                               " bytes runs past the end of the file");
    uint64_t at = 20 + json_length;
    if (at < length) {
      if (length - at < 8) throw FormatError::atByte(name_, at, "truncated GLB chunk header");
      uint64_t chunk_length = readU32(bytes, at);
      if (at + 8 + chunk_length > length)
        throw FormatError::atByte(name_, at, "GLB chunk of " + std::to_string(chunk_length) +
                                                 " bytes runs past the end of the file");
    }
  }

  // ---------------------------------------------------------------- accessors

  // A validated view of an accessor's elements.
  struct Span {
    const unsigned char* data = nullptr;
    size_t count = 0;
    size_t stride = 0;
    int component_type = 0;
    int components = 0;
    bool normalized = false;
  };

  Span accessorSpan(int index, const char* what) const {
    std::string label = std::string(what) + " accessor " + std::to_string(index);
    if (index < 0 || static_cast<size_t>(index) >= model_.accessors.size())
      fail(label + " does not exist");
    const tinygltf::Accessor& a = model_.accessors[static_cast<size_t>(index)];
    if (a.sparse.isSparse) fail(label + ": sparse accessors are not supported");
    if (a.bufferView < 0 || static_cast<size_t>(a.bufferView) >= model_.bufferViews.size())
      fail(label + ": missing or invalid bufferView " + std::to_string(a.bufferView));
    const tinygltf::BufferView& view = model_.bufferViews[static_cast<size_t>(a.bufferView)];
    if (view.buffer < 0 || static_cast<size_t>(view.buffer) >= model_.buffers.size())
      fail(label + ": buffer view " + std::to_string(a.bufferView) + " names invalid buffer " +
           std::to_string(view.buffer));
    const tinygltf::Buffer& buffer = model_.buffers[static_cast<size_t>(view.buffer)];
    int component_bytes = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(a.componentType));
    int components = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(a.type));
    if (component_bytes <= 0) fail(label + ": invalid component type " + std::to_string(a.componentType));
    if (components <= 0) fail(label + ": invalid type " + std::to_string(a.type));
    using U128 = unsigned __int128;
    const U128 element = static_cast<U128>(component_bytes) * static_cast<U128>(components);
    const U128 stride = view.byteStride ? static_cast<U128>(view.byteStride) : element;
    if (stride < element)
      fail(label + ": byteStride " + std::to_string(view.byteStride) + " is smaller than an element");
    if (static_cast<U128>(view.byteOffset) + view.byteLength > buffer.data.size())
      fail(label + ": buffer view " + std::to_string(a.bufferView) + " (offset " +
           std::to_string(view.byteOffset) + ", length " + std::to_string(view.byteLength) +
           ") lies outside buffer " + std::to_string(view.buffer) + " of " +
           std::to_string(buffer.data.size()) + " bytes");
    Span span;
    span.count = a.count;
    if (a.count > 0) {
      U128 end = static_cast<U128>(a.byteOffset) + static_cast<U128>(a.count - 1) * stride + element;
      if (end > view.byteLength)
        fail(label + ": " + std::to_string(a.count) + " elements at offset " +
             std::to_string(a.byteOffset) + " overrun buffer view " + std::to_string(a.bufferView) +
             " of " + std::to_string(view.byteLength) + " bytes");
      span.data = buffer.data.data() + view.byteOffset + a.byteOffset;
    }
    span.stride = static_cast<size_t>(stride);
    span.component_type = a.componentType;
    span.components = components;
    span.normalized = a.normalized;
    return span;
  }

  Span floatVec3(int index, const char* what) const {
    Span s = accessorSpan(index, what);
    if (s.component_type != TINYGLTF_COMPONENT_TYPE_FLOAT || s.components != 3)
      fail(std::string(what) + " accessor " + std::to_string(index) + " must be float VEC3");
    return s;
  }

  static glm::vec3 loadVec3(const Span& s, size_t i) {
    glm::vec3 v;
    std::memcpy(&v, s.data + i * s.stride, sizeof(v));
    return v;
  }

  glm::dvec4 loadColor(const Span& s, size_t i) const {
    const unsigned char* p = s.data + i * s.stride;
    glm::dvec4 c(1.0);
    for (int k = 0; k < s.components; ++k) {
      switch (s.component_type) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT: {
          float f;
          std::memcpy(&f, p + 4 * k, 4);
          c[k] = f;
          break;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: c[k] = p[k] / 255.0; break;
        default: {
          uint16_t u;
          std::memcpy(&u, p + 2 * k, 2);
          c[k] = u / 65535.0;
        }
      }
    }
    return c;
  }

  // ---------------------------------------------------------------- meshes

  glm::dvec4 materialColor(int material) const {
    if (material < 0 || static_cast<size_t>(material) >= model_.materials.size()) return glm::dvec4(1.0);
    const auto& f = model_.materials[static_cast<size_t>(material)].pbrMetallicRoughness.baseColorFactor;
    glm::dvec4 c(1.0);
    for (size_t k = 0; k < 4 && k < f.size(); ++k) c[static_cast<glm::length_t>(k)] = f[k];
    return c;
  }

  static bool isTriangles(const tinygltf::Primitive& p) {
    return p.mode == -1 || p.mode == TINYGLTF_MODE_TRIANGLES ||
           p.mode == TINYGLTF_MODE_TRIANGLE_STRIP || p.mode == TINYGLTF_MODE_TRIANGLE_FAN;
  }

  static int attribute(const tinygltf::Primitive& p, const char* name) {
    auto it = p.attributes.find(name);
    return it == p.attributes.end() ? -1 : it->second;
  }

  void emitMesh(const tinygltf::Node& node, size_t node_index, const glm::dmat4& world) {
    if (node.mesh < 0 || static_cast<size_t>(node.mesh) >= model_.meshes.size())
      fail("node " + std::to_string(node_index) + " names invalid mesh " + std::to_string(node.mesh));
    const tinygltf::Mesh& mesh = model_.meshes[static_cast<size_t>(node.mesh)];

    // Decide the object's attributes over all its triangle primitives first.
    bool all_normals = true, any_vertex_colors = false, any_triangles = false;
    int first_material = -2;
    bool mixed_materials = false;
    for (const auto& p : mesh.primitives) {
      if (!isTriangles(p)) continue;
      any_triangles = true;
      all_normals = all_normals && attribute(p, "NORMAL") >= 0;
      any_vertex_colors = any_vertex_colors || attribute(p, "COLOR_0") >= 0;
      if (first_material == -2) first_material = p.material;
      else if (p.material != first_material) mixed_materials = true;
    }
    if (!any_triangles) return;

    part_ = SceneObject{};
    ObjectInfo& info = part_.info;
    info.id = next_id_++;
    info.name = !node.name.empty() ? node.name
                : !mesh.name.empty() ? mesh.name
                                     : "node " + std::to_string(node_index);
    info.layer = 0;
    info.color_rgba = packColor(materialColor(first_material));
    info.transform.origin = glm::dvec3(world[3]);
    info.transform.linear = glm::mat3(glm::dmat3(world));
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r)
        if (!std::isfinite(info.transform.linear[c][r]) || !std::isfinite(info.transform.origin[c]))
          fail("node " + std::to_string(node_index) + " has a non-finite transform");
    part_.geometry = TriangleMesh{};
    mesh_ = &std::get<TriangleMesh>(part_.geometry);
    with_normals_ = all_normals;
    with_colors_ = any_vertex_colors || mixed_materials;

    for (size_t pi = 0; pi < mesh.primitives.size(); ++pi) {
      const tinygltf::Primitive& p = mesh.primitives[pi];
      if (!isTriangles(p)) continue;
      emitPrimitive(p, "mesh " + std::to_string(node.mesh) + " primitive " + std::to_string(pi));
    }
    flushPart();
  }

  void emitPrimitive(const tinygltf::Primitive& p, const std::string& label) {
    int position_index = attribute(p, "POSITION");
    if (position_index < 0) fail(label + " has no POSITION");
    positions_ = floatVec3(position_index, "POSITION");
    const size_t vertices = positions_.count;
    if (vertices >= 0xffffffffu) fail(label + ": too many vertices");
    normals_ = Span{};
    if (with_normals_) {
      normals_ = floatVec3(attribute(p, "NORMAL"), "NORMAL");
      if (normals_.count != vertices) fail(label + ": NORMAL count differs from POSITION count");
    }
    colors_ = Span{};
    int color_index = attribute(p, "COLOR_0");
    if (with_colors_ && color_index >= 0) {
      colors_ = accessorSpan(color_index, "COLOR_0");
      bool ok_type = colors_.component_type == TINYGLTF_COMPONENT_TYPE_FLOAT ||
                     colors_.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                     colors_.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
      if (!ok_type || (colors_.components != 3 && colors_.components != 4))
        fail(label + ": COLOR_0 must be VEC3 or VEC4 of float, unsigned byte or unsigned short");
      if (colors_.count != vertices) fail(label + ": COLOR_0 count differs from POSITION count");
    }
    material_color_ = materialColor(p.material);
    for (size_t i = 0; i < vertices; ++i) {
      glm::vec3 v = loadVec3(positions_, i);
      if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
        fail(label + ": non-finite position " + std::to_string(i));
    }

    // Corner list: the index accessor, or 0..n-1 when the primitive is not indexed.
    Span index_span;
    size_t corners = vertices;
    if (p.indices >= 0) {
      index_span = accessorSpan(p.indices, "indices");
      if (index_span.components != 1 ||
          (index_span.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
           index_span.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
           index_span.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
        fail(label + ": indices must be unsigned byte, short or int scalars");
      corners = index_span.count;
    }
    auto corner = [&](size_t k) -> uint32_t {
      if (p.indices < 0) return static_cast<uint32_t>(k);
      const unsigned char* at = index_span.data + k * index_span.stride;
      uint32_t value;
      switch (index_span.component_type) {
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: value = *at; break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
          uint16_t u;
          std::memcpy(&u, at, 2);
          value = u;
          break;
        }
        default: std::memcpy(&value, at, 4);
      }
      if (value >= vertices)
        fail(label + ": index " + std::to_string(value) + " at " + std::to_string(k) +
             " is out of range (" + std::to_string(vertices) + " vertices)");
      return value;
    };

    // Each primitive has its own vertex numbering: a new stamp generation.
    if (remap_.size() < vertices) remap_.resize(vertices);
    nextStamp();
    const int mode = p.mode == -1 ? TINYGLTF_MODE_TRIANGLES : p.mode;
    if (mode == TINYGLTF_MODE_TRIANGLES) {
      if (corners % 3 != 0)
        fail(label + ": " + std::to_string(corners) + " triangle corners is not a multiple of 3");
      for (size_t k = 0; k + 2 < corners; k += 3) addTriangle(corner(k), corner(k + 1), corner(k + 2));
    } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
      for (size_t k = 2; k < corners; ++k) {
        if (k % 2 == 0) addTriangle(corner(k - 2), corner(k - 1), corner(k));
        else addTriangle(corner(k - 1), corner(k - 2), corner(k));
      }
    } else {  // fan
      for (size_t k = 2; k < corners; ++k) addTriangle(corner(0), corner(k - 1), corner(k));
    }
  }

  void addTriangle(uint32_t a, uint32_t b, uint32_t c) {
    if (mesh_->triangleCount() >= max_part_triangles_) {
      flushPart();
      nextStamp();
    }
    mesh_->indices.push_back(localVertex(a));
    mesh_->indices.push_back(localVertex(b));
    mesh_->indices.push_back(localVertex(c));
  }

  uint32_t localVertex(uint32_t v) {
    RemapSlot& slot = remap_[v];
    if (slot.stamp == stamp_) return slot.local;
    slot.stamp = stamp_;
    slot.local = static_cast<uint32_t>(mesh_->positions.size());
    mesh_->positions.push_back(loadVec3(positions_, v));
    if (with_normals_) mesh_->normals.push_back(loadVec3(normals_, v));
    if (with_colors_) {
      glm::dvec4 c = material_color_;
      if (colors_.data) c *= loadColor(colors_, v);
      mesh_->colors.push_back(packColor(c));
    }
    return slot.local;
  }

  void nextStamp() {
    if (++stamp_ == 0) {
      for (RemapSlot& s : remap_) s.stamp = 0;
      stamp_ = 1;
    }
  }

  void flushPart() {
    if (mesh_->indices.empty()) return;
    sink_.onObject(part_);
    mesh_->positions.clear();
    mesh_->normals.clear();
    mesh_->colors.clear();
    mesh_->indices.clear();
  }

  // ---------------------------------------------------------------- scene graph

  static glm::dmat4 localMatrix(const tinygltf::Node& node) {
    if (node.matrix.size() == 16) {
      glm::dmat4 m;
      for (int i = 0; i < 16; ++i) m[i / 4][i % 4] = node.matrix[static_cast<size_t>(i)];  // column-major
      return m;
    }
    glm::dmat4 m(1.0);
    if (node.translation.size() == 3)
      m[3] = glm::dvec4(node.translation[0], node.translation[1], node.translation[2], 1.0);
    if (node.rotation.size() == 4) {
      glm::dquat q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
      double len = glm::length(q);
      if (len > 0.0 && std::isfinite(len)) q /= len;
      glm::dmat3 r = glm::mat3_cast(q);
      for (int c = 0; c < 3; ++c) m[c] = glm::dvec4(r[c], 0.0);
    }
    if (node.scale.size() == 3)
      for (int c = 0; c < 3; ++c) m[c] *= node.scale[static_cast<size_t>(c)];
    return m;
  }

  void traverse() {
    const size_t node_count = model_.nodes.size();
    std::vector<int> roots;
    if (!model_.scenes.empty()) {
      size_t scene = 0;
      if (model_.defaultScene >= 0) {
        if (static_cast<size_t>(model_.defaultScene) >= model_.scenes.size())
          fail("default scene " + std::to_string(model_.defaultScene) + " does not exist");
        scene = static_cast<size_t>(model_.defaultScene);
      }
      roots = model_.scenes[scene].nodes;
    } else {
      std::vector<bool> is_child(node_count, false);
      for (const auto& n : model_.nodes)
        for (int c : n.children)
          if (c >= 0 && static_cast<size_t>(c) < node_count) is_child[static_cast<size_t>(c)] = true;
      for (size_t i = 0; i < node_count; ++i)
        if (!is_child[i]) roots.push_back(static_cast<int>(i));
    }

    beginStage(options_.progress, "read glTF", node_count);
    std::vector<bool> visited(node_count, false);
    std::vector<std::pair<int, glm::dmat4>> stack;
    for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.emplace_back(*it, glm::dmat4(1.0));
    uint64_t done = 0;
    while (!stack.empty()) {
      auto [index, parent] = stack.back();
      stack.pop_back();
      if (index < 0 || static_cast<size_t>(index) >= node_count)
        fail("reference to node " + std::to_string(index) + " which does not exist");
      const size_t ni = static_cast<size_t>(index);
      if (visited[ni])
        fail("node " + std::to_string(index) + " is reached twice (cycle or node with two parents)");
      visited[ni] = true;
      const tinygltf::Node& node = model_.nodes[ni];
      glm::dmat4 world = parent * localMatrix(node);
      if (node.mesh >= 0) emitMesh(node, ni, world);
      for (auto c = node.children.rbegin(); c != node.children.rend(); ++c) stack.emplace_back(*c, world);
      updateProgress(options_.progress, ++done);
      if (options_.progress && options_.progress->cancelled()) return;
    }
    endStage(options_.progress);
  }

  struct RemapSlot {
    uint32_t stamp = 0;
    uint32_t local = 0;
  };

  std::filesystem::path path_;
  std::string name_;
  SceneSink& sink_;
  const ReadOptions& options_;
  uint32_t max_part_triangles_;
  tinygltf::Model model_;
  uint32_t next_id_ = 0;

  // Object being emitted.
  SceneObject part_;
  TriangleMesh* mesh_ = nullptr;
  bool with_normals_ = false;
  bool with_colors_ = false;
  // Primitive being emitted.
  Span positions_, normals_, colors_;
  glm::dvec4 material_color_{1.0};
  std::vector<RemapSlot> remap_;
  uint32_t stamp_ = 0;
};

}  // namespace

void readGltf(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options) {
  GltfParser(path, sink, options).run();
}

}  // namespace tw
