// Streaming PLY reader: parse the header, check every element count against the bytes left, then
// walk the elements in file order. The vertex element fills a vertex table (the only thing kept);
// the face element is fan-triangulated and handed to the sink in parts that carry only the
// vertices they use. The common binary layout (float x y z; uchar-count int-index triangles) has a
// fast path over the reader's buffer; every other layout goes through the general path.
#include "ply_reader.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "file_reader.h"
#include "part_vertex_map.h"
#include "spilled_array.h"
#include "text_scan.h"

namespace tw {
namespace {

constexpr size_t kReaderBufferBytes = size_t{4} << 20;
constexpr uint64_t kProgressStepBytes = uint64_t{8} << 20;
// Bounds on the header so that a hostile one cannot make us allocate much: real files have a
// handful of elements with a handful of properties each.
constexpr size_t kMaxElements = 1024;
constexpr size_t kMaxProperties = 1024;  // per element

// ---- Scalar types --------------------------------------------------------------------------

enum class Scalar : uint8_t { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool parseScalar(std::string_view name, Scalar& out) {
  struct Entry {
    std::string_view name, alias;
    Scalar type;
  };
  static constexpr Entry kEntries[] = {
      {"char", "int8", Scalar::Int8},        {"uchar", "uint8", Scalar::UInt8},
      {"short", "int16", Scalar::Int16},     {"ushort", "uint16", Scalar::UInt16},
      {"int", "int32", Scalar::Int32},       {"uint", "uint32", Scalar::UInt32},
      {"float", "float32", Scalar::Float32}, {"double", "float64", Scalar::Float64}};
  for (const Entry& e : kEntries)
    if (name == e.name || name == e.alias) {
      out = e.type;
      return true;
    }
  return false;
}

uint32_t sizeOf(Scalar t) {
  static constexpr uint8_t kSizes[] = {1, 1, 2, 2, 4, 4, 4, 8};  // in Scalar's order
  return kSizes[static_cast<int>(t)];
}

bool isFloat(Scalar t) { return t == Scalar::Float32 || t == Scalar::Float64; }

template <typename T>
inline T loadRaw(const char* p, bool swap) {
  T value;
  if (!swap) {
    std::memcpy(&value, p, sizeof(T));
  } else {
    char bytes[sizeof(T)];
    for (size_t i = 0; i < sizeof(T); ++i) bytes[i] = p[sizeof(T) - 1 - i];
    std::memcpy(&value, bytes, sizeof(T));
  }
  return value;
}

double loadDouble(const char* p, Scalar t, bool swap) {
  switch (t) {
    case Scalar::Int8: return loadRaw<int8_t>(p, swap);
    case Scalar::UInt8: return loadRaw<uint8_t>(p, swap);
    case Scalar::Int16: return loadRaw<int16_t>(p, swap);
    case Scalar::UInt16: return loadRaw<uint16_t>(p, swap);
    case Scalar::Int32: return loadRaw<int32_t>(p, swap);
    case Scalar::UInt32: return loadRaw<uint32_t>(p, swap);
    case Scalar::Float32: return loadRaw<float>(p, swap);
    case Scalar::Float64: return loadRaw<double>(p, swap);
  }
  return 0.0;
}

// A file's text quoted for an error message: short, and printable whatever the bytes were.
std::string shown(std::string_view s) {
  std::string out = "'";
  for (size_t i = 0; i < s.size() && i < 40; ++i) {
    auto c = static_cast<unsigned char>(s[i]);
    out += (c >= 32 && c < 127) ? static_cast<char>(c) : '?';
  }
  if (s.size() > 40) out += "...";
  return out + "'";
}

// ---- Header ---------------------------------------------------------------------------------

struct Property {
  std::string name;
  Scalar type = Scalar::Float32;  // the item type for a list
  bool is_list = false;
  Scalar count_type = Scalar::UInt8;
};

struct Element {
  std::string name;
  uint64_t count = 0;
  uint64_t line = 0;  // where it was declared, for errors
  std::vector<Property> properties;

  // Smallest record in a binary file: every scalar, and an empty list's count.
  uint64_t minRecordBytes() const {
    uint64_t n = 0;
    for (const Property& p : properties) n += p.is_list ? sizeOf(p.count_type) : sizeOf(p.type);
    return n;
  }
  bool hasLists() const {
    for (const Property& p : properties)
      if (p.is_list) return true;
    return false;
  }
};

enum class Encoding { Ascii, LittleEndian, BigEndian };

struct Header {
  Encoding encoding = Encoding::Ascii;
  std::vector<Element> elements;
};

Header parseHeader(FileReader& reader) {
  std::string_view line;
  {
    bool got = reader.readLine(line);
    std::string_view rest = line;
    if (!got || text::nextToken(rest) != "ply" || !text::nextToken(rest).empty())
      throw FormatError::atLine(reader.name(), 1, "not a PLY file (the first line must be 'ply')");
  }
  Header header;
  bool have_format = false;
  for (;;) {
    if (!reader.readLine(line)) reader.failAtLine("the header ends without 'end_header'");
    std::string_view rest = line;
    std::string_view key = text::nextToken(rest);
    if (key.empty() || key == "comment" || key == "obj_info") continue;
    if (key == "end_header") break;
    if (key == "format") {
      std::string_view kind = text::nextToken(rest);
      std::string_view version = text::nextToken(rest);
      if (kind == "ascii")
        header.encoding = Encoding::Ascii;
      else if (kind == "binary_little_endian")
        header.encoding = Encoding::LittleEndian;
      else if (kind == "binary_big_endian")
        header.encoding = Encoding::BigEndian;
      else
        reader.failAtLine("unknown PLY format " + shown(kind));
      if (version != "1.0" && version != "1")
        reader.failAtLine("unsupported PLY version " + shown(version) + " (only 1.0 is known)");
      have_format = true;
    } else if (key == "element") {
      Element e;
      e.name = std::string(text::nextToken(rest));
      int64_t count = -1;
      if (e.name.empty() || !text::parseInt64(rest, count) || count < 0)
        reader.failAtLine("bad element declaration (expected 'element NAME COUNT')");
      if (header.elements.size() >= kMaxElements)
        reader.failAtLine("more than " + std::to_string(kMaxElements) + " elements");
      e.count = static_cast<uint64_t>(count);
      e.line = reader.line();
      header.elements.push_back(std::move(e));
    } else if (key == "property") {
      if (header.elements.empty()) reader.failAtLine("property declared before any element");
      Element& e = header.elements.back();
      if (e.properties.size() >= kMaxProperties)
        reader.failAtLine("more than " + std::to_string(kMaxProperties) +
                          " properties in element " + shown(e.name));
      Property p;
      std::string_view type = text::nextToken(rest);
      if (type == "list") {
        p.is_list = true;
        std::string_view count_type = text::nextToken(rest);
        if (!parseScalar(count_type, p.count_type))
          reader.failAtLine("unknown list count type " + shown(count_type));
        if (isFloat(p.count_type))
          reader.failAtLine("list count type " + shown(count_type) + " is not an integer type");
        type = text::nextToken(rest);
      }
      if (!parseScalar(type, p.type)) reader.failAtLine("unknown property type " + shown(type));
      p.name = std::string(text::nextToken(rest));
      if (p.name.empty()) reader.failAtLine("property without a name");
      e.properties.push_back(std::move(p));
    } else {
      reader.failAtLine("unknown header keyword " + shown(key));
    }
  }
  if (!have_format) reader.failAtLine("the header has no 'format' line");
  return header;
}

// Rejects counts that the remaining bytes cannot hold, before anything is sized from them.
void checkCounts(const FileReader& reader, const Header& header) {
  const uint64_t remaining = reader.remaining();
  uint64_t needed = 0;  // minimum bytes of all elements so far
  for (const Element& e : header.elements) {
    if (e.count == 0 || e.properties.empty()) continue;
    // ASCII: each record is at least one digit and a line break (the last may lack the break).
    uint64_t record = header.encoding == Encoding::Ascii ? 2 : e.minRecordBytes();
    uint64_t available = remaining + (header.encoding == Encoding::Ascii ? 1 : 0);
    if (e.count > (available - std::min(needed, available)) / record) {
      throw FormatError::atLine(reader.name(), e.line,
                                "element " + shown(e.name) + " declares " +
                                    std::to_string(e.count) + " records (at least " +
                                    std::to_string(record) + " bytes each) but only " +
                                    std::to_string(remaining) +
                                    " bytes follow the header: the file is truncated or "
                                    "the count is wrong");
    }
    needed += e.count * record;
  }
}

// ---- Vertex table and parts -----------------------------------------------------------------

enum Role : uint8_t { kNone, kX, kY, kZ, kNx, kNy, kNz, kRed, kGreen, kBlue, kAlpha, kRoleCount };

Role roleOf(std::string_view name) {
  static constexpr std::pair<std::string_view, Role> kNames[] = {
      {"x", kX},         {"y", kY},
      {"z", kZ},         {"nx", kNx},
      {"ny", kNy},       {"nz", kNz},
      {"red", kRed},     {"diffuse_red", kRed},
      {"green", kGreen}, {"diffuse_green", kGreen},
      {"blue", kBlue},   {"diffuse_blue", kBlue},
      {"alpha", kAlpha}};
  for (const auto& [n, role] : kNames)
    if (name == n) return role;
  return kNone;
}

// Integer colours are 0..255 (ushort ones 0..65535); float colours are 0..1.
double colorByte(double v, Scalar t) {
  if (isFloat(t))
    v *= 255.0;
  else if (t == Scalar::UInt16)
    v /= 257.0;
  if (!(v > 0.0)) return 0.0;  // also NaN
  return v >= 255.0 ? 255.0 : std::floor(v + 0.5);
}

struct VertexLayout {
  std::vector<Role> roles;  // one per property of the vertex element
  bool has_normals = false;
  bool has_colors = false;
};

VertexLayout vertexLayout(const FileReader& reader, const Element& e) {
  VertexLayout layout;
  bool seen[kRoleCount] = {};
  for (const Property& p : e.properties) {
    Role r = roleOf(p.name);
    if (r != kNone && p.is_list)
      throw FormatError::atLine(reader.name(), e.line,
                                "vertex property " + shown(p.name) + " is a list, not a scalar");
    if (r != kNone && seen[r]) r = kNone;  // a duplicate name: the first one counts
    seen[r] = true;
    layout.roles.push_back(r);
  }
  if (!seen[kX] || !seen[kY] || !seen[kZ])
    throw FormatError::atLine(reader.name(), e.line, "the vertex element lacks x, y or z");
  layout.has_normals = seen[kNx] && seen[kNy] && seen[kNz];
  layout.has_colors = seen[kRed] && seen[kGreen] && seen[kBlue];
  return layout;
}

// Filled in file order while the vertex element is read; past ReadOptions::vertex_memory_bytes
// it spills to a temporary file in ReadOptions::spill_dir (spilled_array.h).
struct VertexTable {
  SpilledArray<glm::vec3> positions;
  SpilledArray<glm::vec3> normals;  // empty or one per position
  SpilledArray<uint32_t> colors;    // empty or one per position
};

inline bool fitsFloat(double v) { return std::fabs(v) <= std::numeric_limits<float>::max(); }

// Collects triangles (global vertex indices) and hands them to the sink in parts, each with just
// the vertices it references.
class PartBuilder {
 public:
  PartBuilder(const VertexTable& table, SceneSink& sink, ObjectInfo info, uint32_t max_triangles)
      : table_(table), sink_(sink), max_indices_(size_t{max_triangles ? max_triangles : 1} * 3) {
    part_.info = std::move(info);
    part_.geometry = TriangleMesh{};
  }

  // Call once the vertex table is complete.
  void start() {
    remap_ = PartVertexMap(max_indices_);
    mesh().indices.reserve(std::min<size_t>(max_indices_, size_t{1} << 20));
  }

  inline void addTriangle(uint32_t a, uint32_t b, uint32_t c) {
    std::vector<uint32_t>& indices = mesh().indices;
    indices.push_back(local(a));
    indices.push_back(local(b));
    indices.push_back(local(c));
    if (indices.size() >= max_indices_) flush();
  }

  void flush() {
    TriangleMesh& m = mesh();
    if (m.indices.empty()) return;
    sink_.onObject(part_);
    remap_.clear();
    m.positions.clear();
    m.normals.clear();
    m.colors.clear();
    m.indices.clear();
  }

 private:
  TriangleMesh& mesh() { return *std::get_if<TriangleMesh>(&part_.geometry); }

  inline uint32_t local(uint32_t g) {
    return remap_.localOf(g, [&] {
      TriangleMesh& m = mesh();
      const auto slot = static_cast<uint32_t>(m.positions.size());
      m.positions.push_back(table_.positions[g]);
      if (!table_.normals.empty()) m.normals.push_back(table_.normals[g]);
      if (!table_.colors.empty()) m.colors.push_back(table_.colors[g]);
      return slot;
    });
  }

  const VertexTable& table_;
  SceneSink& sink_;
  size_t max_indices_;
  SceneObject part_;
  PartVertexMap remap_;  // global -> local index in the current part
};

// ---- The reader -----------------------------------------------------------------------------

class PlyParser {
 public:
  PlyParser(FileReader& reader, const Header& header, SceneSink& sink, const ReadOptions& options,
            ObjectInfo info)
      : reader_(reader),
        header_(header),
        options_(options),
        swap_((header.encoding == Encoding::LittleEndian) !=
              (std::endian::native == std::endian::little)),
        builder_(table_, sink, std::move(info), options.max_part_triangles) {}

  void run() {
    const Element* vertex = nullptr;
    for (const Element& e : header_.elements) {
      if (e.name == "vertex") {
        if (vertex) throw FormatError::atLine(reader_.name(), e.line, "a second 'vertex' element");
        vertex = &e;
        readVertices(e);
        builder_.start();
      } else if (e.name == "face") {
        if (!vertex)
          throw FormatError::atLine(reader_.name(), e.line,
                                    "the 'face' element comes before the 'vertex' element (faces "
                                    "must follow the vertices they index)");
        readFaces(e);
      } else {
        skipElement(e);
      }
    }
    builder_.flush();
  }

 private:
  bool ascii() const { return header_.encoding == Encoding::Ascii; }

  void reportProgress() {
    if (options_.progress && reader_.offset() >= next_progress_) {
      options_.progress->update(reader_.offset());
      next_progress_ = reader_.offset() + kProgressStepBytes;
    }
  }

  // The next non-blank line of an ASCII body.
  std::string_view recordLine(const Element& e, uint64_t index) {
    std::string_view line;
    while (reader_.readLine(line)) {
      std::string_view rest = line;
      text::skipBlanks(rest);
      if (!rest.empty()) return line;
    }
    reader_.failAtLine("the file ends after " + std::to_string(index) + " of " +
                       std::to_string(e.count) + " " + shown(e.name) + " records");
  }

  void expectLineEnd(std::string_view rest, const Element& e) {
    text::skipBlanks(rest);
    if (!rest.empty())
      reader_.failAtLine("unexpected extra values " + shown(rest) + " at the end of a " +
                         shown(e.name) + " record");
  }

  // Reads one scalar of type `t` at the current offset (general binary path).
  double readDouble(Scalar t) {
    char bytes[8];
    reader_.read(bytes, sizeOf(t));
    return loadDouble(bytes, t, swap_);
  }
  // Integer types only (the header check rejects float list counts and indices); a double holds
  // every 32-bit integer exactly.
  int64_t readInteger(Scalar t) { return static_cast<int64_t>(readDouble(t)); }
  // Reads a list count and checks that its items fit in the rest of the file.
  uint64_t readListCount(const Property& p) {
    uint64_t at = reader_.offset();
    int64_t n = readInteger(p.count_type);
    if (n < 0)
      reader_.failAt(at, "negative list count " + std::to_string(n) + " for " + shown(p.name));
    if (static_cast<uint64_t>(n) > reader_.remaining() / sizeOf(p.type))
      reader_.failAt(at, "list " + shown(p.name) + " of " + std::to_string(n) +
                             " items runs past the end of the file");
    return static_cast<uint64_t>(n);
  }

  // -- vertices --

  void storeVertex(uint64_t i, const double* v, uint64_t byte_offset) {
    if (!fitsFloat(v[kX]) || !fitsFloat(v[kY]) || !fitsFloat(v[kZ])) {
      std::string reason =
          "vertex " + std::to_string(i) + " has a non-finite or out-of-range position";
      if (ascii()) reader_.failAtLine(reason);
      reader_.failAt(byte_offset, reason);
    }
    table_.positions.push_back(glm::vec3(float(v[kX]), float(v[kY]), float(v[kZ])));
    if (layout_.has_normals) {
      glm::dvec3 n(v[kNx], v[kNy], v[kNz]);
      // A non-finite normal is harmless to skip but not to pass on.
      bool ok = fitsFloat(n.x) && fitsFloat(n.y) && fitsFloat(n.z);
      table_.normals.push_back(ok ? glm::vec3(n) : glm::vec3(0.0f));
    }
    if (layout_.has_colors) {
      auto byte = [&](Role r) { return static_cast<uint32_t>(v[r]); };
      table_.colors.push_back(byte(kRed) | byte(kGreen) << 8 | byte(kBlue) << 16 |
                              byte(kAlpha) << 24);
    }
  }

  void readVertices(const Element& e) {
    layout_ = vertexLayout(reader_, e);
    if (e.count > 0xfffffffeull)
      throw FormatError::atLine(reader_.name(), e.line,
                                "more than 4294967294 vertices are not supported");
    // Each present array gets its share of the memory the options allow for vertices.
    const uint64_t limit = options_.vertex_memory_bytes;
    const uint64_t per_vertex = 12 + (layout_.has_normals ? 12 : 0) + (layout_.has_colors ? 4 : 0);
    auto share = [&](uint64_t bytes) { return limit == 0 ? 0 : std::max<uint64_t>(1, limit * bytes / per_vertex); };
    table_.positions = SpilledArray<glm::vec3>(share(12), options_.spill_dir);
    if (layout_.has_normals) table_.normals = SpilledArray<glm::vec3>(share(12), options_.spill_dir);
    if (layout_.has_colors) table_.colors = SpilledArray<uint32_t>(share(4), options_.spill_dir);
    if (ascii())
      readVerticesAscii(e);
    else if (e.hasLists())
      readVerticesBinaryGeneral(e);
    else
      readVerticesBinaryFixed(e);
  }

  double valueFor(Role r, double raw, Scalar t) const {
    return r >= kRed ? colorByte(raw, t) : raw;
  }

  void readVerticesAscii(const Element& e) {
    double v[kRoleCount] = {};
    for (uint64_t i = 0; i < e.count; ++i) {
      std::string_view rest = recordLine(e, i);
      v[kAlpha] = 255.0;
      for (size_t j = 0; j < e.properties.size(); ++j) {
        const Property& p = e.properties[j];
        if (p.is_list) {
          int64_t n = 0;
          if (!text::parseInt64(rest, n) || n < 0)
            reader_.failAtLine("bad list count for vertex property " + shown(p.name));
          double ignored;
          for (int64_t k = 0; k < n; ++k)
            if (!text::parseDouble(rest, ignored))
              reader_.failAtLine("expected " + std::to_string(n) + " numbers in list " +
                                 shown(p.name));
          continue;
        }
        double d;
        if (!text::parseDouble(rest, d))
          reader_.failAtLine("expected a number for vertex property " + shown(p.name));
        v[layout_.roles[j]] = valueFor(layout_.roles[j], d, p.type);
      }
      expectLineEnd(rest, e);
      storeVertex(i, v, 0);
      if ((i & 0xffff) == 0) reportProgress();
    }
  }

  // Fixed-size records: walk whole records in the reader's buffer.
  void readVerticesBinaryFixed(const Element& e) {
    const uint64_t record = e.minRecordBytes();
    struct Field {
      uint32_t offset;
      Scalar type;
      Role role;
    };
    std::vector<Field> fields;
    uint32_t offset = 0;
    for (size_t j = 0; j < e.properties.size(); ++j) {
      if (layout_.roles[j] != kNone)
        fields.push_back({offset, e.properties[j].type, layout_.roles[j]});
      offset += sizeOf(e.properties[j].type);
    }
    auto isFloatAt = [&](Role r, uint32_t at) {
      for (const Field& f : fields)
        if (f.role == r) return f.type == Scalar::Float32 && f.offset == at;
      return false;
    };
    const bool xyz_fast = !swap_ && isFloatAt(kX, 0) && isFloatAt(kY, 4) && isFloatAt(kZ, 8);

    // Float positions first and at most uchar colours besides (the common layouts, and what
    // PlyWriter writes): copied without conversions.
    bool plain = xyz_fast && !layout_.has_normals;
    uint32_t color_at[4] = {0, 0, 0, 0};  // red, green, blue, alpha offsets
    bool has_alpha = false;
    for (const Field& f : fields) {
      if (f.role >= kRed) color_at[f.role - kRed] = f.offset;
      has_alpha = has_alpha || f.role == kAlpha;
      plain = plain && (f.role <= kZ || f.type == Scalar::UInt8);
    }
    double v[kRoleCount] = {};
    for (uint64_t i = 0; i < e.count;) {
      std::string_view view = reader_.peek(kReaderBufferBytes);
      uint64_t n = std::min<uint64_t>(e.count - i, view.size() / record);
      if (n == 0) reader_.fail("vertex data truncated after " + std::to_string(i) + " vertices");
      const uint64_t base = reader_.offset();
      for (uint64_t k = 0; plain && k < n; ++k, ++i) {
        const auto* rec = reinterpret_cast<const uint8_t*>(view.data() + k * record);
        glm::vec3 p;
        std::memcpy(&p, rec, 12);
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
          reader_.failAt(base + k * record,
                         "vertex " + std::to_string(i) + " has a non-finite position");
        table_.positions.push_back(p);
        if (!layout_.has_colors) continue;
        table_.colors.push_back(uint32_t{rec[color_at[0]]} | uint32_t{rec[color_at[1]]} << 8 |
                                uint32_t{rec[color_at[2]]} << 16 |
                                (has_alpha ? uint32_t{rec[color_at[3]]} : 255u) << 24);
      }
      for (uint64_t k = 0; !plain && k < n; ++k, ++i) {
        const char* rec = view.data() + k * record;
        v[kAlpha] = 255.0;
        for (const Field& f : fields)
          v[f.role] = valueFor(f.role, loadDouble(rec + f.offset, f.type, swap_), f.type);
        storeVertex(i, v, base + k * record);
      }
      reader_.consume(static_cast<size_t>(n * record));
      reportProgress();
    }
  }

  // Records with lists: one value at a time.
  void readVerticesBinaryGeneral(const Element& e) {
    double v[kRoleCount] = {};
    for (uint64_t i = 0; i < e.count; ++i) {
      uint64_t start = reader_.offset();
      v[kAlpha] = 255.0;
      for (size_t j = 0; j < e.properties.size(); ++j) {
        const Property& p = e.properties[j];
        if (p.is_list) {
          reader_.skip(readListCount(p) * sizeOf(p.type));
          continue;
        }
        v[layout_.roles[j]] = valueFor(layout_.roles[j], readDouble(p.type), p.type);
      }
      storeVertex(i, v, start);
      if ((i & 0xffff) == 0) reportProgress();
    }
  }

  // -- faces --

  size_t indexProperty(const Element& e) const {
    for (size_t j = 0; j < e.properties.size(); ++j) {
      const Property& p = e.properties[j];
      if (p.name != "vertex_indices" && p.name != "vertex_index") continue;
      if (!p.is_list || isFloat(p.type))
        throw FormatError::atLine(reader_.name(), e.line,
                                  "face property " + shown(p.name) + " must be a list of integers");
      return j;
    }
    throw FormatError::atLine(reader_.name(), e.line,
                              "the face element has no 'vertex_indices' list property");
  }

  [[noreturn]] void badIndex(int64_t index, uint64_t byte_offset) {
    std::string reason = "face vertex index " + std::to_string(index) + " is out of range (" +
                         std::to_string(table_.positions.size()) + " vertices)";
    if (ascii()) reader_.failAtLine(reason);
    reader_.failAt(byte_offset, reason);
  }

  // Fan triangulation, streamed: a face of n >= 3 indices gives n - 2 triangles; faces with fewer
  // than three indices are skipped.
  struct Fan {
    uint32_t first = 0, previous = 0;
    uint64_t count = 0;
  };
  inline void fanAdd(Fan& fan, int64_t index, uint64_t byte_offset) {
    if (index < 0 || static_cast<uint64_t>(index) >= table_.positions.size())
      badIndex(index, byte_offset);
    auto g = static_cast<uint32_t>(index);
    if (fan.count == 0)
      fan.first = g;
    else if (fan.count >= 2)
      builder_.addTriangle(fan.first, fan.previous, g);
    fan.previous = g;
    ++fan.count;
  }

  void readFaces(const Element& e) {
    const size_t index_property = indexProperty(e);
    if (ascii()) return readFacesAscii(e, index_property);
    const Property& p = e.properties[index_property];
    bool fast = e.properties.size() == 1 && p.count_type == Scalar::UInt8 &&
                (p.type == Scalar::Int32 || p.type == Scalar::UInt32);
    if (!fast) return readFacesBinary(e, index_property);
    if (swap_)
      readFacesBinaryFast<true>(e, p.type == Scalar::Int32);
    else
      readFacesBinaryFast<false>(e, p.type == Scalar::Int32);
  }

  void readFacesAscii(const Element& e, size_t index_property) {
    for (uint64_t i = 0; i < e.count; ++i) {
      std::string_view rest = recordLine(e, i);
      for (size_t j = 0; j < e.properties.size(); ++j) {
        const Property& p = e.properties[j];
        if (!p.is_list) {
          double ignored;
          if (!text::parseDouble(rest, ignored))
            reader_.failAtLine("expected a number for face property " + shown(p.name));
          continue;
        }
        int64_t n = 0;
        if (!text::parseInt64(rest, n) || n < 0)
          reader_.failAtLine("bad list count for face property " + shown(p.name));
        Fan fan;
        for (int64_t k = 0; k < n; ++k) {
          if (j == index_property) {
            int64_t index;
            if (!text::parseInt64(rest, index))
              reader_.failAtLine("expected " + std::to_string(n) + " vertex indices");
            fanAdd(fan, index, 0);
          } else {
            double ignored;
            if (!text::parseDouble(rest, ignored))
              reader_.failAtLine("expected " + std::to_string(n) + " numbers in list " +
                                 shown(p.name));
          }
        }
      }
      expectLineEnd(rest, e);
      if ((i & 0xffff) == 0) reportProgress();
    }
  }

  // General binary faces, one value at a time.
  void readFacesBinary(const Element& e, size_t index_property) {
    for (uint64_t i = 0; i < e.count; ++i) {
      readFaceRecord(e, index_property);
      if ((i & 0xffff) == 0) reportProgress();
    }
  }

  void readFaceRecord(const Element& e, size_t index_property) {
    for (size_t j = 0; j < e.properties.size(); ++j) {
      const Property& p = e.properties[j];
      if (!p.is_list) {
        reader_.skip(sizeOf(p.type));
        continue;
      }
      uint64_t n = readListCount(p);
      if (j != index_property) {
        reader_.skip(n * sizeOf(p.type));
        continue;
      }
      Fan fan;
      for (uint64_t k = 0; k < n; ++k) {
        uint64_t at = reader_.offset();
        fanAdd(fan, readInteger(p.type), at);
      }
    }
  }

  // uchar count, 4-byte indices, nothing else in the record: triangles straight from the buffer;
  // any other record (a polygon, or one split across the buffer's end) goes through
  // readFaceRecord.
  template <bool kSwap>
  void readFacesBinaryFast(const Element& e, bool signed_indices) {
    const uint64_t vertex_count = table_.positions.size();
    // Signed indices >= 2^31 read as unsigned are negative in the file: out of range.
    const uint32_t limit = static_cast<uint32_t>(
        signed_indices ? std::min<uint64_t>(vertex_count, uint64_t{1} << 31) : vertex_count);
    for (uint64_t i = 0; i < e.count;) {
      std::string_view view = reader_.peek(kReaderBufferBytes);
      const char* p = view.data();
      const char* end = p + view.size();
      uint64_t left = e.count - i;
      uint64_t run = std::min<uint64_t>(left, view.size() / 13);
      const char* run_end = p + run * 13;
      while (p < run_end && static_cast<uint8_t>(*p) == 3) {
        uint32_t a = loadRaw<uint32_t>(p + 1, kSwap);
        uint32_t b = loadRaw<uint32_t>(p + 5, kSwap);
        uint32_t c = loadRaw<uint32_t>(p + 9, kSwap);
        if ((a >= limit) | (b >= limit) | (c >= limit)) [[unlikely]] {
          uint64_t at = reader_.offset() + static_cast<uint64_t>(p - view.data());
          int k = a >= limit ? 0 : b >= limit ? 1 : 2;
          uint32_t bad = k == 0 ? a : k == 1 ? b : c;
          badIndex(signed_indices ? int64_t{static_cast<int32_t>(bad)} : int64_t{bad},
                   at + 1 + 4 * k);
        }
        builder_.addTriangle(a, b, c);
        p += 13;
      }
      uint64_t consumed = static_cast<uint64_t>(p - view.data());
      i += consumed / 13;
      reader_.consume(static_cast<size_t>(consumed));
      reportProgress();
      if (i < e.count && (p == end || p == run_end || static_cast<uint8_t>(*p) != 3)) {
        // Not a plain triangle, or not wholly in the buffer.
        readFaceRecord(e, 0);
        ++i;
      }
    }
  }

  // -- other elements --

  void skipElement(const Element& e) {
    if (e.properties.empty() || e.count == 0) return;
    if (ascii()) {
      for (uint64_t i = 0; i < e.count; ++i) {
        recordLine(e, i);
        if ((i & 0xffff) == 0) reportProgress();
      }
      return;
    }
    if (!e.hasLists()) {
      reader_.skip(e.count * e.minRecordBytes());  // checkCounts() bounded the product
      reportProgress();
      return;
    }
    for (uint64_t i = 0; i < e.count; ++i) {
      for (const Property& p : e.properties) {
        if (p.is_list)
          reader_.skip(readListCount(p) * sizeOf(p.type));
        else
          reader_.skip(sizeOf(p.type));
      }
      if ((i & 0xffff) == 0) reportProgress();
    }
  }

  FileReader& reader_;
  const Header& header_;
  const ReadOptions& options_;
  const bool swap_;
  VertexTable table_;
  VertexLayout layout_;
  PartBuilder builder_;
  uint64_t next_progress_ = 0;
};

}  // namespace

void readPly(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options) {
  FileReader reader(path, kReaderBufferBytes);  // sized down to small files by FileReader
  beginStage(options.progress, "read", reader.size());
  Header header = parseHeader(reader);
  checkCounts(reader, header);

  sink.onLayer(0, Layer{"default"});
  ObjectInfo info;
  info.id = 0;
  info.name = path.stem().string();
  info.layer = 0;
  PlyParser parser(reader, header, sink, options, std::move(info));
  parser.run();
  updateProgress(options.progress, reader.offset());
  endStage(options.progress);
}

}  // namespace tw
