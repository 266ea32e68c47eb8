// Wavefront OBJ writer: streams objects to a temporary file and renames it into place on finish().
// Layer colours go to a companion NAME.mtl (Kd, d) written at finish(), so they also survive.
//
// Vertices are written in world space (the double-precision transform applied) with 9 significant
// digits, which keeps 0.1 mm at 10 km from the datum. Each object is preceded by a comment
// "# layer NAME key KEY" and a "usemtl LAYER" so that layers survive a round trip through our own
// reader. Consecutive parts of one object (same id) are written under one "o" statement.
#include "obj_writer.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "tessellate.h"

namespace tw {
namespace {

constexpr size_t kFlushBytes = size_t{4} << 20;

// Names go on one line after a keyword: line breaks would end the statement early.
std::string oneLine(const std::string& s) {
  std::string out = s;
  for (char& c : out)
    if (c == '\n' || c == '\r' || c == '\0') c = ' ';
  return out;
}

// Appends " 0.xxxx": one RGBA8 channel as a 0..1 fraction (4 decimals round-trip all 256 levels).
void appendColorChannel(std::string& out, uint32_t rgba, int shift) {
  char tmp[16];
  double v = static_cast<double>((rgba >> shift) & 0xffu) / 255.0;
  auto result = std::to_chars(tmp, tmp + sizeof(tmp), v, std::chars_format::fixed, 4);
  out.push_back(' ');
  out.append(tmp, result.ptr);
}

}  // namespace

struct ObjWriter::State {
  std::filesystem::path path;
  std::filesystem::path temp_path;
  std::FILE* file = nullptr;
  float tolerance = kDefaultChordalTolerance;
  std::string buffer;
  std::vector<std::string> layer_names;
  std::vector<uint32_t> layer_colors;
  std::filesystem::path mtl_path;
  std::filesystem::path mtl_temp_path;
  uint64_t vertex_count = 0;  // written so far: the next "v" is number vertex_count + 1
  uint64_t normal_count = 0;
  bool have_previous = false;
  uint32_t previous_id = 0;
  bool finished = false;
  TriangleMesh scratch;

  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(path.string() + ": " + what + ": " + std::strerror(errno));
  }

  void flush() {
    if (buffer.empty()) return;
    if (std::fwrite(buffer.data(), 1, buffer.size(), file) != buffer.size()) fail("write failed");
    buffer.clear();
  }
  void maybeFlush() {
    if (buffer.size() >= kFlushBytes) flush();
  }

  void number(double v) {
    char tmp[32];
    auto result = std::to_chars(tmp, tmp + sizeof(tmp), v, std::chars_format::general, 9);
    buffer.push_back(' ');
    buffer.append(tmp, result.ptr);
  }
  void integer(uint64_t v) {
    char tmp[24];
    auto result = std::to_chars(tmp, tmp + sizeof(tmp), v);
    buffer.append(tmp, result.ptr);
  }

  void writeMesh(const TriangleMesh& mesh, const Transform& transform) {
    const bool has_normals = !mesh.normals.empty() && mesh.normals.size() == mesh.positions.size();
    const bool has_colors = !mesh.colors.empty() && mesh.colors.size() == mesh.positions.size();
    const uint64_t base_v = vertex_count;
    const uint64_t base_n = normal_count;
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
      glm::dvec3 p = transform.apply(mesh.positions[i]);
      // "nan" or "inf" would make a file that no OBJ reader (ours included) accepts.
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw std::runtime_error(path.string() + ": non-finite vertex position in the scene");
      buffer += 'v';
      number(p.x);
      number(p.y);
      number(p.z);
      if (has_colors) {
        appendColorChannel(buffer, mesh.colors[i], 0);
        appendColorChannel(buffer, mesh.colors[i], 8);
        appendColorChannel(buffer, mesh.colors[i], 16);
      }
      buffer += '\n';
      maybeFlush();
    }
    vertex_count += mesh.positions.size();
    if (has_normals) {
      // Normals transform by the inverse transpose of the linear part.
      glm::mat3 normal_matrix = glm::transpose(glm::inverse(transform.linear));
      for (const glm::vec3& n : mesh.normals) {
        glm::vec3 w = normal_matrix * n;
        float len = glm::length(w);
        // A singular linear part has no normal matrix: write a zero normal rather than "nan".
        w = len > 0.0f && std::isfinite(len) ? w / len : glm::vec3(0.0f);
        buffer += "vn";
        number(w.x);
        number(w.y);
        number(w.z);
        buffer += '\n';
        maybeFlush();
      }
      normal_count += mesh.normals.size();
    }
    const uint64_t vertices = mesh.positions.size();
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
      // Indices that point outside the mesh would produce a file no reader accepts.
      if (mesh.indices[t] >= vertices || mesh.indices[t + 1] >= vertices ||
          mesh.indices[t + 2] >= vertices)
        throw std::runtime_error(path.string() + ": triangle index out of range in mesh");
      buffer += 'f';
      for (int k = 0; k < 3; ++k) {
        buffer += ' ';
        integer(base_v + mesh.indices[t + k] + 1);
        if (has_normals) {
          buffer += "//";
          integer(base_n + mesh.indices[t + k] + 1);
        }
      }
      buffer += '\n';
      maybeFlush();
    }
  }

  // The companion .mtl: one material per named layer, written whole and renamed into place
  // before the OBJ that refers to it.
  void writeMaterials() {
    std::string text = "# layer colours for " + oneLine(path.filename().string()) + "\n";
    bool any = false;
    for (size_t i = 0; i < layer_names.size(); ++i) {
      if (layer_names[i].empty()) continue;
      any = true;
      text += "newmtl " + layer_names[i] + "\nKd";
      appendColorChannel(text, layer_colors[i], 0);
      appendColorChannel(text, layer_colors[i], 8);
      appendColorChannel(text, layer_colors[i], 16);
      text += "\nd";
      appendColorChannel(text, layer_colors[i], 24);
      text += '\n';
    }
    if (!any) return;
    std::FILE* f = std::fopen(mtl_temp_path.string().c_str(), "wb");
    if (!f) fail("cannot create " + mtl_temp_path.string());
    bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
    ok = std::fclose(f) == 0 && ok;
    if (!ok) fail("write failed: " + mtl_temp_path.string());
    std::error_code ec;
    std::filesystem::rename(mtl_temp_path, mtl_path, ec);
    if (ec) throw std::runtime_error(mtl_path.string() + ": cannot rename temporary file: " + ec.message());
  }
};

ObjWriter::ObjWriter(const std::filesystem::path& path, float tolerance)
    : state_(std::make_unique<State>()) {
  state_->path = path;
  state_->temp_path = path;
  state_->temp_path += ".tmp";
  state_->mtl_path = path;
  state_->mtl_path.replace_extension(".mtl");
  if (state_->mtl_path == path) state_->mtl_path += ".mtl";
  state_->mtl_temp_path = state_->mtl_path;
  state_->mtl_temp_path += ".tmp";
  state_->tolerance = tolerance;
  state_->file = std::fopen(state_->temp_path.string().c_str(), "wb");
  if (!state_->file) state_->fail("cannot create " + state_->temp_path.string());
  state_->buffer.reserve(kFlushBytes + 4096);
  state_->buffer += "# written by TeraWalk\nmtllib ";
  state_->buffer += oneLine(state_->mtl_path.filename().string());
  state_->buffer += '\n';
}

ObjWriter::~ObjWriter() {
  if (!state_ || state_->finished) return;
  if (state_->file) std::fclose(state_->file);
  std::error_code ec;
  std::filesystem::remove(state_->temp_path, ec);
  std::filesystem::remove(state_->mtl_temp_path, ec);
}

void ObjWriter::onLayer(uint32_t index, const Layer& layer) {
  if (state_->layer_names.size() <= index) state_->layer_names.resize(index + 1);
  state_->layer_names[index] = oneLine(layer.name);
  if (state_->layer_colors.size() <= index) state_->layer_colors.resize(index + 1, Layer{}.color_rgba);
  state_->layer_colors[index] = layer.color_rgba;
}

void ObjWriter::onObject(const SceneObject& object) {
  State& s = *state_;
  if (s.finished) throw std::runtime_error(s.path.string() + ": object written after finish()");
  const ObjectInfo& info = object.info;
  if (!s.have_previous || s.previous_id != info.id) {
    std::string layer = info.layer < s.layer_names.size() ? s.layer_names[info.layer] : "";
    s.buffer += "# layer ";
    s.buffer += layer;
    s.buffer += " key ";
    s.buffer += oneLine(info.db_key);
    s.buffer += "\no ";
    s.buffer += info.name.empty() ? "object" + std::to_string(info.id) : oneLine(info.name);
    s.buffer += '\n';
    if (!layer.empty()) {
      s.buffer += "usemtl ";
      s.buffer += layer;
      s.buffer += '\n';
    }
    s.have_previous = true;
    s.previous_id = info.id;
  }
  if (const auto* mesh = std::get_if<TriangleMesh>(&object.geometry)) {
    s.writeMesh(*mesh, info.transform);
  } else {
    s.scratch.positions.clear();
    s.scratch.normals.clear();
    s.scratch.colors.clear();
    s.scratch.indices.clear();
    tessellate(object.geometry, s.tolerance, s.scratch);
    s.writeMesh(s.scratch, info.transform);
  }
  s.maybeFlush();
}

void ObjWriter::finish() {
  State& s = *state_;
  if (s.finished) return;
  s.flush();
  std::FILE* f = s.file;
  s.file = nullptr;
  if (std::fflush(f) != 0) {
    std::fclose(f);
    s.fail("write failed");
  }
  if (std::fclose(f) != 0) s.fail("close failed");
  s.writeMaterials();
  std::error_code ec;
  std::filesystem::rename(s.temp_path, s.path, ec);
  if (ec) throw std::runtime_error(s.path.string() + ": cannot rename temporary file: " + ec.message());
  s.finished = true;
}

}  // namespace tw
