// Streaming STL reader. A file is binary exactly when its size is 84 + 50 * (the triangle count at
// byte 80), whatever its first bytes say: many binary exporters start the 80-byte header with
// "solid". Anything else must be ASCII. Triangles are handed over in parts with three fresh
// vertices each (STL shares none).
#include "stl_reader.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "file_reader.h"
#include "text_scan.h"

namespace tw {
namespace {

// Binary STL is little-endian; records are copied as they are.
static_assert(std::endian::native == std::endian::little,
              "binary STL reading assumes a little-endian host");

constexpr size_t kReaderBufferBytes = size_t{4} << 20;
constexpr uint64_t kProgressStepBytes = uint64_t{8} << 20;
constexpr uint64_t kBinaryHeaderBytes = 84;
constexpr uint64_t kBinaryTriangleBytes = 50;

// Accumulates the triangles of one object and hands them on in parts.
class Parts {
 public:
  Parts(SceneSink& sink, uint32_t max_triangles)
      : sink_(sink), max_triangles_(max_triangles ? max_triangles : 1) {}

  void begin(ObjectInfo info) {
    part_.info = std::move(info);
    part_.geometry = TriangleMesh{};
    mesh().positions.reserve(std::min<size_t>(size_t{max_triangles_} * 3, size_t{1} << 18));
    mesh().indices.reserve(std::min<size_t>(size_t{max_triangles_} * 3, size_t{1} << 18));
  }
  void add(const glm::vec3& p) {
    TriangleMesh& m = mesh();
    m.indices.push_back(static_cast<uint32_t>(m.positions.size()));
    m.positions.push_back(p);
  }
  // Call after each complete triangle.
  void endTriangle() {
    if (mesh().indices.size() >= size_t{max_triangles_} * 3) flush();
  }
  void flush() {
    TriangleMesh& m = mesh();
    if (m.indices.empty()) return;
    sink_.onObject(part_);
    m.positions.clear();
    m.indices.clear();
  }

 private:
  TriangleMesh& mesh() { return *std::get_if<TriangleMesh>(&part_.geometry); }

  SceneSink& sink_;
  uint32_t max_triangles_;
  SceneObject part_;
};

ObjectInfo objectInfo(uint32_t id, std::string name) {
  ObjectInfo info;
  info.id = id;
  info.name = std::move(name);
  info.layer = 0;
  return info;
}

inline bool finite(const glm::vec3& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

void readBinary(FileReader& reader, uint64_t triangles, const std::string& name, SceneSink& sink,
                const ReadOptions& options) {
  reader.seek(kBinaryHeaderBytes);
  Parts parts(sink, options.max_part_triangles);
  parts.begin(objectInfo(0, name));
  uint64_t next_progress = 0;
  for (uint64_t done = 0; done < triangles;) {
    std::string_view view = reader.peek(kReaderBufferBytes);
    uint64_t n = std::min<uint64_t>(triangles - done, view.size() / kBinaryTriangleBytes);
    if (n == 0) reader.fail("binary STL truncated after " + std::to_string(done) + " triangles");
    for (uint64_t i = 0; i < n; ++i) {
      const char* record = view.data() + i * kBinaryTriangleBytes;
      glm::vec3 v[3];
      std::memcpy(v, record + 12, sizeof(v));  // after the facet normal, which we ignore
      if (!finite(v[0]) || !finite(v[1]) || !finite(v[2]))
        reader.failAt(reader.offset() + i * kBinaryTriangleBytes,
                      "triangle " + std::to_string(done + i) + " has a non-finite vertex");
      for (const glm::vec3& p : v) parts.add(p);
      parts.endTriangle();
    }
    reader.consume(static_cast<size_t>(n * kBinaryTriangleBytes));
    done += n;
    if (options.progress && reader.offset() >= next_progress) {
      options.progress->update(reader.offset());
      next_progress = reader.offset() + kProgressStepBytes;
    }
  }
  parts.flush();
}

bool equalsNoCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(a[i])) !=
        std::tolower(static_cast<unsigned char>(b[i])))
      return false;
  return true;
}

std::string shown(std::string_view s) {
  std::string out = "'";
  for (size_t i = 0; i < s.size() && i < 40; ++i) {
    auto c = static_cast<unsigned char>(s[i]);
    out += (c >= 32 && c < 127) ? static_cast<char>(c) : '?';
  }
  if (s.size() > 40) out += "...";
  return out + "'";
}

// ASCII grammar, one keyword per line, keywords in any case:
//   solid [name] { facet ... outer loop (vertex x y z){3,} endloop endfacet }* endsolid [name]
// A loop of more than three vertices is fan-triangulated (some exporters write quads).
void readAscii(FileReader& reader, const std::string& stem, SceneSink& sink,
               const ReadOptions& options) {
  enum class State { OutsideSolid, InSolid, InFacet, InLoop, AfterLoop };
  State state = State::OutsideSolid;
  Parts parts(sink, options.max_part_triangles);
  uint32_t solid_index = 0;
  uint64_t loop_vertices = 0;
  glm::vec3 first{0.0f}, previous{0.0f};
  uint64_t next_progress = 0;
  std::string_view line;
  while (reader.readLine(line)) {
    std::string_view rest = line;
    std::string_view key = text::nextToken(rest);
    if (key.empty()) continue;
    auto expect = [&](const char* what) {
      reader.failAtLine("expected " + std::string(what) + ", found " + shown(key));
    };
    switch (state) {
      case State::OutsideSolid: {
        if (!equalsNoCase(key, "solid")) expect("'solid'");
        text::skipBlanks(rest);
        std::string name(rest);
        while (!name.empty() && (name.back() == ' ' || name.back() == '\t')) name.pop_back();
        parts.begin(objectInfo(solid_index, name.empty() ? stem : name));
        state = State::InSolid;
        break;
      }
      case State::InSolid:
        if (equalsNoCase(key, "facet")) {
          state = State::InFacet;
        } else if (equalsNoCase(key, "endsolid")) {
          parts.flush();
          ++solid_index;
          state = State::OutsideSolid;
        } else {
          expect("'facet' or 'endsolid'");
        }
        break;
      case State::InFacet:
        if (!equalsNoCase(key, "outer") || !equalsNoCase(text::nextToken(rest), "loop"))
          expect("'outer loop'");
        loop_vertices = 0;
        state = State::InLoop;
        break;
      case State::InLoop:
        if (equalsNoCase(key, "vertex")) {
          glm::vec3 p;
          if (!text::parseFloat(rest, p.x) || !text::parseFloat(rest, p.y) ||
              !text::parseFloat(rest, p.z))
            reader.failAtLine("expected three numbers after 'vertex'");
          text::skipBlanks(rest);
          if (!rest.empty())
            reader.failAtLine("unexpected '" + std::string(rest.substr(0, 32)) +
                              "' after the vertex's three numbers");
          if (loop_vertices == 0) {
            first = p;
          } else if (loop_vertices >= 2) {
            parts.add(first);
            parts.add(previous);
            parts.add(p);
            parts.endTriangle();
          }
          previous = p;
          ++loop_vertices;
        } else if (equalsNoCase(key, "endloop")) {
          if (loop_vertices < 3)
            reader.failAtLine("a facet loop with " + std::to_string(loop_vertices) +
                              " vertices (at least 3 needed)");
          state = State::AfterLoop;
        } else {
          expect("'vertex' or 'endloop'");
        }
        break;
      case State::AfterLoop:
        if (!equalsNoCase(key, "endfacet")) expect("'endfacet'");
        state = State::InSolid;
        break;
    }
    if (options.progress && reader.offset() >= next_progress) {
      options.progress->update(reader.offset());
      next_progress = reader.offset() + kProgressStepBytes;
    }
  }
  if (state != State::OutsideSolid)
    reader.failAtLine("the file ends inside a solid (no 'endsolid')");
  if (solid_index == 0) reader.failAtLine("no 'solid' in the file");
}

}  // namespace

void readStl(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options) {
  FileReader reader(path, kReaderBufferBytes);  // sized down to small files by FileReader
  beginStage(options.progress, "read", reader.size());
  const std::string stem = path.stem().string();
  bool binary = false;
  uint32_t count = 0;
  if (reader.size() >= kBinaryHeaderBytes) {
    reader.seek(80);
    count = reader.readValue<uint32_t>();  // little-endian on disk; we run on little-endian hosts
    binary = reader.size() == kBinaryHeaderBytes + kBinaryTriangleBytes * uint64_t{count};
    reader.seek(0);
  }
  if (!binary) {
    std::string_view rest = reader.peek(512);
    rest = rest.substr(0, rest.find('\n'));  // nextToken() does not stop at line breaks
    if (!equalsNoCase(text::nextToken(rest), "solid")) {
      std::string why =
          reader.size() >= kBinaryHeaderBytes
              ? "not a binary STL (" + std::to_string(reader.size()) +
                    " bytes, but a triangle count of " + std::to_string(count) + " needs " +
                    std::to_string(kBinaryHeaderBytes + kBinaryTriangleBytes * uint64_t{count}) +
                    ") nor an ASCII one (no 'solid' at the start)"
              : "too short for a binary STL and not an ASCII one (no 'solid' at the start)";
      reader.failAt(0, why);
    }
  }
  sink.onLayer(0, Layer{"default"});
  if (binary)
    readBinary(reader, count, stem, sink, options);
  else
    readAscii(reader, stem, sink, options);
  updateProgress(options.progress, reader.offset());
  endStage(options.progress);
}

}  // namespace tw
