// PlyWriter: vertices go straight into the temporary output file behind a fixed-size header
// placeholder, faces into a side file; finish() writes the real header into the placeholder (the
// slack taken up by a comment line), appends the faces and renames the file into place. Memory
// stays at one object's tessellation plus a staging buffer whatever the scene size.
#include "ply_writer.h"

#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "tessellate.h"

namespace tw {
namespace {

// Room for the header with 20-digit counts and then some; the rest is a comment line.
constexpr size_t kHeaderBytes = 512;
constexpr size_t kVertexBytes = 15;  // float x, y, z; uchar red, green, blue
constexpr size_t kFaceBytes = 13;    // uchar 3; int a, b, c
constexpr size_t kStagingBytes = size_t{1} << 20;
constexpr uint32_t kGrey = 0xff808080u;
// Indices are written as PLY "int".
constexpr uint64_t kMaxVertices = static_cast<uint64_t>(std::numeric_limits<int32_t>::max()) + 1;

inline void putLe32(char* p, uint32_t v) {
  p[0] = static_cast<char>(v);
  p[1] = static_cast<char>(v >> 8);
  p[2] = static_cast<char>(v >> 16);
  p[3] = static_cast<char>(v >> 24);
}

std::string headerText(uint64_t vertices, uint64_t faces) {
  std::string h = "ply\nformat binary_little_endian 1.0\ncomment written by TeraWalk\n";
  h += "element vertex " + std::to_string(vertices) + "\n";
  h += "property float x\nproperty float y\nproperty float z\n";
  h += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  h += "element face " + std::to_string(faces) + "\n";
  h += "property list uchar int vertex_indices\n";
  // Pad to exactly kHeaderBytes with a comment: every PLY reader ignores comments, which is not
  // true of leading zeros or trailing blanks in the counts.
  const std::string end = "end_header\n";
  const std::string pad_start = "comment padding";
  size_t used = h.size() + pad_start.size() + 1 + end.size();
  h += pad_start + std::string(kHeaderBytes - used, ' ') + "\n" + end;
  return h;
}

}  // namespace

struct PlyWriter::State {
  std::filesystem::path path;
  std::filesystem::path temp_path;
  std::filesystem::path faces_path;
  float tolerance = kDefaultChordalTolerance;
  std::FILE* main = nullptr;
  std::FILE* faces = nullptr;
  std::vector<uint32_t> layer_colors;  // 0 where a layer was not declared
  uint64_t vertices = 0;
  uint64_t triangles = 0;
  bool finished = false;
  std::vector<char> staging;
  TriangleMesh scratch;

  [[noreturn]] void fail(const std::string& what, int error) const {
    throw std::runtime_error("PLY writer: " + what + " " + path.string() + ": " +
                             std::strerror(error));
  }
  void write(std::FILE* f, const char* data, size_t bytes) {
    if (bytes && std::fwrite(data, 1, bytes, f) != bytes) fail("cannot write", errno);
  }
  void flushStaging(std::FILE* f) {
    write(f, staging.data(), staging.size());
    staging.clear();
  }
  void closeAndRemove() {
    if (main) std::fclose(main);
    if (faces) std::fclose(faces);
    main = faces = nullptr;
    std::error_code ec;
    std::filesystem::remove(temp_path, ec);
    std::filesystem::remove(faces_path, ec);
  }
};

PlyWriter::PlyWriter(const std::filesystem::path& path, float tolerance)
    : state_(std::make_unique<State>()) {
  State& s = *state_;
  s.path = path;
  s.temp_path = path;
  s.temp_path += ".tmp";
  s.faces_path = path;
  s.faces_path += ".faces.tmp";
  s.tolerance = tolerance;
  s.main = std::fopen(s.temp_path.string().c_str(), "wb");
  if (!s.main) s.fail("cannot create", errno);
  s.faces = std::fopen(s.faces_path.string().c_str(), "w+b");
  if (!s.faces) {
    int error = errno;
    s.closeAndRemove();
    s.fail("cannot create a side file for", error);
  }
  s.staging.reserve(kStagingBytes + 64);
  std::string header = headerText(0, 0);  // placeholder; finish() writes the real counts
  try {
    s.write(s.main, header.data(), header.size());
  } catch (...) {
    s.closeAndRemove();
    throw;
  }
}

PlyWriter::~PlyWriter() {
  if (state_ && !state_->finished) state_->closeAndRemove();
}

void PlyWriter::onLayer(uint32_t index, const Layer& layer) {
  State& s = *state_;
  if (s.layer_colors.size() <= index) s.layer_colors.resize(size_t{index} + 1, 0);
  s.layer_colors[index] = layer.color_rgba;
}

void PlyWriter::onObject(const SceneObject& object) {
  State& s = *state_;
  if (s.finished || !s.main)
    throw std::runtime_error("PLY writer: object after finish() for " + s.path.string());
  const TriangleMesh* mesh = std::get_if<TriangleMesh>(&object.geometry);
  if (!mesh) {
    s.scratch.positions.clear();
    s.scratch.normals.clear();
    s.scratch.colors.clear();
    s.scratch.indices.clear();
    tessellate(object.geometry, s.tolerance, s.scratch);
    mesh = &s.scratch;
  }
  const uint64_t n = mesh->positions.size();
  if (n == 0 || mesh->indices.size() < 3) return;
  if (s.vertices + n > kMaxVertices)
    throw std::runtime_error("PLY writer: " + s.path.string() +
                             ": more than 2^31 vertices do not fit PLY int indices");
  for (uint32_t index : mesh->indices)
    if (index >= n)
      throw std::runtime_error("PLY writer: object '" + object.info.name + "' has index " +
                               std::to_string(index) + " out of range for " + s.path.string());

  // Object colour, else the mesh's own vertex colours, else the layer's colour, else grey.
  uint32_t color = object.info.color_rgba;
  const bool vertex_colors = color == 0 && mesh->colors.size() == n;
  if (color == 0 && object.info.layer < s.layer_colors.size())
    color = s.layer_colors[object.info.layer];
  if (color == 0) color = kGrey;

  const Transform& t = object.info.transform;
  for (uint64_t i = 0; i < n; ++i) {
    glm::vec3 w = glm::vec3(t.apply(mesh->positions[i]));
    uint32_t c = vertex_colors ? mesh->colors[i] : color;
    char record[kVertexBytes];
    putLe32(record + 0, std::bit_cast<uint32_t>(w.x));
    putLe32(record + 4, std::bit_cast<uint32_t>(w.y));
    putLe32(record + 8, std::bit_cast<uint32_t>(w.z));
    record[12] = static_cast<char>(c & 0xff);
    record[13] = static_cast<char>((c >> 8) & 0xff);
    record[14] = static_cast<char>((c >> 16) & 0xff);
    s.staging.insert(s.staging.end(), record, record + kVertexBytes);
    if (s.staging.size() >= kStagingBytes) s.flushStaging(s.main);
  }
  s.flushStaging(s.main);

  const uint32_t base = static_cast<uint32_t>(s.vertices);
  const size_t triangles = mesh->indices.size() / 3;
  for (size_t f = 0; f < triangles; ++f) {
    char record[kFaceBytes];
    record[0] = 3;
    for (int k = 0; k < 3; ++k) putLe32(record + 1 + 4 * k, base + mesh->indices[3 * f + k]);
    s.staging.insert(s.staging.end(), record, record + kFaceBytes);
    if (s.staging.size() >= kStagingBytes) s.flushStaging(s.faces);
  }
  s.flushStaging(s.faces);
  s.vertices += n;
  s.triangles += triangles;
}

void PlyWriter::finish() {
  State& s = *state_;
  if (s.finished) return;
  if (!s.main) throw std::runtime_error("PLY writer: " + s.path.string() + " is not open");
  std::string header = headerText(s.vertices, s.triangles);
  if (std::fflush(s.faces) != 0) s.fail("cannot write", errno);
  if (std::fseek(s.main, 0, SEEK_SET) != 0) s.fail("cannot seek in", errno);
  s.write(s.main, header.data(), header.size());
  if (std::fseek(s.main, 0, SEEK_END) != 0) s.fail("cannot seek in", errno);
  if (std::fseek(s.faces, 0, SEEK_SET) != 0) s.fail("cannot seek in the side file of", errno);
  s.staging.resize(kStagingBytes);
  for (;;) {
    size_t got = std::fread(s.staging.data(), 1, kStagingBytes, s.faces);
    if (got == 0) {
      if (std::ferror(s.faces)) s.fail("cannot read back the side file of", errno);
      break;
    }
    s.write(s.main, s.staging.data(), got);
  }
  s.staging.clear();
  if (std::fflush(s.main) != 0) s.fail("cannot write", errno);
  int closed = std::fclose(s.main);
  s.main = nullptr;
  if (closed != 0) s.fail("cannot close", errno);
  std::fclose(s.faces);
  s.faces = nullptr;
  std::error_code ec;
  std::filesystem::remove(s.faces_path, ec);
  std::filesystem::rename(s.temp_path, s.path, ec);
  if (ec)
    throw std::runtime_error("PLY writer: cannot rename " + s.temp_path.string() + " to " +
                             s.path.string() + ": " + ec.message());
  s.finished = true;
}

uint64_t PlyWriter::vertexCount() const { return state_->vertices; }
uint64_t PlyWriter::triangleCount() const { return state_->triangles; }

}  // namespace tw
