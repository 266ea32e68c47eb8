// Tests for the .twk package: storage -> file -> view round trip of every section, specific
// errors (with byte offsets) for hand-damaged headers, tables, checksums and references, damage
// robustness over every truncation and byte flip, and the size per triangle on a real mesh.
#include <gtest/gtest.h>
#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

#include "obj_reader.h"
#include "package_view.h"
#include "package_writer.h"
#include "test_support.h"

namespace tw {
namespace {

using pkg::ClusterRecord;
using pkg::SectionType;

constexpr float kInf = std::numeric_limits<float>::infinity();

struct Patch {
  std::vector<glm::vec3> positions, normals;
  std::vector<uint32_t> indices, objects;
  ClusterGeometryInput input() const { return {positions, normals, indices, objects}; }
};

Patch makePatch(int n, float size_m, glm::vec3 offset, uint32_t first_object, uint32_t objects) {
  Patch p;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) {
      float u = float(x) / n, v = float(y) / n;
      p.positions.push_back(offset + glm::vec3(u, v, 0.2f * u * v) * size_m);
      p.normals.push_back(glm::normalize(glm::vec3(-0.2f * v, -0.2f * u, 1.0f)));
    }
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      uint32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      p.indices.insert(p.indices.end(), {a, b, d, a, d, c});
      uint32_t object = first_object + uint32_t(y % objects);
      p.objects.insert(p.objects.end(), {object, object});
    }
  return p;
}

// Two LOD levels (4 clusters in group 0 simplified into 1 root cluster in group 1), two
// parametric clusters (cylinders; an extrusion with a profile), 3 objects on 2 layers, pages small
// enough that there are several.
// With `spill`, finished pages stream to that file (spillPagesTo) with `spill_options`; with
// `tables`, the tables stream to files in that directory keeping `tail_bytes` in memory.
PackageStorage makeStorage(const std::filesystem::path& spill = {},
                           const PackageWriteOptions& spill_options = {},
                           const std::filesystem::path& tables = {}, uint64_t tail_bytes = 1) {
  PackageStorage s;
  s.origin = glm::dvec3(451234.5, 6781234.25, -12.0);
  s.input_hash = 0x1234abcd5678ef90ull;
  s.target_page_bytes = 1500;
  if (!spill.empty()) s.spillPagesTo(spill, spill_options);
  if (!tables.empty()) s.spillTablesTo(tables, tail_bytes);
  s.addLayer({"piping", 0xff0000ffu});
  s.addLayer({"structure", 0xff00ff00u});
  ObjectInfo o;
  o.id = 100;
  o.name = "pipe-1";
  o.layer = 0;
  o.db_key = "P-0001";
  s.addObject(o, glm::vec3(-1.0f), glm::vec3(1.0f));
  o.id = 101;
  o.name = "beam-7";
  o.layer = 1;
  o.db_key = "";
  s.addObject(o, glm::vec3(0.0f), glm::vec3(2.0f));
  o.id = 205;
  o.name = "deck";
  o.layer = 1;
  o.db_key = "D-17";
  s.addObject(o, glm::vec3(0.0f), glm::vec3(4.0f));

  ClusterLod fine;
  fine.group = pkg::kNone;
  fine.parent_group = 0;
  fine.level = 0;
  fine.error = 0.0f;
  fine.parent_error = 0.02f;
  fine.lod_sphere = glm::vec4(1.0f, 1.0f, 0.0f, 1.6f);
  fine.parent_lod_sphere = glm::vec4(1.0f, 1.0f, 0.0f, 1.7f);
  for (int i = 0; i < 4; ++i) {
    Patch p = makePatch(6, 1.0f, glm::vec3(float(i % 2), float(i / 2), 0.0f), i % 2 ? 1 : 0, 2);
    s.addMeshCluster(p.input(), fine);
  }
  ClusterLod root;
  root.group = 0;
  root.level = 1;
  root.error = 0.02f;
  root.lod_sphere = fine.parent_lod_sphere;
  Patch coarse = makePatch(3, 2.0f, glm::vec3(0.0f), 0, 3);
  s.addMeshCluster(coarse.input(), root);
  // Group 0 simplified clusters 0-3 into cluster 4; group 1 dropped the cylinders (no output).
  s.appendGroup({{1.0f, 1.0f, 0.0f}, 1.7f, {0, 0, 0}, 0.02f, {2, 2, 0.5f}, kInf, 4, 1, 0, 0});
  s.appendGroup({{0.0f, 0.0f, 0.0f}, 3.0f, {-3, -3, -3}, 0.05f, {3, 3, 3}, 0.05f, 0, 0, 0, 0});

  Transform t;
  t.origin = s.origin;
  s.addInstance(Cylinder{0.1f, 2.0f, true}, t, 0);
  t.origin += glm::dvec3(1.0);
  t.linear = glm::mat3(0.0f, 1.0f, 0.0f, -1.0f, 0.0f, 0.0f, 0.0f, 0.0f, 1.0f);
  s.addInstance(Cylinder{0.1f, 2.0f, false}, t, 0);
  t.origin += glm::dvec3(1.0);
  s.addInstance(Extrusion{{{0.0f, 0.0f}, {1.0f, 0.0f}, {0.0f, 1.0f}}, 2.0f}, t, 2);
  ClusterLod dropped;  // the cylinders vanish at group 1's error
  dropped.parent_group = 1;
  dropped.parent_error = 0.05f;
  s.addParametricCluster(0, 2, dropped);
  s.addParametricCluster(2, 1, ClusterLod{});
  return s;
}

std::string writeToString(const PackageStorage& s, const std::filesystem::path& path,
                          const PackageWriteOptions& options = {}) {
  writePackage(s, path, options);
  return test::readFile(path);
}

// Byte surgery on a written package, keeping checksums right unless asked not to.
struct Bytes {
  std::string data;

  pkg::PackageHeader header() const {
    pkg::PackageHeader h;
    std::memcpy(&h, data.data(), sizeof(h));
    return h;
  }
  pkg::SectionEntry entry(SectionType t) const {
    pkg::SectionEntry e;
    std::memcpy(&e, data.data() + sizeof(pkg::PackageHeader) + uint32_t(t) * sizeof(e), sizeof(e));
    return e;
  }
  void setEntry(SectionType t, const pkg::SectionEntry& e) {
    std::memcpy(data.data() + sizeof(pkg::PackageHeader) + uint32_t(t) * sizeof(e), &e, sizeof(e));
  }
  template <typename T>
  void put(uint64_t offset, const T& value) {
    std::memcpy(data.data() + offset, &value, sizeof(T));
  }
  void fixHeaderChecksum() {
    pkg::PackageHeader h = header();
    std::vector<pkg::SectionEntry> table(h.section_count);
    std::memcpy(table.data(), data.data() + sizeof(h), table.size() * sizeof(pkg::SectionEntry));
    h.header_checksum = packageHeaderChecksum(h, table);
    put(0, h);
  }
  void fixSectionChecksum(SectionType t) {
    pkg::SectionEntry e = entry(t);
    e.checksum = packageSectionChecksum({reinterpret_cast<const uint8_t*>(data.data()) + e.offset,
                                         static_cast<size_t>(pkg::storedBytes(e))});
    setEntry(t, e);
    fixHeaderChecksum();
  }
  // Patches a field of record `index` of section `t`, then fixes the checksums.
  template <typename T>
  void patchRecord(SectionType t, uint64_t index, uint64_t field_offset, const T& value) {
    pkg::SectionEntry e = entry(t);
    put(e.offset + index * e.record_bytes + field_offset, value);
    fixSectionChecksum(t);
  }
};

// Opens `bytes` and expects a FormatError whose reason contains `reason` at byte `offset`
// (offset < 0: any offset).
void expectRejected(const std::string& bytes, const std::string& reason, int64_t offset,
                    PackageView::Verify verify = PackageView::Verify::Headers) {
  auto path = test::scratchDir() / "bad.twk";
  test::writeFile(path, bytes);
  try {
    PackageView::open(path, verify);
    ADD_FAILURE() << "accepted a package that should fail with: " << reason;
  } catch (const FormatError& e) {
    EXPECT_NE(e.reason().find(reason), std::string::npos) << e.what();
    EXPECT_EQ(e.where(), FormatError::Where::Byte) << e.what();
    EXPECT_NE(std::string(e.what()).find("bad.twk: byte "), std::string::npos) << e.what();
    if (offset >= 0) {
      EXPECT_EQ(e.position(), uint64_t(offset)) << e.what();
    }
  }
}

TEST(Package, RoundTripOfEverySection) {
  PackageStorage s = makeStorage();
  auto dir = test::scratchDir();
  auto path = dir / "small.twk";
  PackageWriteStats stats = writePackage(s, path);
  EXPECT_EQ(stats.file_bytes, std::filesystem::file_size(path));
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(entry.path().filename(), "small.twk") << "temporary file left behind";

  PackageView view = PackageView::open(path, PackageView::Verify::All);
  const pkg::PackageHeader& h = view.header();
  EXPECT_EQ(h.version, pkg::kVersion);
  EXPECT_EQ(view.origin(), s.origin);
  EXPECT_EQ(h.input_hash, s.input_hash);
  EXPECT_EQ(h.position_step_m, s.position_step_m);
  EXPECT_EQ(h.level_count, 2u);
  EXPECT_EQ(h.total_triangles, 4u * 72u);
  EXPECT_EQ(h.max_cluster_triangles, 72u);
  EXPECT_FLOAT_EQ(h.bounds_min[0], -0.1f);  // the first cylinder

  ASSERT_EQ(view.clusters().size(), s.clusters.size());
  EXPECT_EQ(std::memcmp(view.clusters().data(), s.clusters.data(),
                        s.clusters.size() * sizeof(ClusterRecord)),
            0);
  ASSERT_EQ(view.groups().size(), 2u);
  EXPECT_EQ(std::memcmp(view.groups().data(), s.groups.data(), 2 * sizeof(pkg::GroupRecord)), 0);
  ASSERT_EQ(view.instances().size(), 3u);
  EXPECT_EQ(
      std::memcmp(view.instances().data(), s.instances.data(), 3 * sizeof(pkg::InstanceRecord)), 0);
  ASSERT_EQ(view.profilePoints().size(), 3u);
  EXPECT_EQ(view.profilePoints()[2], glm::vec2(0.0f, 1.0f));
  ASSERT_EQ(view.objects().size(), 3u);
  EXPECT_EQ(view.objects()[2].id, 205u);
  EXPECT_EQ(view.objectName(1), "beam-7");
  EXPECT_EQ(view.objectDbKey(0), "P-0001");
  EXPECT_EQ(view.objectDbKey(1), "");
  ASSERT_EQ(view.layers().size(), 2u);
  EXPECT_EQ(view.layerName(1), "structure");
  EXPECT_EQ(view.layers()[0].color_rgba, 0xff0000ffu);
  EXPECT_EQ(view.strings(), s.strings);
  EXPECT_TRUE(view.visibility().empty());

  ASSERT_EQ(view.pages().size(), s.pages.size());
  EXPECT_GE(s.pages.size(), 2u);
  bool any_zstd = false;
  std::vector<uint8_t> raw;
  for (uint32_t p = 0; p < view.pages().size(); ++p) {
    view.readPage(p, raw);
    EXPECT_EQ(raw, s.pages[p]);
    any_zstd |= view.pages()[p].codec == uint32_t(pkg::PageCodec::Zstd);
  }
  EXPECT_TRUE(any_zstd);
  DecodedCluster from_view, direct;
  for (uint32_t c = 0; c < 5; ++c) {
    const ClusterRecord& r = view.clusters()[c];
    view.readPage(r.page, raw);
    view.decodeCluster(c, raw, from_view);
    ASSERT_TRUE(decodeCluster(std::span(s.pages[r.page]).subspan(r.page_offset, r.encoded_bytes),
                              s.position_step_m, 3, direct)
                    .ok());
    EXPECT_EQ(from_view.positions, direct.positions);
    EXPECT_EQ(from_view.indices, direct.indices);
    EXPECT_EQ(from_view.triangle_objects, direct.triangle_objects);
    EXPECT_EQ(from_view.positions.size(), r.vertex_count);
  }

  // Uncompressed pages read back the same.
  PackageWriteOptions plain;
  plain.zstd = false;
  writePackage(s, path, plain);
  PackageView raw_view = PackageView::open(path, PackageView::Verify::All);
  for (uint32_t p = 0; p < raw_view.pages().size(); ++p) {
    EXPECT_EQ(raw_view.pages()[p].codec, uint32_t(pkg::PageCodec::None));
    raw_view.readPage(p, raw);
    EXPECT_EQ(raw, s.pages[p]);
    std::vector<uint8_t> scratch;
    std::span<const uint8_t> loaded = raw_view.loadPage(p, scratch);
    EXPECT_EQ(loaded.data(), scratch.data());  // read straight into the caller's buffer
    EXPECT_TRUE(std::equal(loaded.begin(), loaded.end(), s.pages[p].begin(), s.pages[p].end()));
  }
  // The view stays valid after a move.
  PackageView moved = std::move(raw_view);
  EXPECT_EQ(moved.objectName(2), "deck");
}

// Pages streamed to a spill file as they fill give the very bytes of pages kept in memory, with
// and without zstd; the storage then keeps only the open page.
TEST(Package, SpilledPagesGiveTheSameFile) {
  const std::filesystem::path dir = test::scratchDir();
  const PackageStorage in_memory = makeStorage();
  ASSERT_GE(in_memory.pages.size(), 2u);  // at least one spilled, one open
  PackageWriteOptions plain;
  plain.zstd = false;
  for (const PackageWriteOptions& options : {PackageWriteOptions{}, plain}) {
    const PackageStorage spilled = makeStorage(dir / "pages.spill", options);
    EXPECT_EQ(spilled.pages.size(), 1u);
    EXPECT_EQ(spilled.pageCount(), in_memory.pages.size());
    EXPECT_GT(spilled.spilledPageBytes(), 0u);
    EXPECT_EQ(writeToString(spilled, dir / "spilled.twk", options),
              writeToString(in_memory, dir / "memory.twk", options))
        << "zstd " << options.zstd;
    PackageView::open(dir / "spilled.twk", PackageView::Verify::All);
  }
  // The spill's options are the writer's: another codec would mix two layouts.
  const PackageStorage spilled = makeStorage(dir / "pages.spill");
  EXPECT_THROW(writePackage(spilled, dir / "mixed.twk", plain), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(dir / "mixed.twk"));
  // Spilling starts before the first page or not at all.
  PackageStorage late = makeStorage();
  EXPECT_THROW(late.spillPagesTo(dir / "late.spill"), std::logic_error);
  // An unwritable spill path is an I/O error naming it.
  PackageStorage nowhere;
  try {
    nowhere.spillPagesTo(dir / "absent" / "pages.spill");
    ADD_FAILURE() << "no error for an unwritable spill file";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("pages.spill"), std::string::npos) << e.what();
  }
}

// Tables streamed to files as they fill (every record at once with a 1-byte tail, or in chunks)
// give the very bytes of tables kept in memory, together with spilled pages or not; the storage
// keeps only the tail, and its counts and readers see every record.
TEST(Package, SpilledTablesGiveTheSameFile) {
  const std::filesystem::path dir = test::scratchDir();
  const PackageStorage in_memory = makeStorage();
  const std::string expected = writeToString(in_memory, dir / "memory.twk");
  for (uint64_t tail_bytes : {uint64_t(1), uint64_t(200), uint64_t(1) << 20}) {
    for (bool pages : {false, true}) {
      const PackageStorage spilled =
          makeStorage(pages ? dir / "pages.spill" : std::filesystem::path(), {}, dir / "tables",
                      tail_bytes);
      SCOPED_TRACE("tail " + std::to_string(tail_bytes) + " pages " + std::to_string(pages));
      EXPECT_EQ(writeToString(spilled, dir / "spilled.twk"), expected);
      EXPECT_EQ(spilled.clusterCount(), in_memory.clusters.size());
      EXPECT_EQ(spilled.groupCount(), 2u);
      EXPECT_EQ(spilled.instanceCount(), 3u);
      EXPECT_EQ(spilled.profilePointCount(), 3u);
      EXPECT_EQ(spilled.objectCount(), 3u);
      EXPECT_EQ(spilled.stringBytes(), in_memory.strings.size());
      if (tail_bytes == 1) {  // everything went to the files
        EXPECT_TRUE(spilled.clusters.empty());
        EXPECT_TRUE(spilled.groups.empty());
        EXPECT_TRUE(spilled.instances.empty());
        EXPECT_TRUE(spilled.objects.empty());
        EXPECT_TRUE(spilled.strings.empty());
      }
      for (uint32_t c = 0; c < spilled.clusterCount(); ++c) {
        const ClusterRecord r = spilled.clusterRecord(c);
        EXPECT_EQ(std::memcmp(&r, &in_memory.clusters[c], sizeof r), 0) << "cluster " << c;
      }
      const pkg::InstanceRecord extrusion = spilled.instanceRecord(2);
      EXPECT_EQ(std::memcmp(&extrusion, &in_memory.instances[2], sizeof extrusion), 0);
      std::vector<glm::vec2> points;
      spilled.readProfilePoints(extrusion.profile_first, extrusion.profile_count, points);
      EXPECT_EQ(points, in_memory.profile_points);
      EXPECT_THROW(spilled.clusterRecord(spilled.clusterCount()), std::out_of_range);
      EXPECT_THROW(spilled.readProfilePoints(2, 2, points), std::out_of_range);
    }
  }
  // Spilling starts before the first record or not at all; an unwritable directory is an error
  // naming it.
  PackageStorage late = makeStorage();
  EXPECT_THROW(late.spillTablesTo(dir / "late"), std::logic_error);
  test::writeFile(dir / "a-file", "x");
  PackageStorage nowhere;
  try {
    nowhere.spillTablesTo(dir / "a-file" / "tables");
    ADD_FAILURE() << "no error for an unwritable table directory";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("a-file"), std::string::npos) << e.what();
  }
}

TEST(Package, ParametricInstancesRoundTripWithConservativeBounds) {
  PackageStorage s = makeStorage();
  const pkg::InstanceRecord& rotated = s.instances[1];
  EXPECT_EQ(rotated.type, uint32_t(pkg::PrimitiveType::Cylinder));
  EXPECT_EQ(rotated.flags, 0u);
  EXPECT_FLOAT_EQ(rotated.origin[0], 1.0f);
  EXPECT_FLOAT_EQ(rotated.params[1], 2.0f);
  EXPECT_EQ(s.instances[2].profile_count, 3u);
  EXPECT_EQ(s.instances[0].flags, pkg::kInstanceCapped);
  // Points on the rotated cylinder's surface lie in the cluster's box and sphere.
  const ClusterRecord& c = s.clusters[5];
  EXPECT_EQ(c.kind, uint8_t(pkg::ClusterKind::Parametric));
  EXPECT_EQ(c.instance_count, 2u);
  glm::mat3 linear(rotated.linear[0], rotated.linear[1], rotated.linear[2], rotated.linear[3],
                   rotated.linear[4], rotated.linear[5], rotated.linear[6], rotated.linear[7],
                   rotated.linear[8]);
  for (int i = 0; i < 64; ++i) {
    float a = float(i) * 0.3f, z = float(i % 9) * 0.25f;
    glm::vec3 p = glm::vec3(1.0f) + linear * glm::vec3(0.1f * std::cos(a), 0.1f * std::sin(a), z);
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(p[k], c.aabb_min[k] - 1e-6f);
      EXPECT_LE(p[k], c.aabb_max[k] + 1e-6f);
    }
    EXPECT_LE(glm::length(p - glm::vec3(c.center[0], c.center[1], c.center[2])), c.radius);
  }
  EXPECT_THROW(s.addInstance(Sphere{-1.0f}, Transform{}, 0), std::invalid_argument);
  EXPECT_THROW(s.addParametricCluster(1, 2, ClusterLod{}), std::invalid_argument);  // mixed
  EXPECT_THROW(s.addParametricCluster(2, 5, ClusterLod{}), std::invalid_argument);
}

TEST(Package, WriterRefusesInconsistentStorageAndLeavesNoFile) {
  auto dir = test::scratchDir();
  PackageStorage s = makeStorage();
  s.objects[1].layer = 9;
  try {
    writePackage(s, dir / "x.twk");
    ADD_FAILURE() << "wrote an inconsistent package";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("object layer 9 is out of range"), std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir));
  s = makeStorage();
  s.clusters[4].parent_error = 0.001f;  // root with a finite parent error
  EXPECT_THROW(writePackage(s, dir / "x.twk"), std::invalid_argument);
  EXPECT_TRUE(std::filesystem::is_empty(dir));

  // A failed write leaves an existing package untouched.
  const std::string good = writeToString(makeStorage(), dir / "x.twk");
  EXPECT_THROW(writePackage(s, dir / "x.twk"), std::invalid_argument);
  EXPECT_EQ(test::readFile(dir / "x.twk"), good);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), {}), 1);
}

TEST(Package, MissingFileOrDirectoryIsAFormatError) {
  auto dir = test::scratchDir();
  EXPECT_THROW(PackageView::open(dir / "none.twk"), FormatError);
  EXPECT_THROW(PackageView::open(dir), FormatError);
  test::writeFile(dir / "empty.twk", "");
  expectRejected("", "too small for a package header", 0);
}

TEST(Package, SpecificErrorsNameTheOffset) {
  PackageStorage s = makeStorage();
  // Records patched in place: tables stored as they are (as 1.1 wrote them, still valid).
  PackageWriteOptions plain;
  plain.compress_tables = false;
  const Bytes good{writeToString(s, test::scratchDir() / "good.twk", plain)};
  const pkg::SectionEntry clusters = good.entry(SectionType::Clusters);
  const pkg::SectionEntry objects = good.entry(SectionType::Objects);

  Bytes b = good;
  b.data[3] = 'X';
  expectRejected(b.data, "bad magic", 0);

  b = good;
  b.put<uint32_t>(8, 2);
  expectRejected(b.data, "unsupported package version 2", 8);

  b = good;
  b.put<uint32_t>(offsetof(pkg::PackageHeader, cluster_record_bytes), 120);
  expectRejected(b.data, "cluster record size 120 != 128", 48);

  expectRejected(good.data.substr(0, good.data.size() - 10), "truncated", 32);
  expectRejected(good.data.substr(0, 100), "too small for a package header", 100);

  b = good;
  b.data[sizeof(pkg::PackageHeader) + 10] ^= 0x40;  // section table, checksum not fixed
  expectRejected(b.data, "header checksum mismatch", offsetof(pkg::PackageHeader, header_checksum));

  b = good;
  pkg::SectionEntry e = clusters;
  e.offset += 8;
  b.setEntry(SectionType::Clusters, e);
  b.fixHeaderChecksum();
  expectRejected(b.data, "clusters section: offset", 256 + 8);

  b = good;
  e = good.entry(SectionType::Groups);
  e.offset = clusters.offset;
  b.setEntry(SectionType::Groups, e);
  b.fixHeaderChecksum();
  expectRejected(b.data, "overlaps", int64_t(clusters.offset));

  b = good;
  e = good.entry(SectionType::Strings);
  e.bytes = e.count = uint64_t(1) << 62;
  b.setEntry(SectionType::Strings, e);
  b.fixHeaderChecksum();
  expectRejected(b.data, "strings section: bytes", 256 + 7 * 48 + 8);

  b = good;
  e = clusters;
  e.count -= 1;  // bytes no longer match count * 128
  b.setEntry(SectionType::Clusters, e);
  b.fixHeaderChecksum();
  expectRejected(b.data, "do not hold", 256 + 24);

  b = good;
  b.data[clusters.offset + 5] ^= 0x01;
  expectRejected(b.data, "clusters section checksum mismatch", int64_t(clusters.offset));

  b = good;
  b.patchRecord<uint32_t>(SectionType::Clusters, 2, offsetof(ClusterRecord, page), 77);
  expectRejected(b.data, "cluster 2 page 77 is out of range",
                 int64_t(clusters.offset + 2 * 128 + 92));

  b = good;
  b.patchRecord<uint32_t>(SectionType::Clusters, 1, offsetof(ClusterRecord, encoded_bytes),
                          1u << 30);
  expectRejected(b.data, "are not inside page", int64_t(clusters.offset + 128 + 96));

  b = good;
  b.patchRecord<uint32_t>(SectionType::Clusters, 0, offsetof(ClusterRecord, object_max), 3);
  expectRejected(b.data, "cluster 0 object range [0, 3] is invalid (3 objects)",
                 int64_t(clusters.offset + 112));

  b = good;
  b.patchRecord<float>(SectionType::Clusters, 3, offsetof(ClusterRecord, parent_error), -1.0f);
  expectRejected(b.data, "not monotone", int64_t(clusters.offset + 3 * 128 + 44));

  b = good;
  b.patchRecord<uint32_t>(SectionType::Clusters, 1, offsetof(ClusterRecord, group), 0);
  expectRejected(b.data, "cluster 1 is not one of the clusters its group 0 produced",
                 int64_t(clusters.offset + 128 + 80));

  b = good;
  b.patchRecord<uint32_t>(SectionType::Clusters, 4, offsetof(ClusterRecord, parent_group), 0);
  b.patchRecord<float>(SectionType::Clusters, 4, offsetof(ClusterRecord, parent_error), 0.02f);
  expectRejected(b.data, "cluster 4 parent group 0 is out of range or does not match",
                 int64_t(clusters.offset + 4 * 128 + 84));

  b = good;
  b.patchRecord<float>(SectionType::Clusters, 2, offsetof(ClusterRecord, parent_error), 0.03f);
  expectRejected(b.data, "cluster 2 parent group 0 is out of range or does not match",
                 int64_t(clusters.offset + 2 * 128 + 84));

  b = good;
  b.patchRecord<uint32_t>(SectionType::Objects, 1, offsetof(pkg::ObjectRecord, layer), 2);
  expectRejected(b.data, "object layer 2 is out of range (2 layers)",
                 int64_t(objects.offset + 64 + 4));

  b = good;
  b.patchRecord<uint32_t>(SectionType::Objects, 1, offsetof(pkg::ObjectRecord, flags), 2u);
  expectRejected(b.data, "object flags has unknown bits", int64_t(objects.offset + 64 + 36));

  b = good;
  b.patchRecord<uint64_t>(SectionType::Objects, 2, offsetof(pkg::ObjectRecord, name_offset), 1000);
  expectRejected(b.data, "object name [1000, +4) is not inside the string pool",
                 int64_t(objects.offset + 128));

  b = good;
  b.patchRecord<uint32_t>(SectionType::Layers, 0, offsetof(pkg::LayerRecord, name_bytes), 70000);
  expectRejected(b.data, "layer name", int64_t(good.entry(SectionType::Layers).offset));

  b = good;
  b.patchRecord<uint32_t>(SectionType::Instances, 1, offsetof(pkg::InstanceRecord, object), 3);
  expectRejected(b.data, "instance object 3 is out of range", -1);

  b = good;
  b.patchRecord<uint32_t>(SectionType::Instances, 2, offsetof(pkg::InstanceRecord, profile_count),
                          4);
  expectRejected(b.data, "instance profile range is invalid", -1);

  b = good;
  b.patchRecord<uint32_t>(SectionType::Pages, 0, offsetof(pkg::PageRecord, stored_bytes), 1u << 31);
  expectRejected(b.data, "are not inside the page data section",
                 int64_t(good.entry(SectionType::Pages).offset));

  b = good;
  b.patchRecord<uint32_t>(SectionType::Groups, 0, offsetof(pkg::GroupRecord, cluster_count), 9);
  expectRejected(b.data, "group cluster range is invalid",
                 int64_t(good.entry(SectionType::Groups).offset + 48));
}

// Format 1.2: the instance, profile, object and string tables stored as zstd frames read back
// as the very records written plainly; a damaged frame or a wrong size is a FormatError at the
// frame's offset, and only those four sections may be compressed.
TEST(Package, CompressedTablesRoundTripAndRejectDamage) {
  PackageStorage s = makeStorage();
  // Enough instances and objects for zstd to have something to find.
  Transform t;
  for (int i = 0; i < 200; ++i) {
    t.origin = s.origin + glm::dvec3(0.5 * i, 0.0, 1.0);
    s.addInstance(Cylinder{0.05f, 3.0f, true}, t, uint32_t(i % 3));
  }
  s.addParametricCluster(3, 200, ClusterLod{});
  PackageWriteOptions plain;
  plain.compress_tables = false;
  const auto dir = test::scratchDir();
  const std::string packed = writeToString(s, dir / "packed.twk");
  const std::string unpacked = writeToString(s, dir / "plain.twk", plain);
  EXPECT_LT(packed.size(), unpacked.size());

  const Bytes good{packed};
  const pkg::SectionEntry instances = good.entry(SectionType::Instances);
  EXPECT_GT(instances.stored_bytes, 0u);
  EXPECT_LT(instances.stored_bytes, instances.bytes / 4) << "203 pipe records compress 4x or more";
  EXPECT_EQ(instances.count, 203u);
  EXPECT_EQ(good.entry(SectionType::Clusters).stored_bytes, 0u);
  EXPECT_EQ(good.entry(SectionType::PageData).stored_bytes, 0u);
  EXPECT_EQ(Bytes{unpacked}.entry(SectionType::Instances).stored_bytes, 0u);

  PackageView a = PackageView::open(dir / "packed.twk", PackageView::Verify::All);
  const PackageView b = PackageView::open(dir / "plain.twk", PackageView::Verify::All);
  auto same = [](auto x, auto y) {
    return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size_bytes()) == 0;
  };
  EXPECT_TRUE(same(a.instances(), b.instances()));
  EXPECT_TRUE(same(a.objects(), b.objects()));
  EXPECT_TRUE(same(a.profilePoints(), b.profilePoints()));
  EXPECT_EQ(a.strings(), b.strings());
  EXPECT_EQ(a.objectName(1), b.objectName(1));
  // The view moves with its decompressed tables.
  PackageView moved = std::move(a);
  EXPECT_TRUE(same(moved.instances(), b.instances()));

  // A damaged frame, its checksum made to match: zstd's own checks catch it.
  Bytes bad = good;
  for (uint64_t k = 8; k < instances.stored_bytes; k += 7) bad.data[instances.offset + k] ^= 0x5a;
  bad.fixSectionChecksum(SectionType::Instances);
  expectRejected(bad.data, "instances section ", int64_t(instances.offset));

  // A table that claims more records than the frame holds.
  bad = good;
  pkg::SectionEntry e = instances;
  e.count -= 1;
  e.bytes -= sizeof(pkg::InstanceRecord);
  bad.setEntry(SectionType::Instances, e);
  bad.fixHeaderChecksum();
  expectRejected(bad.data, "instances section zstd frame holds " + std::to_string(instances.bytes),
                 int64_t(instances.offset));

  // Clusters are read in place: a compressed cluster section is refused.
  bad = good;
  e = good.entry(SectionType::Clusters);
  e.stored_bytes = e.bytes;
  bad.setEntry(SectionType::Clusters, e);
  bad.fixHeaderChecksum();
  expectRejected(bad.data, "clusters section: stored compressed, but it must be read in place",
                 256 + 40);

  // A frame longer than the file.
  bad = good;
  e = instances;
  e.stored_bytes = uint64_t(1) << 40;
  bad.setEntry(SectionType::Instances, e);
  bad.fixHeaderChecksum();
  expectRejected(bad.data, "instances section: bytes", 256 + 3 * 48 + 8);
}

TEST(Package, PageDamageIsCaughtByPageChecksums) {
  PackageStorage s = makeStorage();
  auto path = test::scratchDir() / "p.twk";
  Bytes b{writeToString(s, path)};
  const pkg::SectionEntry data = b.entry(SectionType::PageData);
  b.data[data.offset + 20] ^= 0x10;  // inside page 0
  test::writeFile(path, b.data);
  // Headers-only open does not read page data; loading the page does.
  PackageView view = PackageView::open(path, PackageView::Verify::Headers);
  std::vector<uint8_t> raw;
  try {
    view.readPage(0, raw);
    ADD_FAILURE() << "corrupt page accepted";
  } catch (const FormatError& e) {
    EXPECT_NE(e.reason().find("page 0 checksum mismatch"), std::string::npos) << e.what();
    EXPECT_EQ(e.position(), data.offset);
  }
  view.readPage(1, raw);  // other pages are fine
  expectRejected(b.data, "page data section checksum mismatch", int64_t(data.offset),
                 PackageView::Verify::All);
}

// Opening a damaged package either works or throws FormatError naming the file.
TEST(Package, RobustToTruncationAndCorruption) {
  PackageStorage s = makeStorage();
  const std::string original = writeToString(s, test::scratchDir() / "orig.twk");
  ASSERT_LT(original.size(), 16384u);
  for (PackageView::Verify verify : {PackageView::Verify::Headers, PackageView::Verify::All}) {
    int rejected = test::expectRobustToDamage(
        original, "damaged.twk",
        [verify](const std::filesystem::path& path, SceneSink&) {
          PackageView view = PackageView::open(path, verify);
          // Use it the way the runtime does: every page, every mesh cluster.
          std::vector<uint8_t> raw;
          DecodedCluster decoded;
          for (uint32_t c = 0; c < view.clusters().size(); ++c) {
            if (view.clusters()[c].kind != uint8_t(pkg::ClusterKind::Mesh)) continue;
            view.readPage(view.clusters()[c].page, raw);
            view.decodeCluster(c, raw, decoded);
          }
        },
        500);
    EXPECT_GT(rejected, 0);
  }
}

// With Verify::All every changed byte anywhere in the file is caught, at every offset.
TEST(Package, VerifyAllCatchesEveryByteFlip) {
  PackageStorage s = makeStorage();
  const std::string original = writeToString(s, test::scratchDir() / "orig.twk");
  auto path = test::scratchDir() / "flipped.twk";
  int accepted = 0;
  for (size_t at = 0; at < original.size(); ++at) {
    std::string bytes = original;
    bytes[at] = static_cast<char>(bytes[at] ^ (1 << (at % 8)));
    test::writeFile(path, bytes);
    try {
      PackageView::open(path, PackageView::Verify::All);
      ++accepted;
      ADD_FAILURE() << "flip at byte " << at << " not detected";
    } catch (const FormatError&) {
    }
    if (accepted > 5) break;
  }
}

// A whole OBJ merged into one indexed mesh, with per-vertex object indices and smooth normals.
struct MergedMesh {
  std::vector<glm::vec3> positions, normals;
  std::vector<uint32_t> indices, vertex_objects;
  uint32_t object_count = 0;
};

MergedMesh loadMerged(const std::filesystem::path& obj) {
  test::CollectingSink sink;
  readObj(obj, sink);
  MergedMesh m;
  for (const SceneObject& o : sink.objects) {
    const auto& part = std::get<TriangleMesh>(o.geometry);
    uint32_t base = static_cast<uint32_t>(m.positions.size());
    m.positions.insert(m.positions.end(), part.positions.begin(), part.positions.end());
    m.vertex_objects.insert(m.vertex_objects.end(), part.positions.size(), o.info.id);
    m.object_count = std::max(m.object_count, o.info.id + 1);
    for (uint32_t i : part.indices) m.indices.push_back(base + i);
  }
  m.normals.assign(m.positions.size(), glm::vec3(0.0f));
  for (size_t t = 0; t < m.indices.size() / 3; ++t) {
    const uint32_t* v = &m.indices[t * 3];
    glm::vec3 n =
        glm::cross(m.positions[v[1]] - m.positions[v[0]], m.positions[v[2]] - m.positions[v[0]]);
    for (int k = 0; k < 3; ++k) m.normals[v[k]] += n;
  }
  for (glm::vec3& n : m.normals) n = glm::length(n) > 0 ? glm::normalize(n) : glm::vec3(0, 0, 1);
  return m;
}

// Cuts `indices` (a level of `m`) into consecutive 256-triangle clusters after a spatial sort.
void addLevel(PackageStorage& s, const MergedMesh& m, const std::vector<uint32_t>& indices,
              uint16_t level, float error) {
  const size_t triangles = indices.size() / 3;
  std::vector<uint32_t> sorted(indices.size());
  meshopt_spatialSortTriangles(sorted.data(), indices.data(), indices.size(), &m.positions[0].x,
                               m.positions.size(), sizeof(glm::vec3));
  const size_t kClusterTriangles = 256;
  std::vector<uint32_t> remap(m.positions.size(), ~0u);
  for (size_t first = 0; first < triangles; first += kClusterTriangles) {
    size_t count = std::min(kClusterTriangles, triangles - first);
    std::vector<glm::vec3> positions, normals;
    std::vector<uint32_t> cluster_indices, objects;
    for (size_t i = first * 3; i < (first + count) * 3; ++i) {
      uint32_t v = sorted[i];
      if (remap[v] == ~0u) {
        remap[v] = static_cast<uint32_t>(positions.size());
        positions.push_back(m.positions[v]);
        normals.push_back(m.normals[v]);
      }
      cluster_indices.push_back(remap[v]);
    }
    for (size_t i = first * 3; i < (first + count) * 3; ++i) remap[sorted[i]] = ~0u;
    for (size_t t = first; t < first + count; ++t)
      objects.push_back(m.vertex_objects[sorted[t * 3]]);
    ClusterLod lod;  // a size measurement: every cluster a root, no groups
    lod.level = level;
    lod.error = error;
    s.addMeshCluster({positions, normals, cluster_indices, objects}, lod);
  }
}

struct SizeReport {
  double level0_bytes_per_triangle = 0;      // file with level 0 only
  double all_levels_bytes_per_triangle = 0;  // file with a simplification chain, per input triangle
  double level_triangle_ratio = 0;           // triangles in all levels / input triangles
};

// Level 0 alone, then level 0 plus a chain of 50% simplifications (meshopt_simplify, sloppy when
// it stalls on disconnected parts) down to one cluster: a stand-in for the cluster DAG's levels,
// which add about as many triangles.
SizeReport measureSize(const std::filesystem::path& obj, const std::string& label) {
  MergedMesh m = loadMerged(obj);
  const size_t input_triangles = m.indices.size() / 3;
  auto fresh = [&] {
    PackageStorage s;
    s.addLayer({"default", 0xffffffffu});
    for (uint32_t o = 0; o < m.object_count; ++o) {
      ObjectInfo info;
      info.id = o;
      info.name = "object-" + std::to_string(o);
      s.addObject(info, glm::vec3(0.0f), glm::vec3(0.0f));
    }
    return s;
  };
  auto path = test::scratchDir() / "measure.twk";
  SizeReport report;
  PackageStorage s = fresh();
  addLevel(s, m, m.indices, 0, 0.0f);
  PackageWriteStats level0 = writePackage(s, path);
  PackageView::open(path, PackageView::Verify::All);
  report.level0_bytes_per_triangle = double(level0.file_bytes) / input_triangles;

  std::vector<uint32_t> level = m.indices;
  size_t total_triangles = input_triangles;
  float error = 0.0f;
  const float scale =
      meshopt_simplifyScale(&m.positions[0].x, m.positions.size(), sizeof(glm::vec3));
  for (uint16_t l = 1; level.size() / 3 > 256 && l < 30; ++l) {
    std::vector<uint32_t> next(level.size());
    size_t target = level.size() / 6 * 3;
    float level_error = 0.0f;
    next.resize(meshopt_simplify(next.data(), level.data(), level.size(), &m.positions[0].x,
                                 m.positions.size(), sizeof(glm::vec3), target, 1.0f, 0,
                                 &level_error));
    if (next.size() > level.size() * 85 / 100) {
      next.resize(level.size());
      next.resize(meshopt_simplifySloppy(next.data(), level.data(), level.size(), &m.positions[0].x,
                                         m.positions.size(), sizeof(glm::vec3), target, 1.0f,
                                         &level_error));
    }
    if (next.empty()) break;
    error += level_error * scale;
    addLevel(s, m, next, l, error);
    total_triangles += next.size() / 3;
    level.swap(next);
  }
  PackageWriteStats all = writePackage(s, path);
  PackageView::open(path, PackageView::Verify::All);
  report.all_levels_bytes_per_triangle = double(all.file_bytes) / input_triangles;
  report.level_triangle_ratio = double(total_triangles) / input_triangles;
  std::cout << label << ": " << input_triangles << " triangles, " << m.object_count
            << " objects; level 0: " << report.level0_bytes_per_triangle
            << " bytes/triangle (page data "
            << double(level0.section_bytes[uint32_t(SectionType::PageData)]) / input_triangles
            << ", raw pages " << double(level0.page_raw_bytes) / input_triangles
            << ", cluster table "
            << double(level0.section_bytes[uint32_t(SectionType::Clusters)]) / input_triangles
            << "); with " << report.level_triangle_ratio
            << "x triangles in all levels: " << report.all_levels_bytes_per_triangle
            << " bytes per input triangle\n";
  ::testing::Test::RecordProperty(label + "_level0_bytes_per_triangle",
                                  std::to_string(report.level0_bytes_per_triangle));
  ::testing::Test::RecordProperty(label + "_all_levels_bytes_per_triangle",
                                  std::to_string(report.all_levels_bytes_per_triangle));
  return report;
}

TEST(Package, BunnyBytesPerTriangle) {
  auto obj = test::sharedDataDir() / "stanford-bunny.obj";
  if (!std::filesystem::exists(obj)) GTEST_SKIP() << "no " << obj;
  SizeReport r = measureSize(obj, "bunny");
  EXPECT_LT(r.level0_bytes_per_triangle, 12.0);
  EXPECT_LT(r.all_levels_bytes_per_triangle, 24.0);
}

TEST(Package, CadPartsBytesPerTriangle) {
  auto obj = test::sharedDataDir() / "kicad_dsub62.obj";
  if (!std::filesystem::exists(obj)) GTEST_SKIP() << "no " << obj;
  SizeReport r = measureSize(obj, "kicad_dsub62");
  EXPECT_LT(r.level0_bytes_per_triangle, 12.0);
  EXPECT_LT(r.all_levels_bytes_per_triangle, 24.0);
}

}  // namespace
}  // namespace tw
