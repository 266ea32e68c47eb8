// The native scene format (.tws): exact round trips of every geometry kind, format stability
// against committed fixtures, and clear errors (with offsets) for damaged or hostile files.
#include <gtest/gtest.h>

#include <atomic>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>
#include <string>
#include <vector>

#include <xxhash.h>

#include "file_reader.h"
#include "test_support.h"
#include "tws_format.h"
#include "tws_reader.h"
#include "tws_writer.h"

// Tracks the largest single heap allocation, so tests can prove that hostile counts in a file do
// not make the reader allocate what the file claims.
namespace {
std::atomic<size_t> g_largest_allocation{0};
void* trackedAlloc(size_t bytes) {
  size_t seen = g_largest_allocation.load(std::memory_order_relaxed);
  while (bytes > seen && !g_largest_allocation.compare_exchange_weak(seen, bytes)) {
  }
  if (void* p = std::malloc(bytes ? bytes : 1)) return p;
  throw std::bad_alloc();
}
}  // namespace
void* operator new(size_t bytes) { return trackedAlloc(bytes); }
void* operator new[](size_t bytes) { return trackedAlloc(bytes); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }
void operator delete[](void* p, size_t) noexcept { std::free(p); }

namespace tw {
namespace {

// ---------------------------------------------------------------------------------------------
// Scenes and exact comparison

struct Scene {
  std::vector<Layer> layers;
  std::vector<SceneObject> objects;
};

void writeScene(const std::filesystem::path& path, const Scene& scene) {
  TwsWriter writer(path);
  for (uint32_t i = 0; i < scene.layers.size(); ++i) writer.onLayer(i, scene.layers[i]);
  for (const SceneObject& o : scene.objects) writer.onObject(o);
  writer.finish();
}

// Floats as hex (%a) so that "equal text" means "equal bits" and a mismatch reads well.
std::string num(double v) {
  char text[64];
  std::snprintf(text, sizeof text, "%a", v);
  return text;
}
std::string describe(const glm::vec2& v) { return num(v.x) + "," + num(v.y); }
std::string describe(const glm::vec3& v) { return num(v.x) + "," + num(v.y) + "," + num(v.z); }
std::string describe(const glm::vec4& v) { return describe(glm::vec3(v)) + "," + num(v.w); }
template <typename T>
std::string describeAll(const std::vector<T>& values) {
  std::string out = "[" + std::to_string(values.size()) + "]";
  for (const T& v : values) {
    if constexpr (std::is_arithmetic_v<T>) {
      out += ' ';  // appended separately: GCC 12 warns falsely on " " + std::string
      out += std::is_floating_point_v<T> ? num(v) : std::to_string(v);
    } else {
      out += ' ';
      out += describe(v);
    }
  }
  return out;
}

struct DescribePrimitive {
  std::string operator()(const Cylinder& c) const {
    return "cylinder " + num(c.radius) + " " + num(c.height) + " " + std::to_string(c.capped);
  }
  std::string operator()(const Cone& c) const {
    return "cone " + num(c.radius_bottom) + " " + num(c.radius_top) + " " + num(c.height) + " " +
           std::to_string(c.capped);
  }
  std::string operator()(const Sphere& s) const { return "sphere " + num(s.radius); }
  std::string operator()(const TorusSegment& t) const {
    return "torus " + num(t.major_radius) + " " + num(t.minor_radius) + " " + num(t.sweep_rad);
  }
  std::string operator()(const Box& b) const { return "box " + describe(b.half_extents); }
  std::string operator()(const Extrusion& e) const {
    return "extrusion " + num(e.height) + " " + describeAll(e.profile);
  }
  std::string operator()(const Revolution& r) const {
    return "revolution " + num(r.sweep_rad) + " " + describeAll(r.profile);
  }
};

std::string describe(const SceneObject& o) {
  const ObjectInfo& i = o.info;
  std::string out = "id " + std::to_string(i.id) + " name '" + i.name + "' layer " +
                    std::to_string(i.layer) + " key '" + i.db_key + "' colour " +
                    std::to_string(i.color_rgba) + " origin " + num(i.transform.origin.x) + "," +
                    num(i.transform.origin.y) + "," + num(i.transform.origin.z) + " linear";
  for (int c = 0; c < 3; ++c) out += " " + describe(i.transform.linear[c]);
  out += "\n";
  if (const auto* m = std::get_if<TriangleMesh>(&o.geometry)) {
    out += "mesh positions " + describeAll(m->positions) + "\nnormals " +
           describeAll(m->normals) + "\ncolours " + describeAll(m->colors) + "\nindices " +
           describeAll(m->indices);
  } else if (const auto* p = std::get_if<Primitive>(&o.geometry)) {
    out += std::visit(DescribePrimitive{}, *p);
  } else {
    for (const NurbsPatch& patch : std::get<NurbsPatchSet>(o.geometry).patches)
      out += "patch " + std::to_string(patch.degree_u) + " " + std::to_string(patch.degree_v) +
             " " + std::to_string(patch.count_u) + " " + std::to_string(patch.count_v) + " u " +
             describeAll(patch.knots_u) + " v " + describeAll(patch.knots_v) + " points " +
             describeAll(patch.control_points) + "\n";
  }
  return out;
}

void expectSameScene(const Scene& expected, const test::CollectingSink& got) {
  ASSERT_EQ(got.layers.size(), expected.layers.size());
  for (size_t i = 0; i < expected.layers.size(); ++i) {
    EXPECT_EQ(got.layers[i].name, expected.layers[i].name);
    EXPECT_EQ(got.layers[i].color_rgba, expected.layers[i].color_rgba);
  }
  ASSERT_EQ(got.objects.size(), expected.objects.size());
  for (size_t i = 0; i < expected.objects.size(); ++i)
    EXPECT_EQ(describe(got.objects[i]), describe(expected.objects[i])) << "object " << i;
}

TriangleMesh gridMesh(uint32_t nx, uint32_t ny, bool normals, bool colors) {
  TriangleMesh m;
  for (uint32_t y = 0; y <= ny; ++y)
    for (uint32_t x = 0; x <= nx; ++x) {
      m.positions.push_back({0.1f * x, 0.1f * y, 0.01f * float((x * 7 + y * 3) % 5)});
      // Constants, not computed normals: fixture bytes must not depend on FMA contraction.
      static const glm::vec3 kNormals[3] = {{0, 0, 1}, {0.6f, 0, 0.8f}, {0, -0.8f, 0.6f}};
      if (normals) m.normals.push_back(kNormals[(x + y) % 3]);
      if (colors) m.colors.push_back(0xff000000u | (x * 2654435761u + y) % 0xffffffu);
    }
  for (uint32_t y = 0; y < ny; ++y)
    for (uint32_t x = 0; x < nx; ++x) {
      uint32_t a = y * (nx + 1) + x, b = a + 1, c = a + nx + 1, d = c + 1;
      m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
    }
  return m;
}

NurbsPatch bilinearishPatch(float x0, float weight) {
  NurbsPatch p;
  p.degree_u = p.degree_v = 2;
  p.count_u = 3;
  p.count_v = 4;
  p.knots_u = {0, 0, 0, 1, 1, 1};
  p.knots_v = {0, 0, 0, 0.5f, 1, 1, 1};
  for (uint32_t v = 0; v < p.count_v; ++v)
    for (uint32_t u = 0; u < p.count_u; ++u)
      p.control_points.push_back({x0 + float(u), float(v), 0.25f * float(u * v), u == 1 ? weight : 1});
  return p;
}

SceneObject makeObject(uint32_t id, std::string name, uint32_t layer, Geometry geometry) {
  SceneObject o;
  o.info.id = id;
  o.info.name = std::move(name);
  o.info.layer = layer;
  o.info.db_key = "PDMS/" + std::to_string(id * 31);
  o.info.color_rgba = id % 2 ? 0 : 0xff2080c0u + id;
  o.info.transform.origin = {6.5e6 + 0.123456789 * id, -7.3e6 + 1e-3 * id, 12.5 + id};
  o.info.transform.linear = glm::mat3(0.0f, 1.0f, 0.0f, -1.0f, 0.0f, 0.0f, 0.0f, 0.0f, 2.5f);
  o.geometry = std::move(geometry);
  return o;
}

// One object of every geometry kind and primitive alternative; small enough for a fixture.
Scene allKindsScene() {
  Scene s;
  s.layers = {{"Structure", 0xff808080u}, {"Piping \xc3\x98 200 \xe2\x80\x93 \xe9\x85\x8d\xe7\xae\xa1", 0xff00a0ffu}, {"", 0x00000000u}};
  s.objects.push_back(makeObject(1, "mesh full", 0, gridMesh(4, 3, true, true)));
  s.objects.push_back(makeObject(2, "mesh plain", 1, gridMesh(3, 2, false, false)));
  s.objects.push_back(makeObject(3, "mesh normals", 2, gridMesh(2, 2, true, false)));
  s.objects.push_back(makeObject(4, "mesh colours", 0, gridMesh(2, 1, false, true)));
  s.objects.push_back(makeObject(5, "", 0, TriangleMesh{}));
  s.objects.back().info.db_key = "";
  s.objects.push_back(makeObject(6, "cyl", 1, Primitive{Cylinder{0.1f, 3.0f, false}}));
  s.objects.push_back(makeObject(7, "cone", 1, Primitive{Cone{0.3f, 0.1f, 0.4f, true}}));
  s.objects.push_back(makeObject(8, "sphere", 1, Primitive{Sphere{1.25f}}));
  s.objects.push_back(makeObject(9, "elbow", 1, Primitive{TorusSegment{0.3f, 0.1f, 1.0f}}));
  s.objects.push_back(makeObject(10, "box", 0, Primitive{Box{glm::vec3(1, 2, 0.5f)}}));
  s.objects.push_back(makeObject(
      11, "beam", 0, Primitive{Extrusion{{{0, 0}, {0.2f, 0}, {0.2f, 0.1f}, {0.1f, 0.3f}}, 6.0f}}));
  s.objects.push_back(makeObject(
      12, "vessel head \xe2\x88\x85", 2, Primitive{Revolution{{{0, 0}, {1, 0}, {1, 2}, {0, 2.5f}}, 6.2831855f}}));
  NurbsPatchSet set;
  set.patches = {bilinearishPatch(0, 0.7f), bilinearishPatch(2, 1.5f)};
  s.objects.push_back(makeObject(13, "hull", 2, std::move(set)));
  return s;
}

// The worked example of docs/scene-format.md: one layer and one box.
Scene exampleScene() {
  Scene s;
  s.layers = {{"Steel", 0xff3366ccu}};
  SceneObject box;
  box.info.id = 7;
  box.info.name = "B-1";
  box.info.db_key = "K7";
  box.info.transform.origin = {6500000.0, 0.5, 10.0};
  box.geometry = Primitive{Box{glm::vec3(1.0f, 0.5f, 0.25f)}};
  s.objects.push_back(std::move(box));
  return s;
}

test::CollectingSink readBack(const std::filesystem::path& path, const ReadOptions& options = {}) {
  test::CollectingSink sink;
  readTws(path, sink, options);
  return sink;
}

// ---------------------------------------------------------------------------------------------
// Raw chunk editing, for hand-made bad files

struct RawChunk {
  tws::ChunkHeader header;
  std::string payload;
};

struct RawFile {
  std::string header;  // the file header bytes
  std::vector<RawChunk> chunks;
  std::vector<uint64_t> offsets;  // file offset of each chunk, as parsed
};

RawFile splitChunks(const std::string& bytes) {
  RawFile f;
  f.header = bytes.substr(0, sizeof(tws::FileHeader));
  uint64_t at = sizeof(tws::FileHeader);
  while (at + sizeof(tws::ChunkHeader) <= bytes.size()) {
    RawChunk c;
    std::memcpy(&c.header, bytes.data() + at, sizeof c.header);
    f.offsets.push_back(at);
    at += sizeof c.header;
    c.payload = bytes.substr(at, c.header.payload_bytes);
    at += tws::alignUp(c.header.payload_bytes);
    f.chunks.push_back(std::move(c));
  }
  return f;
}

// Reassembles the file; payload_bytes and checksums are recomputed unless keep_headers.
std::string joinChunks(const RawFile& f, bool keep_headers = false) {
  std::string out = f.header;
  for (const RawChunk& c : f.chunks) {
    tws::ChunkHeader h = c.header;
    if (!keep_headers) {
      h.payload_bytes = c.payload.size();
      h.checksum = XXH3_64bits(c.payload.data(), c.payload.size());
    }
    out.append(reinterpret_cast<const char*>(&h), sizeof h);
    out += c.payload;
    out.append(tws::alignUp(c.payload.size()) - c.payload.size(), '\0');
  }
  return out;
}

// Walks whatever chunks fit and rewrites their checksums: damage then reaches the payload parser
// instead of stopping at the checksum test. Tolerates any garbage.
void fixChecksums(std::string& bytes) {
  uint64_t at = sizeof(tws::FileHeader);
  while (at + sizeof(tws::ChunkHeader) <= bytes.size()) {
    tws::ChunkHeader h;
    std::memcpy(&h, bytes.data() + at, sizeof h);
    uint64_t payload_at = at + sizeof h;
    if (h.payload_bytes > bytes.size() - payload_at) return;
    h.checksum = XXH3_64bits(bytes.data() + payload_at, h.payload_bytes);
    std::memcpy(bytes.data() + at, &h, sizeof h);
    at = payload_at + tws::alignUp(h.payload_bytes);
  }
}

template <typename T>
void poke(std::string& bytes, uint64_t offset, T value) {
  ASSERT_LE(offset + sizeof value, bytes.size());
  std::memcpy(bytes.data() + offset, &value, sizeof value);
}

RawChunk& firstChunkOfType(RawFile& f, uint32_t type) {
  for (RawChunk& c : f.chunks)
    if (c.header.type == type) return c;
  throw std::runtime_error("no such chunk");
}

// Reads and expects a FormatError at `position` whose reason contains `reason`.
void expectError(const std::filesystem::path& path, uint64_t position, const std::string& reason,
                 const ReadOptions& options = {}) {
  try {
    test::NullSink sink;
    readTws(path, sink, options);
    ADD_FAILURE() << "no error; expected: " << reason;
  } catch (const FormatError& e) {
    EXPECT_EQ(e.where(), FormatError::Where::Byte) << e.what();
    EXPECT_EQ(e.position(), position) << e.what();
    EXPECT_NE(e.reason().find(reason), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(path.filename().string()), std::string::npos);
  }
}

// Writes `scene`, lets `edit` change the chunks, and writes the result (checksums fixed).
std::filesystem::path editedFile(const Scene& scene, const std::function<void(RawFile&)>& edit,
                                 const std::string& name = "edited.tws") {
  auto dir = test::scratchDir();
  writeScene(dir / "original.tws", scene);
  RawFile f = splitChunks(test::readFile(dir / "original.tws"));
  edit(f);
  test::writeFile(dir / name, joinChunks(f));
  return dir / name;
}

// ---------------------------------------------------------------------------------------------
// Round trips

TEST(Tws, RoundTripsEveryGeometryKindExactly) {
  auto path = test::scratchDir() / "all.tws";
  Scene scene = allKindsScene();
  writeScene(path, scene);
  test::CollectingSink got = readBack(path);
  expectSameScene(scene, got);
  // The plant-scale origin survives to the last bit (a float would lose metres).
  ASSERT_EQ(got.objects.size(), 13u);
  EXPECT_EQ(got.objects[0].info.transform.origin.x, 6.5e6 + 0.123456789);
  EXPECT_EQ(got.layers[1].name, "Piping \xc3\x98 200 \xe2\x80\x93 \xe9\x85\x8d\xe7\xae\xa1");
  EXPECT_TRUE(std::holds_alternative<Cylinder>(std::get<Primitive>(got.objects[5].geometry)));
  EXPECT_FALSE(std::get<Cylinder>(std::get<Primitive>(got.objects[5].geometry)).capped);
}

TEST(Tws, EmptySceneIsValid) {
  auto path = test::scratchDir() / "empty.tws";
  writeScene(path, Scene{});
  test::CollectingSink got = readBack(path);
  EXPECT_TRUE(got.layers.empty());
  EXPECT_TRUE(got.objects.empty());
  EXPECT_EQ(std::filesystem::file_size(path), 32u + 24u + 32u);  // header + END chunk
}

// The committed fixtures pin the byte layout: if this fails, the format changed, which needs a
// version bump and a note in docs/scene-format.md. Regenerate with TW_UPDATE_FIXTURES=1.
TEST(Tws, WriterOutputMatchesCommittedFixtures) {
  struct Fixture {
    const char* name;
    Scene scene;
  };
  for (const Fixture& f : {Fixture{"tws_example.tws", exampleScene()},
                           Fixture{"tws_all_kinds.tws", allKindsScene()}}) {
    auto fresh = test::scratchDir() / f.name;
    writeScene(fresh, f.scene);
    auto committed = test::dataDir() / "fixtures" / f.name;
    if (std::getenv("TW_UPDATE_FIXTURES")) std::filesystem::copy_file(
        fresh, committed, std::filesystem::copy_options::overwrite_existing);
    ASSERT_TRUE(std::filesystem::exists(committed)) << committed;
    EXPECT_TRUE(test::readFile(fresh) == test::readFile(committed)) << f.name << " differs";
    expectSameScene(f.scene, readBack(committed));
  }
  EXPECT_EQ(std::filesystem::file_size(test::dataDir() / "fixtures" / "tws_example.tws"), 304u);
}

TEST(Tws, BytesWrittenMatchesFileSizeAndTempFileIsRenamed) {
  auto path = test::scratchDir() / "sized.tws";
  TwsWriter writer(path);
  writer.onLayer(0, {"L", 1});
  writer.onObject(makeObject(1, "m", 0, gridMesh(5, 5, true, false)));
  EXPECT_FALSE(std::filesystem::exists(path));  // only the temporary exists until finish()
  writer.finish();
  EXPECT_TRUE(std::filesystem::exists(path));
  EXPECT_EQ(writer.bytesWritten(), std::filesystem::file_size(path));
  EXPECT_EQ(std::filesystem::directory_iterator(path.parent_path())->path(), path);
}

TEST(Tws, WriterWithoutFinishLeavesNothing) {
  auto dir = test::scratchDir();
  {
    TwsWriter writer(dir / "abandoned.tws");
    writer.onLayer(0, {"L", 1});
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir));
}

TEST(Tws, WriterReportsIoFailureNamingTheFile) {
  auto path = test::scratchDir() / "no-such-dir" / "x.tws";
  try {
    TwsWriter writer(path);
    FAIL() << "opened a file in a missing directory";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("x.tws"), std::string::npos) << e.what();
  }
}

TEST(Tws, WriterRefusesWhatTheReaderWouldReject) {
  TwsWriter writer(test::scratchDir() / "refused.tws");
  EXPECT_THROW(writer.onObject(makeObject(1, "no layer yet", 0, Primitive{Sphere{}})),
               std::invalid_argument);
  writer.onLayer(0, {"L", 1});
  EXPECT_THROW(writer.onLayer(2, {"gap", 1}), std::invalid_argument);
  TriangleMesh bad_index = gridMesh(1, 1, false, false);
  bad_index.indices[2] = 99;
  EXPECT_THROW(writer.onObject(makeObject(1, "m", 0, bad_index)), std::invalid_argument);
  EXPECT_THROW(writer.onObject(makeObject(1, "s", 0, Primitive{Sphere{-1.0f}})),
               std::invalid_argument);
  SceneObject nan_origin = makeObject(1, "s", 0, Primitive{Sphere{}});
  nan_origin.info.transform.origin.y = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(writer.onObject(nan_origin), std::invalid_argument);
  NurbsPatchSet bad_nurbs;
  bad_nurbs.patches = {bilinearishPatch(0, 1.0f)};
  bad_nurbs.patches[0].knots_u = {1, 0, 0, 1, 1, 1};  // decreasing
  EXPECT_THROW(writer.onObject(makeObject(1, "n", 0, bad_nurbs)), std::invalid_argument);
  writer.finish();
}

TEST(Tws, MultiPartObjectsArriveAsParts) {
  auto path = test::scratchDir() / "parts.tws";
  Scene scene;
  scene.layers = {{"L", 1}};
  scene.objects.push_back(makeObject(42, "big", 0, gridMesh(3, 3, true, false)));
  scene.objects.push_back(makeObject(42, "big", 0, gridMesh(2, 2, true, false)));
  scene.objects.push_back(makeObject(43, "next", 0, Primitive{Sphere{}}));
  writeScene(path, scene);
  test::CollectingSink got = readBack(path);
  expectSameScene(scene, got);
  RawFile raw = splitChunks(test::readFile(path));
  tws::EndRecord end;
  std::memcpy(&end, raw.chunks.back().payload.data(), sizeof end);
  EXPECT_EQ(end.object_chunk_count, 3u);
  EXPECT_EQ(end.object_count, 2u);
  EXPECT_EQ(end.layer_count, 1u);
  EXPECT_EQ(end.chunk_count, 4u);
}

// Corner positions, normals and colours of every triangle, in order: what splitting preserves.
std::vector<float> triangleSoup(const std::vector<const TriangleMesh*>& parts) {
  std::vector<float> out;
  for (const TriangleMesh* m : parts)
    for (uint32_t i : m->indices) {
      const glm::vec3& p = m->positions[i];
      out.insert(out.end(), {p.x, p.y, p.z});
      if (!m->normals.empty()) out.insert(out.end(), {m->normals[i].x, m->normals[i].y, m->normals[i].z});
      if (!m->colors.empty()) out.push_back(static_cast<float>(m->colors[i]));
    }
  return out;
}

TEST(Tws, ReaderSplitsMeshesToMaxPartTriangles) {
  auto path = test::scratchDir() / "split.tws";
  Scene scene;
  scene.layers = {{"L", 1}};
  scene.objects.push_back(makeObject(5, "grid", 0, gridMesh(25, 20, true, true)));  // 1000 tris
  writeScene(path, scene);
  ReadOptions options;
  options.max_part_triangles = 300;
  test::CollectingSink got = readBack(path, options);
  ASSERT_EQ(got.objects.size(), 4u);
  std::vector<const TriangleMesh*> parts;
  for (const SceneObject& o : got.objects) {
    EXPECT_EQ(o.info.id, 5u);
    EXPECT_EQ(o.info.name, "grid");
    const auto& m = std::get<TriangleMesh>(o.geometry);
    EXPECT_LE(m.triangleCount(), 300u);
    EXPECT_LT(m.positions.size(), 400u);  // only the vertices the part uses
    parts.push_back(&m);
  }
  EXPECT_EQ(got.triangles(), 1000u);
  const auto& original = std::get<TriangleMesh>(scene.objects[0].geometry);
  EXPECT_EQ(triangleSoup(parts), triangleSoup({&original}));
}

TEST(Tws, WriterSplitsHugeMeshesIntoBoundedChunks) {
  auto path = test::scratchDir() / "huge.tws";
  Scene scene;
  scene.layers = {{"L", 1}};
  // 1.44 M vertices with normals and colours, 2.9 M triangles: about 75 MB, over the 64 MiB bound.
  scene.objects.push_back(makeObject(9, "huge", 0, gridMesh(1199, 1199, true, true)));
  writeScene(path, scene);
  RawFile raw = splitChunks(test::readFile(path));
  size_t object_chunks = 0;
  for (const RawChunk& c : raw.chunks) {
    EXPECT_LE(c.header.payload_bytes, tws::kWriterMaxPayloadBytes);
    object_chunks += c.header.type == tws::kChunkObject;
  }
  EXPECT_EQ(object_chunks, 2u);
  ReadOptions options;
  options.max_part_triangles = 0;  // as written
  test::CollectingSink got = readBack(path, options);
  ASSERT_EQ(got.objects.size(), 2u);
  const auto& original = std::get<TriangleMesh>(scene.objects[0].geometry);
  EXPECT_EQ(got.triangles(), original.triangleCount());
  EXPECT_TRUE(triangleSoup({&std::get<TriangleMesh>(got.objects[0].geometry),
                            &std::get<TriangleMesh>(got.objects[1].geometry)}) ==
              triangleSoup({&original}));
}

class RecordingProgress : public Progress {
 public:
  void beginStage(std::string_view name, uint64_t total) override {
    stages.emplace_back(name);
    totals.push_back(total);
  }
  void update(uint64_t done) override { updates.push_back(done); }
  void endStage() override { ++ended; }
  std::vector<std::string> stages;
  std::vector<uint64_t> totals, updates;
  int ended = 0;
};

TEST(Tws, ReportsProgressInBytes) {
  auto path = test::scratchDir() / "progress.tws";
  writeScene(path, allKindsScene());
  RecordingProgress progress;
  ReadOptions options;
  options.progress = &progress;
  readBack(path, options);
  ASSERT_EQ(progress.stages, std::vector<std::string>{"read"});
  EXPECT_EQ(progress.totals[0], std::filesystem::file_size(path));
  ASSERT_GE(progress.updates.size(), 10u);
  EXPECT_TRUE(std::is_sorted(progress.updates.begin(), progress.updates.end()));
  EXPECT_EQ(progress.updates.back(), std::filesystem::file_size(path));
  EXPECT_EQ(progress.ended, 1);
}

// ---------------------------------------------------------------------------------------------
// Compatibility rules

TEST(Tws, UnknownOptionalChunksAreSkipped) {
  Scene scene = exampleScene();
  auto path = editedFile(scene, [](RawFile& f) {
    RawChunk extra{{tws::fourCc('X', 'T', 'R', 'A'), 0, 0, 0}, std::string(13, 'x')};
    f.chunks.insert(f.chunks.begin() + 1, extra);
    tws::EndRecord end;
    std::memcpy(&end, f.chunks.back().payload.data(), sizeof end);
    ++end.chunk_count;
    std::memcpy(f.chunks.back().payload.data(), &end, sizeof end);
  });
  expectSameScene(scene, readBack(path));
}

TEST(Tws, UnknownRequiredChunkIsRejected) {
  auto path = editedFile(exampleScene(), [](RawFile& f) {
    f.chunks.insert(f.chunks.begin(), RawChunk{{tws::fourCc('N', 'E', 'W', '!'),
                                                tws::kChunkRequired, 0, 0}, "abc"});
  });
  expectError(path, 32, "unknown required chunk type 'NEW!'");
}

TEST(Tws, LongerRecordsFromNewerWritersAreAccepted) {
  // A newer minor version may grow the object record; old readers skip to record_bytes.
  Scene scene = exampleScene();
  auto path = editedFile(scene, [](RawFile& f) {
    RawChunk& obj = firstChunkOfType(f, tws::kChunkObject);
    uint32_t grown = sizeof(tws::ObjectRecord) + 8;
    std::memcpy(obj.payload.data(), &grown, 4);
    obj.payload.insert(sizeof(tws::ObjectRecord), std::string(8, '\x5a'));
  });
  expectSameScene(scene, readBack(path));
}

// ---------------------------------------------------------------------------------------------
// Specific errors

TEST(Tws, WrongMagicAndVersionAreClear) {
  auto dir = test::scratchDir();
  writeScene(dir / "good.tws", exampleScene());
  std::string bytes = test::readFile(dir / "good.tws");
  std::string bad_magic = bytes;
  bad_magic[0] = 'P';
  test::writeFile(dir / "magic.tws", bad_magic);
  expectError(dir / "magic.tws", 0, "not a .tws file (bad magic)");
  test::writeFile(dir / "ply.tws", "ply\nformat ascii 1.0\n");
  expectError(dir / "ply.tws", 0, "not a .tws file (bad magic)");
  std::string v2 = bytes;
  poke<uint32_t>(v2, 8, 2);
  test::writeFile(dir / "v2.tws", v2);
  expectError(dir / "v2.tws", 8, "unsupported .tws version 2 (this reader supports up to 1)");
  test::writeFile(dir / "tiny.tws", bytes.substr(0, 20));
  expectError(dir / "tiny.tws", 20, "file too short");
}

TEST(Tws, ChecksumMismatchNamesTheChunkOffset) {
  auto dir = test::scratchDir();
  writeScene(dir / "good.tws", exampleScene());
  std::string bytes = test::readFile(dir / "good.tws");
  RawFile f = splitChunks(bytes);
  ASSERT_EQ(f.chunks[1].header.type, tws::kChunkObject);
  bytes[f.offsets[1] + 24 + 40] ^= 0x01;  // one bit of the object's origin
  test::writeFile(dir / "flipped.tws", bytes);
  expectError(dir / "flipped.tws", f.offsets[1], "chunk 'OBJT' checksum mismatch");
}

TEST(Tws, MissingEndChunkMeansTruncated) {
  auto dir = test::scratchDir();
  writeScene(dir / "good.tws", allKindsScene());
  std::string bytes = test::readFile(dir / "good.tws");
  RawFile f = splitChunks(bytes);
  uint64_t end_offset = f.offsets.back();
  test::writeFile(dir / "cut.tws", bytes.substr(0, end_offset));
  expectError(dir / "cut.tws", end_offset, "missing end chunk (file truncated?)");
  test::writeFile(dir / "cut2.tws", bytes.substr(0, end_offset + 10));
  expectError(dir / "cut2.tws", end_offset, "truncated chunk header");
  test::writeFile(dir / "cut3.tws", bytes.substr(0, f.offsets[3] + 100));
  expectError(dir / "cut3.tws", f.offsets[3] + 8, "runs past the end of the file");
}

TEST(Tws, EndTotalsDetectLostChunks) {
  // A damaged type field turns an object into an unknown (skipped) chunk; END catches it.
  auto dir = test::scratchDir();
  writeScene(dir / "good.tws", allKindsScene());
  std::string bytes = test::readFile(dir / "good.tws");
  RawFile f = splitChunks(bytes);
  poke<uint32_t>(bytes, f.offsets[5], tws::fourCc('O', 'B', 'J', 'U'));
  test::writeFile(dir / "lost.tws", bytes);
  expectError(dir / "lost.tws", f.offsets.back(), "end chunk counts 13 object chunks but the file has 12");
  std::string tail = test::readFile(dir / "good.tws") + std::string(8, '\0');
  test::writeFile(dir / "tail.tws", tail);
  expectError(dir / "tail.tws", tail.size() - 8, "8 unexpected bytes after the end chunk");
}

TEST(Tws, HostileSizesAreRejectedWithoutAllocating) {
  auto dir = test::scratchDir();
  writeScene(dir / "good.tws", exampleScene());
  std::string bytes = test::readFile(dir / "good.tws");
  RawFile f = splitChunks(bytes);
  std::string huge = bytes;
  poke<uint64_t>(huge, f.offsets[1] + 8, uint64_t{1} << 60);
  test::writeFile(dir / "huge.tws", huge);
  g_largest_allocation = 0;
  expectError(dir / "huge.tws", f.offsets[1] + 8, "runs past the end of the file");
  EXPECT_LE(g_largest_allocation.load(), FileReader::kDefaultBufferBytes);

  // Counts inside a payload whose checksum is valid: the payload parser must catch them.
  Scene mesh_scene;
  mesh_scene.layers = {{"L", 1}};
  mesh_scene.objects.push_back(makeObject(1, "m", 0, gridMesh(2, 2, false, false)));
  const uint64_t mesh_at = sizeof(tws::ObjectRecord) + 8;  // "m" + "PDMS/31", padded to 8
  auto path = editedFile(mesh_scene, [&](RawFile& raw) {
    poke<uint32_t>(firstChunkOfType(raw, tws::kChunkObject).payload, mesh_at, 0xffffffffu);
  }, "vertices.tws");
  RawFile edited = splitChunks(test::readFile(path));
  g_largest_allocation = 0;
  expectError(path, edited.offsets[1] + 24 + mesh_at + 16, "mesh arrays (4294967295 vertices");
  EXPECT_LE(g_largest_allocation.load(), FileReader::kDefaultBufferBytes);

  Scene nurbs_scene = allKindsScene();
  nurbs_scene.objects.erase(nurbs_scene.objects.begin(), nurbs_scene.objects.end() - 1);
  nurbs_scene.objects[0].info.name = "n";
  nurbs_scene.objects[0].info.db_key = "k";
  path = editedFile(nurbs_scene, [&](RawFile& raw) {
    std::string& payload = firstChunkOfType(raw, tws::kChunkObject).payload;
    poke<uint32_t>(payload, 104 + 8 + 8, 0x7fffffffu);  // first patch's count_u
    poke<uint32_t>(payload, 104 + 8 + 12, 0x7fffffffu);  // and count_v
  }, "nurbs.tws");
  edited = splitChunks(test::readFile(path));
  g_largest_allocation = 0;
  expectError(path, edited.offsets[3] + 24 + 104 + 8, "NURBS patch 0: control points exceed");
  EXPECT_LE(g_largest_allocation.load(), FileReader::kDefaultBufferBytes);
}

TEST(Tws, BadPayloadValuesAreRejectedWithOffsets) {
  // Pokes `value` at `field` of object `object`'s payload (checksums fixed) and expects `reason`
  // at the field, or at `error_field` where the error names the enclosing record.
  Scene scene = allKindsScene();
  auto check = [&](const char* name, uint64_t field, auto value, const std::string& reason,
                   int object = 0, uint64_t error_field = ~uint64_t{0}) {
    auto path = editedFile(scene, [&](RawFile& f) {
      poke(f.chunks[3 + object].payload, field, value);
    }, name);
    RawFile f = splitChunks(test::readFile(path));
    if (error_field == ~uint64_t{0}) error_field = field;
    expectError(path, f.offsets[3 + object] + 24 + error_field, reason);
  };
  check("layer.tws", offsetof(tws::ObjectRecord, layer), uint32_t{3},
        "object 1 uses layer 3 but only 3 layers were declared before it");
  check("origin.tws", offsetof(tws::ObjectRecord, origin) + 8,
        std::numeric_limits<double>::infinity(), "object 1: origin is not finite");
  check("linear.tws", offsetof(tws::ObjectRecord, linear) + 4 * 4,
        std::numeric_limits<float>::quiet_NaN(), "object 1: transform is not finite");
  check("kind.tws", offsetof(tws::ObjectRecord, geometry), uint32_t{7},
        "object 1: unknown geometry kind 7");
  // Object 1 ("mesh full", key "PDMS/31"): the mesh block starts at 96 + 16 = 112.
  check("index.tws", 112 + 16 + 20 * 28 + 4 * 5, uint32_t{20}, "mesh index 20 out of range");
  check("count.tws", 112 + 4, uint32_t{7}, "mesh index count 7 is not a multiple of 3");
  check("attr.tws", 112 + 8, uint32_t{8}, "unknown mesh attribute bits");
  check("position.tws", 112 + 16 + 4, std::numeric_limits<float>::infinity(),
        "mesh position is not finite");
  // Object 8 ("sphere", "PDMS/248"): primitive record at 96 + 16 = 112.
  check("sphere.tws", 112 + 8, -1.0f, "sphere radius is negative", 7);
  check("primtype.tws", 112, uint32_t{9}, "unknown primitive type 9", 7);
  // Object 13 ("hull", "PDMS/403"): NURBS set record at 112; patch 0's knots_u[1] at 112+8+16+4.
  check("knots.tws", 112 + 8 + 16 + 4, 5.0f, "NURBS patch 0: ", 12, 112 + 8);
  check("patches.tws", 112, uint32_t{0xffffffffu}, "4294967295 NURBS patches cannot fit", 12);
  // Object 11 ("beam", "PDMS/341"): extrusion record at 112, profile_count at 112 + 32.
  check("profile.tws", 112 + 32, uint32_t{1u << 28}, "profile of 268435456 points needs", 10,
        112 + 40);
  check("noprofile.tws", 112 + 32, uint32_t{1}, "primitive type 2 has no profile", 7);
  // Layers: chunk 1 claims index 5.
  auto path = editedFile(scene, [](RawFile& f) { poke<uint32_t>(f.chunks[1].payload, 4, 5); },
                         "layer_order.tws");
  expectError(path, splitChunks(test::readFile(path)).offsets[1] + 24 + 4,
              "layer 5 declared out of order (expected 1)");
}

// ---------------------------------------------------------------------------------------------
// Damage

TEST(Tws, RobustToTruncationAndCorruption) {
  auto dir = test::scratchDir();
  writeScene(dir / "all.tws", allKindsScene());
  std::string bytes = test::readFile(dir / "all.tws");
  ASSERT_GT(bytes.size(), 2000u);
  int rejected = test::expectRobustToDamage(bytes, "damaged.tws",
                                            [](const std::filesystem::path& p, SceneSink& sink) {
                                              readTws(p, sink);
                                            });
  EXPECT_GT(rejected, 250);  // nearly every damaged copy fails a checksum or the END check
}

TEST(Tws, RobustToCorruptPayloadsWithValidChecksums) {
  // Recomputing checksums after the damage sends it past the checksum test into the parsers.
  auto dir = test::scratchDir();
  writeScene(dir / "all.tws", allKindsScene());
  std::string bytes = test::readFile(dir / "all.tws");
  int accepted = 0;
  int rejected = test::expectRobustToDamage(
      bytes, "fixed.tws",
      [&](const std::filesystem::path& p, SceneSink& sink) {
        std::string damaged = test::readFile(p);
        fixChecksums(damaged);
        test::writeFile(p, damaged);
        readTws(p, sink);
        ++accepted;
      },
      600);
  EXPECT_GT(rejected, 100);
  EXPECT_GT(accepted, 100);  // damage to plain coordinates is legal data
}

}  // namespace
}  // namespace tw
