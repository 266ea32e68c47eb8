// Tests for checkPackage (`terawalk verify`) and summarizePackage (`terawalk info` on a .twk): a
// hand-made, consistent 3-level DAG over a grid passes every check; each way of breaking it
// (checksum, references, errors, bounds, a moved locked border, a new hole) fails with the
// specific check, record and reason. End to end: packages of the bunny and the KiCad connector
// built by the real DAG builder and assembler pass every check.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "cluster_dag.h"
#include "covered_box_faces.h"
#include "obj_reader.h"
#include "package_assembly.h"
#include "package_check.h"
#include "package_summary.h"
#include "package_view.h"
#include "package_writer.h"
#include "test_support.h"

namespace tw {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// The surface z = 0.01 x y over [0, 2]^2: off the quantization grid, so clusters with different
// shifts (quadrants use cells of 2 steps, the halves and the root 4) decode shared vertices a
// little apart and the crack check must weld them within the quantization error.
glm::vec3 surface(float x, float y) { return {x, y, 0.01f * x * y}; }

struct Mesh {
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices, objects;
  ClusterGeometryInput input() const { return {positions, {}, indices, objects}; }
};

// Grid of quads with spacing 0.25 m over [x0, x0 + nx/4] x [y0, y0 + ny/4].
Mesh gridMesh(int nx, int ny, float x0, float y0) {
  Mesh m;
  for (int y = 0; y <= ny; ++y)
    for (int x = 0; x <= nx; ++x) m.positions.push_back(surface(x0 + 0.25f * x, y0 + 0.25f * y));
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x) {
      uint32_t a = y * (nx + 1) + x, b = a + 1, c = a + nx + 1, d = c + 1;
      m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
      m.objects.insert(m.objects.end(), {0, 0});
    }
  return m;
}

// The same rectangle simplified with its border locked: every border vertex of the grid kept,
// every interior one removed, triangulated as a fan around the centre.
Mesh lockedFan(int nx, int ny, float x0, float y0, glm::vec3 moved_from = glm::vec3(-1.0f),
               glm::vec3 moved_to = glm::vec3(0.0f)) {
  Mesh m;
  m.positions.push_back(surface(x0 + 0.125f * nx, y0 + 0.125f * ny));
  auto add = [&](int x, int y) {
    glm::vec3 p = surface(x0 + 0.25f * x, y0 + 0.25f * y);
    if (glm::length(p - moved_from) < 1e-6f) p = moved_to;
    m.positions.push_back(p);
  };
  for (int x = 0; x < nx; ++x) add(x, 0);
  for (int y = 0; y < ny; ++y) add(nx, y);
  for (int x = nx; x > 0; --x) add(x, ny);
  for (int y = ny; y > 0; --y) add(0, y);
  const uint32_t ring = static_cast<uint32_t>(m.positions.size() - 1);
  for (uint32_t i = 0; i < ring; ++i) {
    m.indices.insert(m.indices.end(), {0, 1 + i, 1 + (i + 1) % ring});
    m.objects.push_back(0);
  }
  return m;
}

struct Damage {
  glm::vec3 moved_from{-1.0f}, moved_to{0.0f};  // a vertex of cluster 4 (bottom half) moved
};

// Level 0: quadrants 0 (x<1,y<1), 1 (x>1,y<1), 2 (x<1,y>1), 3 (x>1,y>1).
// Group 0 (level 0): children 0, 1 -> cluster 4 (bottom half).
// Group 1 (level 0): children 2, 3 -> cluster 5 (top half).
// Group 2 (level 1): children 4, 5 -> cluster 6 (the whole square, root).
// Cluster 7: a parametric root (a cylinder) of object 1.
PackageStorage makeDag(const Damage& damage = {}) {
  PackageStorage s;
  s.origin = glm::dvec3(1000.0, 2000.0, 3.0);
  s.addLayer({"deck", 0xff808080u});
  s.addLayer({"piping", 0xff0000ffu});
  ObjectInfo o;
  o.id = 7;
  o.name = "plate";
  o.layer = 0;
  s.addObject(o, glm::vec3(0.0f), glm::vec3(2.0f, 2.0f, 0.05f));
  o.id = 8;
  o.name = "pipe";
  o.layer = 1;
  o.db_key = "P-8";
  s.addObject(o, glm::vec3(3.0f, 0.0f, 0.0f), glm::vec3(3.2f, 0.2f, 1.0f));

  const glm::vec4 sphere0(1.0f, 0.5f, 0.0f, 1.5f), sphere1(1.0f, 1.5f, 0.0f, 1.5f);
  const glm::vec4 sphere2(1.0f, 1.0f, 0.0f, 2.5f);
  for (int q = 0; q < 4; ++q) {
    ClusterLod lod;
    lod.parent_group = q < 2 ? 0 : 1;
    lod.parent_error = 0.01f;
    lod.parent_lod_sphere = q < 2 ? sphere0 : sphere1;
    s.addMeshCluster(gridMesh(4, 4, float(q % 2), float(q / 2)).input(), lod);
  }
  for (int half = 0; half < 2; ++half) {
    ClusterLod lod;
    lod.group = uint32_t(half);
    lod.parent_group = 2;
    lod.level = 1;
    lod.error = 0.01f;
    lod.parent_error = 0.05f;
    lod.lod_sphere = half == 0 ? sphere0 : sphere1;
    lod.parent_lod_sphere = sphere2;
    Mesh m = half == 0 ? lockedFan(8, 4, 0.0f, 0.0f, damage.moved_from, damage.moved_to)
                       : lockedFan(8, 4, 0.0f, 1.0f);
    s.addMeshCluster(m.input(), lod);
  }
  ClusterLod root;
  root.group = 2;
  root.level = 2;
  root.error = 0.05f;
  root.lod_sphere = sphere2;
  s.addMeshCluster(lockedFan(8, 8, 0.0f, 0.0f).input(), root);
  s.groups.push_back(
      {{1.0f, 0.5f, 0.0f}, 1.5f, {0, 0, 0}, 0.01f, {2, 1, 0.05f}, 0.05f, 4, 1, 0, 0});
  s.groups.push_back(
      {{1.0f, 1.5f, 0.0f}, 1.5f, {0, 1, 0}, 0.01f, {2, 2, 0.05f}, 0.05f, 5, 1, 0, 0});
  s.groups.push_back({{1.0f, 1.0f, 0.0f}, 2.5f, {0, 0, 0}, 0.05f, {2, 2, 0.05f}, kInf, 6, 1, 1, 0});

  Transform t;
  t.origin = s.origin + glm::dvec3(3.1, 0.1, 0.0);
  s.addInstance(Cylinder{0.1f, 1.0f, true}, t, 1);
  s.addParametricCluster(0, 1, ClusterLod{});
  return s;
}

PackageView writeAndOpen(const PackageStorage& s, const std::string& name = "dag.twk") {
  auto path = test::scratchDir() / name;
  writePackage(s, path, PackageWriteOptions{false, 9});
  return PackageView::open(path);
}

CheckReport check(const PackageStorage& s) { return checkPackage(writeAndOpen(s)); }

std::string describe(const CheckReport& r) {
  return r.failure ? r.failure->check + ": " + r.failure->what : std::string("ok");
}

TEST(PackageCheck, ConsistentDagPasses) {
  CheckReport r = check(makeDag());
  ASSERT_TRUE(r.ok()) << describe(r);
  EXPECT_EQ(r.counts.clusters, 8u);
  EXPECT_EQ(r.counts.groups, 3u);
  EXPECT_EQ(r.counts.instances, 1u);
  EXPECT_EQ(r.counts.pages, 1u);
  // Groups 0 and 1 each share the 8 edges of the line y = 1 with the other; group 2 shares none.
  EXPECT_EQ(r.counts.border_edges, 16u);
  // Every boundary edge of clusters 4, 5 (24 each) and 6 (32) was checked against the children.
  EXPECT_EQ(r.counts.boundary_edges, 80u);
  EXPECT_GT(r.counts.vertices, 4u * 25u);
  // header + 10 sections + 1 page
  EXPECT_EQ(r.counts.checksums, 12u);
}

TEST(PackageCheck, CompressedPagesAndSeveralPagesPass) {
  // The same DAG with one cluster per page, zstd on.
  PackageStorage base = makeDag();
  PackageStorage many = base;
  many.target_page_bytes = 200;
  many.pages.clear();
  for (pkg::ClusterRecord& c : many.clusters) {
    if (c.kind != static_cast<uint8_t>(pkg::ClusterKind::Mesh)) continue;
    std::vector<uint8_t> copy(base.pages[c.page].begin() + c.page_offset,
                              base.pages[c.page].begin() + c.page_offset + c.encoded_bytes);
    many.placeEncodedCluster(copy, c);
  }
  auto path = test::scratchDir() / "zstd.twk";
  writePackage(many, path);
  PackageView view = PackageView::open(path);
  EXPECT_GT(view.pages().size(), 3u);
  CheckReport r = checkPackage(view);
  EXPECT_TRUE(r.ok()) << describe(r);
  EXPECT_EQ(r.counts.pages, view.pages().size());
}

TEST(PackageCheck, CorruptPageByteFailsChecksums) {
  auto dir = test::scratchDir();
  auto path = dir / "bad.twk";
  writePackage(makeDag(), path, PackageWriteOptions{false, 9});
  std::string bytes = test::readFile(path);
  uint64_t page_data;
  {
    PackageView view = PackageView::open(path);
    page_data = view.section(pkg::SectionType::PageData).offset;
  }
  bytes[page_data + 100] ^= 0x10;
  test::writeFile(path, bytes);
  PackageView view = PackageView::open(path);  // Verify::Headers does not read page data
  CheckReport r = checkPackage(view);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->check, "checksums");
  EXPECT_EQ(r.failure->page, 0u);
  EXPECT_NE(r.failure->what.find("page 0 checksum"), std::string::npos) << r.failure->what;
  EXPECT_EQ(r.failure->file_offset, page_data);
}

TEST(PackageCheck, NonZeroPaddingFailsChecksums) {
  auto path = test::scratchDir() / "pad.twk";
  writePackage(makeDag(), path);
  std::string bytes = test::readFile(path);
  uint64_t gap = 0;
  {
    // The first byte after a section that ends off a 64-byte boundary is padding.
    PackageView view = PackageView::open(path);
    for (uint32_t i = 0; i < pkg::kSectionCount && gap == 0; ++i) {
      const auto& e = view.section(static_cast<pkg::SectionType>(i));
      const uint64_t stored = pkg::storedBytes(e);
      if (stored > 0 && (e.offset + stored) % 64 != 0) gap = e.offset + stored;
    }
  }
  ASSERT_NE(gap, 0u);
  bytes[gap] = 1;
  test::writeFile(path, bytes);
  CheckReport r = checkPackage(PackageView::open(path));
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->check, "checksums");
  EXPECT_EQ(r.failure->file_offset, gap);
}

TEST(PackageCheck, ErrorMonotonicityIsEnforced) {
  // The view itself rejects a cluster whose error exceeds its parent error: not writable.
  PackageStorage bad = makeDag();
  bad.clusters[4].error = 0.2f;
  bad.groups[0].error = 0.2f;
  EXPECT_THROW(writePackage(bad, test::scratchDir() / "x.twk"), std::invalid_argument);

  // A parent lod sphere that does not hold the child's: the projected error can shrink.
  PackageStorage s = makeDag();
  for (int c : {4, 5}) s.clusters[c].parent_lod_radius = 1.0f;
  s.clusters[6].lod_radius = 1.0f;
  s.clusters[6].parent_lod_radius = 1.0f;
  s.groups[2].lod_radius = 1.0f;
  CheckReport r = check(s);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->check, "errors");
  EXPECT_EQ(r.failure->cluster, 4u);
  EXPECT_NE(r.failure->what.find("not inside its parent lod sphere"), std::string::npos)
      << r.failure->what;

  // The group's max parent error must be its produced clusters' largest.
  s = makeDag();
  s.groups[0].max_parent_error = 0.04f;
  r = check(s);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->check, "errors");
  EXPECT_EQ(r.failure->group, 0u);
  EXPECT_NE(r.failure->what.find("max parent error 0.04"), std::string::npos) << r.failure->what;

  // Siblings share their group's lod sphere.
  s = makeDag();
  s.clusters[4].lod_center[0] += 0.1f;
  r = check(s);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->check, "errors");
  EXPECT_EQ(r.failure->cluster, 4u);
}

TEST(PackageCheck, GroupWithoutChildrenFailsReferences) {
  PackageStorage s = makeDag();
  s.groups.push_back(
      {{1.0f, 1.0f, 0.0f}, 2.5f, {0, 0, 0}, 0.05f, {2, 2, 0.05f}, 0.05f, 0, 0, 0, 0});
  CheckReport r = check(s);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->check, "references");
  EXPECT_EQ(r.failure->group, 3u);
  EXPECT_NE(r.failure->what.find("replaces no cluster"), std::string::npos) << r.failure->what;
}

TEST(PackageCheck, BoxNotHoldingItsVerticesFailsBounds) {
  PackageStorage s = makeDag();
  s.clusters[1].aabb_max[0] -= 0.1f;  // quadrant 1 reaches x = 2
  CheckReport r = check(s);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->check, "bounds");
  EXPECT_EQ(r.failure->cluster, 1u);
  EXPECT_NE(r.failure->what.find("outside the cluster box"), std::string::npos) << r.failure->what;
}

TEST(PackageCheck, SphereNotHoldingItsVerticesFailsBounds) {
  PackageStorage s = makeDag();
  s.clusters[2].radius *= 0.9f;
  CheckReport r = check(s);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->check, "bounds");
  EXPECT_EQ(r.failure->cluster, 2u);
  EXPECT_NE(r.failure->what.find("from the sphere centre"), std::string::npos) << r.failure->what;
}

TEST(PackageCheck, InstanceOutsideItsClusterFailsBounds) {
  PackageStorage s = makeDag();
  s.clusters[7].aabb_max[2] = 0.5f;  // the cylinder is 1 m tall
  CheckReport r = check(s);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->check, "bounds");
  EXPECT_EQ(r.failure->cluster, 7u);
  EXPECT_NE(r.failure->what.find("instance 0"), std::string::npos) << r.failure->what;
}

// A package marked as holding the sealed-run search's roles passes while they are the search's
// (the lone capped cylinder is in no run); a member flag the search does not find fails, naming
// the instance; and an unmarked package may not carry such flags at all.
TEST(PackageCheck, SealedRunFlagsMustBeTheSearchResult) {
  PackageStorage s = makeDag();
  s.sealed_runs_marked = true;
  CheckReport marked = check(s);
  EXPECT_TRUE(marked.ok()) << describe(marked);
  EXPECT_TRUE(writeAndOpen(s).header().flags & pkg::kHeaderSealedRunsMarked);

  s.instances[0].flags |= pkg::kInstanceSealedRunMember;
  CheckReport r = check(s);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->check, "sealed runs");
  EXPECT_NE(r.failure->what.find("instance 0 has sealed-run flags 2 but the search finds 0"),
            std::string::npos)
      << r.failure->what;

  s.sealed_runs_marked = false;
  EXPECT_THROW(writeAndOpen(s, "unmarked.twk"), std::invalid_argument);
}

// Two plates side by side: a package marked as holding the covered-face search's result passes
// while the flags are the search's; a face it does not find fails, naming the instance; an
// unmarked package may not carry such flags, nor may anything but a box.
TEST(PackageCheck, CoveredFaceFlagsMustBeTheSearchResult) {
  PackageStorage s = makeDag();
  s.covered_faces_marked = true;
  Transform left, right;
  left.origin = s.origin + glm::dvec3(3.5, 1.0, 0.0);
  right.origin = s.origin + glm::dvec3(4.5, 1.0, 0.0);
  const Box plate{glm::vec3(0.5f, 0.5f, 0.05f)};
  constexpr uint8_t kPlusX = 2, kMinusX = 1;
  s.addInstance(plate, left, 1, coveredFaceInstanceFlags(kPlusX));
  s.addInstance(plate, right, 1, coveredFaceInstanceFlags(kMinusX));
  s.addParametricCluster(1, 2, ClusterLod{});
  CheckReport marked = check(s);
  EXPECT_TRUE(marked.ok()) << describe(marked);
  EXPECT_TRUE(writeAndOpen(s).header().flags & pkg::kHeaderCoveredFacesMarked);

  s.instances[2].flags |= coveredFaceInstanceFlags(8);  // +Y: nothing there
  CheckReport r = check(s);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->check, "box faces");
  EXPECT_NE(r.failure->what.find("instance 2 has covered faces 9 but the search finds 1"),
            std::string::npos)
      << r.failure->what;

  s.covered_faces_marked = false;
  EXPECT_THROW(writeAndOpen(s, "unmarked-faces.twk"), std::invalid_argument);
  Transform t;
  t.origin = s.origin;
  EXPECT_THROW(s.addInstance(Cylinder{0.1f, 1.0f, true}, t, 1, coveredFaceInstanceFlags(1)),
               std::invalid_argument);
}

TEST(PackageCheck, ObjectBoxMustHoldItsLevel0Triangles) {
  PackageStorage s = makeDag();
  s.objects[0].aabb_max[0] = 1.5f;  // the plate reaches x = 2
  CheckReport r = check(s);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->check, "bounds");
  EXPECT_NE(r.failure->what.find("outside the object's box"), std::string::npos) << r.failure->what;
  EXPECT_NE(r.failure->what.find("of object 0"), std::string::npos) << r.failure->what;
}

TEST(PackageCheck, GroupBoxMustHoldProducedClusters) {
  PackageStorage s = makeDag();
  s.groups[1].aabb_min[1] = 1.5f;
  CheckReport r = check(s);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->check, "bounds");
  EXPECT_EQ(r.failure->group, 1u);
  EXPECT_EQ(r.failure->cluster, 5u);
}

TEST(PackageCheck, MovedSharedBorderVertexIsACrack) {
  Damage d;
  d.moved_from = surface(1.0f, 1.0f);  // on the line group 0 shares with group 1's children
  d.moved_to = surface(1.0f, 0.98f);
  CheckReport r = check(makeDag(d));
  ASSERT_TRUE(r.failure) << "a moved locked vertex must fail";
  EXPECT_EQ(r.failure->check, "cracks");
  EXPECT_EQ(r.failure->group, 0u);
  EXPECT_NE(r.failure->what.find("locked border moved"), std::string::npos) << r.failure->what;
}

TEST(PackageCheck, TinyBorderShiftWithinQuantizationIsNotACrack) {
  // Moving a shared border vertex by a fraction of the quantization step changes nothing the
  // decoder can see at the coarser shift, so the check must accept it.
  Damage d;
  d.moved_from = surface(1.0f, 1.0f);
  d.moved_to = surface(1.0f, 1.0f) + glm::vec3(2e-6f, 0.0f, 0.0f);
  CheckReport r = check(makeDag(d));
  EXPECT_TRUE(r.ok()) << describe(r);
}

TEST(PackageCheck, MovedOpenBorderVertexIsAHole) {
  Damage d;
  d.moved_from = surface(0.5f, 0.0f);  // on the mesh's open border, shared with nobody
  d.moved_to = surface(0.5f, 0.1f);
  CheckReport r = check(makeDag(d));
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->check, "cracks");
  EXPECT_EQ(r.failure->group, 0u);
  EXPECT_NE(r.failure->what.find("boundary edge"), std::string::npos) << r.failure->what;
}

TEST(PackageCheck, CrackCheckCanBeSkipped) {
  Damage d;
  d.moved_from = surface(1.0f, 1.0f);
  d.moved_to = surface(1.0f, 0.98f);
  CheckOptions options;
  options.cracks = false;
  CheckReport r = checkPackage(writeAndOpen(makeDag(d)), options);
  EXPECT_TRUE(r.ok()) << describe(r);
  EXPECT_EQ(r.counts.border_edges, 0u);
}

TEST(PackageCheck, EmptyPackagePasses) {
  PackageStorage s;
  s.addLayer({"default", 0});
  CheckReport r = check(s);
  EXPECT_TRUE(r.ok()) << describe(r);
}

// open(Verify::Headers) + checkPackage catch every changed byte, as Verify::All does, and never
// crash or throw anything but FormatError on damaged files.
TEST(PackageCheck, EveryByteFlipIsCaught) {
  auto dir = test::scratchDir();
  writePackage(makeDag(), dir / "orig.twk");
  const std::string original = test::readFile(dir / "orig.twk");
  auto path = dir / "flipped.twk";
  int missed = 0;
  for (size_t at = 0; at < original.size() && missed <= 5; ++at) {
    std::string bytes = original;
    bytes[at] = static_cast<char>(bytes[at] ^ (1 << (at % 8)));
    test::writeFile(path, bytes);
    try {
      CheckReport r = checkPackage(PackageView::open(path));
      if (r.ok()) {
        ++missed;
        ADD_FAILURE() << "flip at byte " << at << " not detected";
      }
    } catch (const FormatError&) {
    }
  }
}

TEST(PackageCheck, RobustToDamage) {
  auto dir = test::scratchDir();
  writePackage(makeDag(), dir / "orig.twk");
  int rejected = test::expectRobustToDamage(
      test::readFile(dir / "orig.twk"), "damaged.twk",
      [](const std::filesystem::path& path, SceneSink&) {
        CheckReport r = checkPackage(PackageView::open(path));
        if (!r.ok())
          throw FormatError::atByte(path.string(), r.failure->file_offset, r.failure->what);
      });
  EXPECT_GT(rejected, 300);
}

struct CancelAfter : Progress {
  int updates_left;
  explicit CancelAfter(int n) : updates_left(n) {}
  void beginStage(std::string_view, uint64_t) override {}
  void update(uint64_t) override { --updates_left; }
  void endStage() override {}
  bool cancelled() const override { return updates_left <= 0; }
};

TEST(PackageCheck, CancellationStopsEarly) {
  CancelAfter progress(1);
  CheckReport r = checkPackage(writeAndOpen(makeDag()), {}, &progress);
  EXPECT_TRUE(r.cancelled);
  EXPECT_FALSE(r.failure);
  EXPECT_FALSE(r.ok());
}

TEST(PackageSummary, CountsPerLevel) {
  PackageStorage s = makeDag();
  PackageView view = writeAndOpen(s);
  PackageSummary sum = summarizePackage(view);
  ASSERT_EQ(sum.levels.size(), 3u);
  EXPECT_EQ(sum.level_count, 3u);
  EXPECT_EQ(sum.levels[0].clusters, 5u);  // 4 quadrants + the parametric cluster
  EXPECT_EQ(sum.levels[0].parametric_clusters, 1u);
  EXPECT_EQ(sum.levels[0].instances, 1u);
  EXPECT_EQ(sum.levels[0].triangles, 4u * 32u);
  EXPECT_EQ(sum.levels[1].triangles, 2u * 24u);
  EXPECT_EQ(sum.levels[2].triangles, 32u);
  EXPECT_EQ(sum.levels[0].groups, 2u);
  EXPECT_EQ(sum.levels[1].groups, 1u);
  EXPECT_EQ(sum.levels[2].roots, 1u);
  EXPECT_EQ(sum.levels[0].roots, 1u);  // the cylinder
  EXPECT_FLOAT_EQ(sum.levels[1].min_error_m, 0.01f);
  EXPECT_FLOAT_EQ(sum.levels[2].max_error_m, 0.05f);
  EXPECT_NEAR(sum.levels[0].mean_error_m, 0.0, 1e-12);
  EXPECT_EQ(sum.total_triangles, 128u);
  EXPECT_EQ(sum.all_level_triangles, 128u + 48u + 32u);
  EXPECT_EQ(sum.objects, 2u);
  EXPECT_EQ(sum.objects_with_db_key, 1u);
  ASSERT_EQ(sum.layers.size(), 2u);
  EXPECT_EQ(sum.layers[1].name, "piping");
  EXPECT_EQ(sum.layers[1].objects, 1u);
  EXPECT_EQ(sum.instances_by_type[0], 1u);  // cylinder
  EXPECT_FALSE(sum.sealed_runs_marked);
  EXPECT_EQ(sum.pages, 1u);
  EXPECT_EQ(sum.pages_compressed, 0u);
  EXPECT_EQ(sum.page_stored_bytes, sum.page_raw_bytes);
  EXPECT_EQ(sum.section_bytes[0], 8u * sizeof(pkg::ClusterRecord));
  EXPECT_EQ(sum.file_bytes, view.fileBytes());
  EXPECT_DOUBLE_EQ(sum.origin.x, 1000.0);
  EXPECT_NEAR(sum.bytesPerInputTriangle(), double(view.fileBytes()) / 128.0, 1e-9);
  EXPECT_STREQ(packagePrimitiveTypeName(3), "torus");
}

// Reads an OBJ into one buffer relative to its first object's origin, with one package object
// per mesh object (boxes of their level-0 geometry), builds the DAG and writes the package.
std::filesystem::path buildRealPackage(const std::filesystem::path& obj, const std::string& name,
                                       const std::function<void(ClusterDag&)>& damage = {}) {
  test::CollectingSink sink;
  readObj(obj, sink);
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices, ids;
  PackageStorage storage;
  storage.addLayer({"default", 0xff808080u});
  bool first = true;
  for (const auto& object : sink.objects) {
    const auto* mesh = std::get_if<TriangleMesh>(&object.geometry);
    if (!mesh) continue;
    if (first) storage.origin = object.info.transform.origin;
    first = false;
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    const uint32_t base = uint32_t(positions.size());
    for (const glm::vec3& p : mesh->positions) {
      positions.push_back(glm::vec3(object.info.transform.apply(p) - storage.origin));
      lo = glm::min(lo, positions.back());
      hi = glm::max(hi, positions.back());
    }
    ObjectInfo info = object.info;
    info.layer = 0;
    const uint32_t id = storage.addObject(info, lo, hi);
    for (uint32_t i : mesh->indices) indices.push_back(base + i);
    ids.insert(ids.end(), mesh->triangleCount(), id);
  }
  ClusterDag dag = buildClusterDag({positions, indices, ids});
  if (damage) damage(dag);
  addDagToPackage(dag, storage);
  auto path = test::scratchDir() / name;
  writePackage(storage, path);
  return path;
}

TEST(PackageCheck, BunnyPackagePasses) {
  auto obj = test::sharedDataDir() / "stanford-bunny.obj";
  if (!std::filesystem::exists(obj)) GTEST_SKIP() << "shared data not present: " << obj;
  PackageView view = PackageView::open(buildRealPackage(obj, "bunny.twk"));
  CheckReport r = checkPackage(view);
  EXPECT_TRUE(r.ok()) << describe(r);
  EXPECT_EQ(r.counts.clusters, view.clusters().size());
  EXPECT_EQ(r.counts.groups, view.groups().size());
  EXPECT_GT(r.counts.border_edges, 1000u);
  std::printf(
      "[ verify ] bunny: %zu clusters, %zu groups, %llu shared border edges, %llu "
      "boundary edges checked\n",
      view.clusters().size(), view.groups().size(), (unsigned long long)r.counts.border_edges,
      (unsigned long long)r.counts.boundary_edges);
}

TEST(PackageCheck, BunnyWithAMovedLockedVertexFailsCracks) {
  auto obj = test::sharedDataDir() / "stanford-bunny.obj";
  if (!std::filesystem::exists(obj)) GTEST_SKIP() << "shared data not present: " << obj;
  uint32_t damaged_group = pkg::kNone;
  auto moveSharedVertex = [&](ClusterDag& dag) {
    // A vertex of group g's produced cluster that also belongs to a level-0 cluster of another
    // group: on the locked border. Move it by 0.1 mm (the quantization error is 13 um here).
    for (uint32_t g = 0; g < dag.groups.size() && damaged_group == pkg::kNone; ++g) {
      const DagGroup& group = dag.groups[g];
      if (group.level != 0 || group.clusters.empty()) continue;
      std::set<std::tuple<float, float, float>> outside;
      for (const DagCluster& c : dag.clusters)
        if (c.level == 0 && c.parent_group != g)
          for (const glm::vec3& p : c.positions) outside.insert({p.x, p.y, p.z});
      DagCluster& produced = dag.clusters[group.clusters[0]];
      for (glm::vec3& p : produced.positions)
        if (outside.count({p.x, p.y, p.z})) {
          p.x += 1e-4f;
          damaged_group = g;
          break;
        }
    }
  };
  PackageView view = PackageView::open(buildRealPackage(obj, "bunny.twk", moveSharedVertex));
  ASSERT_NE(damaged_group, pkg::kNone);
  CheckReport r = checkPackage(view);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->check, "cracks") << r.failure->what;
  EXPECT_EQ(r.failure->group, damaged_group) << r.failure->what;
}

TEST(PackageCheck, KicadPackagePasses) {
  // 648 parts, clusters at different quantization shifts: the crack check welds across shifts.
  auto obj = test::sharedDataDir() / "kicad_dsub62.obj";
  if (!std::filesystem::exists(obj)) GTEST_SKIP() << "shared data not present: " << obj;
  PackageView view = PackageView::open(buildRealPackage(obj, "kicad.twk"));
  CheckReport r = checkPackage(view);
  EXPECT_TRUE(r.ok()) << describe(r);
  EXPECT_GT(r.counts.border_edges, 1000u);
}

}  // namespace
}  // namespace tw
