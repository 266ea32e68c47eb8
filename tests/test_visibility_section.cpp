// The package's visibility section end to end on the formats side: encode/parse round trip, every
// truncation and random corruption rejected cleanly, hand-made bad inputs with their messages and
// offsets; replacePackageSection on a real (small) package, the view's extra checks, and what
// `terawalk info` reports.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>

#include "dag_front.h"
#include "package_rewrite.h"
#include "package_summary.h"
#include "package_view.h"
#include "preprocess_driver.h"
#include "test_support.h"
#include "tws_writer.h"
#include "visibility_section.h"

namespace tw {
namespace {

namespace fs = std::filesystem;
using pkg::VisibilityCellRecord;
using pkg::VisibilityHeader;

constexpr uint64_t kSectionOffset = 1024;  // where the hand-made sections "are" in a file
constexpr uint64_t kClusterCount = 200;

// 6 x 5 x 4 grid, 40 stored cells, occluder and visible sets of varied sizes (about 2.9 KB, so the
// damage harness tries every truncation).
VisibilityData sampleData(bool visible_sets = true) {
  VisibilityData d;
  d.grid_dims = {6, 5, 4};
  d.grid_min = {-3.0, 10.5, 0.25};
  d.cell_size_m = 2.5;
  d.rays_per_cell = 256;
  d.candidate_level = 2;
  d.candidate_triangles = 12345;
  d.solid_cells = 17;
  d.visible_sets = visible_sets;
  for (uint32_t i = 0; i < 40; ++i) {
    VisibilityCell c;
    c.grid_index = i * 3 + (i % 2);
    for (uint32_t k = 0; k < 1 + i % 5; ++k) c.occluders.push_back((i * 7 + k * 13) % 200);
    if (visible_sets)
      for (uint32_t k = 0; k < 3 + i % 8; ++k) c.visible.push_back(i + k * 17);
    c.occluder_coverage = 0.5f + 0.01f * float(i);
    c.hit_fraction = 0.9f;
    d.cells.push_back(c);
  }
  d.rays_cast = uint64_t{d.rays_per_cell} * d.cells.size();
  return d;
}

// Parses bytes from an 8-byte-aligned copy (a vector<uint8_t> promises no alignment).
struct AlignedBytes {
  std::vector<uint64_t> storage;
  std::span<const uint8_t> bytes;
  explicit AlignedBytes(std::span<const uint8_t> in) : storage((in.size() + 7) / 8) {
    if (!in.empty()) std::memcpy(storage.data(), in.data(), in.size());
    bytes = {reinterpret_cast<const uint8_t*>(storage.data()), in.size()};
  }
};

VisibilityView parseCopy(const AlignedBytes& a, uint64_t cluster_count = kClusterCount) {
  return VisibilityView::parse(a.bytes, "vis.bin", kSectionOffset, cluster_count);
}

template <typename T>
void patch(std::vector<uint8_t>& bytes, size_t offset, T value) {
  std::memcpy(bytes.data() + offset, &value, sizeof(T));
}

constexpr size_t kCellsAt = sizeof(VisibilityHeader);
size_t cellAt(size_t i) { return kCellsAt + i * sizeof(VisibilityCellRecord); }

TEST(VisibilitySection, RoundTrip) {
  const VisibilityData d = sampleData();
  const std::vector<uint8_t> bytes = encodeVisibility(d);
  uint64_t occluders = 0, visible = 0;
  for (const VisibilityCell& c : d.cells) {
    occluders += c.occluders.size();
    visible += c.visible.size();
  }
  EXPECT_EQ(bytes.size(), 128 + 32 * d.cells.size() + 4 * (occluders + visible));
  AlignedBytes a(bytes);
  const VisibilityView view = parseCopy(a);
  ASSERT_FALSE(view.empty());
  const VisibilityHeader& h = view.header();
  EXPECT_EQ(std::memcmp(h.magic, "TWVIS001", 8), 0);
  EXPECT_EQ(h.grid_dims[0], 6u);
  EXPECT_EQ(h.grid_dims[1], 5u);
  EXPECT_EQ(h.grid_dims[2], 4u);
  EXPECT_EQ(h.grid_min[1], 10.5);
  EXPECT_EQ(h.cell_size_m, 2.5);
  EXPECT_EQ(h.rays_per_cell, 256u);
  EXPECT_EQ(h.rays_cast, 256u * 40u);
  EXPECT_EQ(h.candidate_level, 2u);
  EXPECT_EQ(h.candidate_triangles, 12345u);
  EXPECT_EQ(h.solid_cells, 17u);
  EXPECT_EQ(h.flags, uint32_t{pkg::kVisibleSetsPresent});
  EXPECT_EQ(h.occluder_id_count, occluders);
  EXPECT_EQ(h.visible_id_count, visible);
  ASSERT_EQ(view.cells().size(), d.cells.size());
  for (size_t i = 0; i < d.cells.size(); ++i) {
    const VisibilityCell& want = d.cells[i];
    const VisibilityCellRecord* got = view.cell(want.grid_index);
    ASSERT_NE(got, nullptr) << i;
    EXPECT_EQ(got, &view.cells()[i]);
    auto occ = view.occluders(*got);
    auto vis = view.visible(*got);
    EXPECT_EQ(std::vector<uint32_t>(occ.begin(), occ.end()), want.occluders) << i;
    EXPECT_EQ(std::vector<uint32_t>(vis.begin(), vis.end()), want.visible) << i;
    EXPECT_EQ(got->occluder_coverage, want.occluder_coverage);
    EXPECT_EQ(got->hit_fraction, want.hit_fraction);
  }
  double expected_average = double(occluders) / double(d.cells.size());
  EXPECT_DOUBLE_EQ(view.averageOccluders(), expected_average);
  // Cells not stored (solid or gaps) and indices past the grid.
  EXPECT_EQ(view.cell(2), nullptr);    // between 0 and 4
  EXPECT_EQ(view.cell(119), nullptr);  // last grid cell, not stored
  EXPECT_EQ(view.cell(UINT32_MAX), nullptr);
  // Encoding is deterministic.
  EXPECT_EQ(encodeVisibility(d), bytes);
  EXPECT_TRUE(view.parametricCandidates().empty());

  // Parametric candidates follow the visible ids.
  VisibilityData p = d;
  p.parametric_occluders = true;
  p.parametric_candidates = {3, 8, 9};
  const std::vector<uint8_t> p_bytes = encodeVisibility(p);
  EXPECT_EQ(p_bytes.size(), bytes.size() + 12);
  AlignedBytes pa(p_bytes);
  const VisibilityView p_view = parseCopy(pa);
  EXPECT_EQ(p_view.header().flags, uint32_t{pkg::kVisibleSetsPresent | pkg::kParametricCandidates});
  EXPECT_EQ(p_view.header().parametric_candidate_count, 3u);
  const auto listed = p_view.parametricCandidates();
  EXPECT_EQ(std::vector<uint32_t>(listed.begin(), listed.end()), p.parametric_candidates);
  const auto last_visible = p_view.visible(p_view.cells().back());
  EXPECT_EQ(std::vector<uint32_t>(last_visible.begin(), last_visible.end()), d.cells.back().visible);
}

TEST(VisibilitySection, GridLookup) {
  AlignedBytes a(encodeVisibility(sampleData()));
  const VisibilityView view = parseCopy(a);
  const glm::dvec3 lo(-3.0, 10.5, 0.25);
  auto centre = [&](int x, int y, int z) { return lo + 2.5 * glm::dvec3(x + 0.5, y + 0.5, z + 0.5); };
  EXPECT_EQ(view.gridIndexAt(centre(0, 0, 0)), 0u);
  EXPECT_EQ(view.gridIndexAt(centre(1, 0, 0)), 1u);
  EXPECT_EQ(view.gridIndexAt(centre(0, 1, 0)), 6u);
  EXPECT_EQ(view.gridIndexAt(centre(0, 0, 1)), 30u);
  EXPECT_EQ(view.gridIndexAt(centre(5, 4, 3)), 119u);
  EXPECT_EQ(view.gridIndexAt(lo), 0u);  // the min corner is inside
  constexpr uint32_t kOut = UINT32_MAX;
  EXPECT_EQ(view.gridIndexAt(lo - glm::dvec3(1e-9, 0, 0)), kOut);
  EXPECT_EQ(view.gridIndexAt(lo + glm::dvec3(15.0, 1.0, 1.0)), kOut);  // x == max face
  EXPECT_EQ(view.gridIndexAt(centre(2, 5, 0)), kOut);
  EXPECT_EQ(view.gridIndexAt(glm::dvec3(std::nan(""), 11.0, 1.0)), kOut);
  EXPECT_EQ(view.gridIndexAt(glm::dvec3(1e300, 11.0, 1.0)), kOut);
  // cellAt: grid index 3 * 1 + 1 = 4 is stored (cell 1), grid index 2 is not.
  const VisibilityCellRecord* c = view.cellAt(centre(4, 0, 0));
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->grid_index, 4u);
  EXPECT_EQ(view.cellAt(centre(2, 0, 0)), nullptr);
  EXPECT_EQ(VisibilityView().gridIndexAt(centre(0, 0, 0)), kOut);
  EXPECT_EQ(VisibilityView().cellAt(centre(0, 0, 0)), nullptr);
}

TEST(VisibilitySection, EmptyAndCellFreeSections) {
  const VisibilityView none = VisibilityView::parse({}, "vis.bin", 0, 0);
  EXPECT_TRUE(none.empty());
  EXPECT_TRUE(none.cells().empty());
  EXPECT_EQ(none.averageOccluders(), 0.0);
  // Every cell solid: a header and nothing else, which is not the same as no section.
  VisibilityData d = sampleData(false);
  d.cells.clear();
  d.solid_cells = 120;
  AlignedBytes a(encodeVisibility(d));
  EXPECT_EQ(a.bytes.size(), 128u);
  const VisibilityView view = parseCopy(a, 0);
  EXPECT_FALSE(view.empty());
  EXPECT_EQ(view.header().flags, 0u);
  EXPECT_EQ(view.averageOccluders(), 0.0);
  EXPECT_EQ(view.cell(0), nullptr);
  // Without visible sets every visible() is empty.
  AlignedBytes b(encodeVisibility(sampleData(false)));
  const VisibilityView occluders_only = parseCopy(b);
  for (const VisibilityCellRecord& c : occluders_only.cells()) {
    EXPECT_TRUE(occluders_only.visible(c).empty());
    EXPECT_FALSE(occluders_only.occluders(c).empty());
  }
}

TEST(VisibilitySection, EncodeRejectsDataThatBreaksTheLayout) {
  auto rejects = [](VisibilityData d) { EXPECT_THROW(encodeVisibility(d), std::invalid_argument); };
  VisibilityData d = sampleData();
  d.grid_dims.y = 0;
  rejects(d);
  d = sampleData();
  d.grid_dims = {65536, 65536, 1};
  rejects(d);
  d = sampleData();
  d.cell_size_m = 0.0;
  rejects(d);
  d = sampleData();
  d.cell_size_m = std::numeric_limits<double>::infinity();
  rejects(d);
  d = sampleData();
  std::swap(d.cells[3], d.cells[4]);
  rejects(d);
  d = sampleData();
  d.cells[5].grid_index = d.cells[4].grid_index;
  rejects(d);
  d = sampleData();
  d.cells.back().grid_index = 120;
  rejects(d);
  d = sampleData(false);
  d.cells[0].visible = {1, 2};
  rejects(d);
  d = sampleData();
  d.cells[0].visible = {5, 5};
  rejects(d);
  d = sampleData();
  d.cells[0].occluder_coverage = 1.5f;
  rejects(d);
  d = sampleData();
  d.solid_cells = 100;  // + 40 stored > 120
  rejects(d);
  d = sampleData();
  d.parametric_candidates = {1};  // without parametric_occluders
  rejects(d);
  d.parametric_occluders = true;
  d.parametric_candidates = {4, 2};
  rejects(d);
}

TEST(VisibilitySection, EveryTruncationAndCorruptionIsRejectedCleanly) {
  const std::vector<uint8_t> bytes = encodeVisibility(sampleData());
  ASSERT_LE(bytes.size(), 4096u);  // every truncation is tried
  const std::string original(bytes.begin(), bytes.end());
  int rejected = test::expectRobustToDamage(
      original, "vis.bin",
      [](const fs::path& path, SceneSink&) {
        const std::string data = test::readFile(path);
        AlignedBytes a(std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(data.data()),
                                                data.size()));
        const VisibilityView view = VisibilityView::parse(a.bytes, path.string(), 4096, 200);
        // Whatever was accepted must be safe to walk.
        for (const VisibilityCellRecord& c : view.cells()) {
          for (uint32_t id : view.occluders(c)) ASSERT_LT(id, 200u);
          for (uint32_t id : view.visible(c)) ASSERT_LT(id, 200u);
          ASSERT_EQ(view.cell(c.grid_index), &c);
        }
      });
  // Every truncation but the empty one (no section = no data) is rejected, and so are most
  // corruptions (ids, ranges, order, sizes; a few land on free-form fields such as rays_cast).
  EXPECT_GE(rejected, int(bytes.size()) - 1 + 150);
}

struct BadCase {
  const char* name;
  std::function<void(std::vector<uint8_t>&)> damage;
  uint64_t offset;  // in the section
  const char* reason;
  uint64_t cluster_count = kClusterCount;
};

TEST(VisibilitySection, HandMadeBadInputsNameTheFieldAndOffset) {
  const std::vector<uint8_t> good = encodeVisibility(sampleData());
  const VisibilityData data = sampleData();
  const size_t occluders_at = cellAt(data.cells.size());
  size_t visible_ids = 0;
  for (const VisibilityCell& c : data.cells) visible_ids += c.visible.size();
  const size_t visible_at = good.size() - 4 * visible_ids;
  const BadCase cases[] = {
      {"magic", [](auto& b) { b[3] = 'X'; }, 0, "bad magic"},
      {"header size", [](auto& b) { patch<uint32_t>(b, 8, 64); }, 8, "header size 64 != 128"},
      {"record size", [](auto& b) { patch<uint32_t>(b, 12, 16); }, 12, "cell record size 16 != 32"},
      {"zero dim", [](auto& b) { patch<uint32_t>(b, 20, 0); }, 16, "grid dimension is zero"},
      {"huge grid",
       [](auto& b) {
         patch<uint32_t>(b, 16, 1u << 20);
         patch<uint32_t>(b, 20, 1u << 20);
       },
       16, "too large for 32-bit indices"},
      {"cell count past grid", [](auto& b) { patch<uint32_t>(b, 28, 121); }, 28,
       "cell count 121 exceeds the grid's 120 cells"},
      {"negative cell size", [](auto& b) { patch<double>(b, 56, -1.0); }, 56,
       "cell size is not finite and positive"},
      {"nan grid min", [](auto& b) { patch<double>(b, 40, std::nan("")); }, 32,
       "grid bounds are not finite"},
      {"too many solid", [](auto& b) { patch<uint32_t>(b, 96, 81); }, 96,
       "solid cells 81 plus stored cells 40 exceed"},
      {"unknown flag", [](auto& b) { patch<uint32_t>(b, 100, 5); }, 100, "unknown flags 4"},
      {"visible ids without flag", [](auto& b) { patch<uint32_t>(b, 100, 0); }, 72,
       "visible-sets flag is off"},
      {"reserved", [](auto& b) { patch<uint64_t>(b, 120, 1); }, 120,
       "reserved header field is not zero"},
      {"parametric list without flag", [](auto& b) { patch<uint64_t>(b, 112, 1); }, 112,
       "parametric flag is off"},
      {"parametric list past the end",
       [](auto& b) {
         patch<uint32_t>(b, 100, pkg::kVisibleSetsPresent | pkg::kParametricCandidates);
         patch<uint64_t>(b, 112, 1);
       },
       112, "1 parametric candidate ids need more than the 0 bytes"},
      {"cells past the end", [](auto& b) { patch<uint32_t>(b, 28, 100); }, 28,
       "100 cell records need more than the"},
      {"occluder ids past the end", [](auto& b) { patch<uint64_t>(b, 64, uint64_t{1} << 62); }, 64,
       "occluder ids need more than the"},
      {"visible ids past the end", [](auto& b) { patch<uint64_t>(b, 72, ~uint64_t{0}); }, 72,
       "visible ids need more than the"},
      {"trailing bytes", [](auto& b) { b.insert(b.end(), 8, 0); }, good.size(),
       "8 trailing bytes after the last ids"},
      {"occluder id out of range", [&](auto& b) { patch<uint32_t>(b, occluders_at + 8, 200); },
       occluders_at + 8, "occluder id 200 is out of range (200 clusters)"},
      {"visible id out of range", [&](auto& b) { patch<uint32_t>(b, visible_at, 999); }, visible_at,
       "visible id 999 is out of range"},
      // Occluders are cell 0: {0}, cell 1: {7, 20}: the first too large for 10 clusters is 20.
      {"few clusters", [](auto&) {}, occluders_at + 8, "occluder id 20 is out of range (10 clusters)",
       10},
      {"grid index repeats",
       [](auto& b) { patch<uint32_t>(b, cellAt(7), 3 * 6 + 0); },  // cell 6 has grid index 18
       cellAt(7), "cell 7 grid index 18 is not greater than the previous cell's 18"},
      {"grid index outside",
       [](auto& b) { patch<uint32_t>(b, cellAt(39), 120); }, cellAt(39),
       "cell 39 grid index 120 is outside the 120-cell grid"},
      {"occluder range", [](auto& b) { patch<uint32_t>(b, cellAt(2) + 8, 1000); }, cellAt(2) + 4,
       "cell 2 occluders ["},
      {"visible range", [](auto& b) { patch<uint32_t>(b, cellAt(2) + 12, 0xfffffff0u); },
       cellAt(2) + 12, "cell 2 visible ids ["},
      {"coverage", [](auto& b) { patch<float>(b, cellAt(5) + 20, 1.5f); }, cellAt(5) + 20,
       "cell 5 coverage or hit fraction is not in [0, 1]"},
      {"hit fraction nan", [](auto& b) { patch<float>(b, cellAt(5) + 24, std::nanf("")); },
       cellAt(5) + 20, "coverage or hit fraction"},
      {"cell reserved", [](auto& b) { patch<uint32_t>(b, cellAt(9) + 28, 1); }, cellAt(9) + 28,
       "cell 9 reserved field is not zero"},
      {"short header", [](auto& b) { b.resize(100); }, 100, "too small for its 128-byte header"},
  };
  for (const BadCase& c : cases) {
    std::vector<uint8_t> bytes = good;
    c.damage(bytes);
    AlignedBytes a(bytes);
    try {
      parseCopy(a, c.cluster_count);
      ADD_FAILURE() << c.name << ": accepted";
    } catch (const FormatError& e) {
      EXPECT_EQ(e.file(), "vis.bin") << c.name;
      EXPECT_EQ(e.where(), FormatError::Where::Byte) << c.name;
      EXPECT_EQ(e.position(), kSectionOffset + c.offset) << c.name << ": " << e.what();
      EXPECT_NE(e.reason().find(c.reason), std::string::npos) << c.name << ": " << e.what();
      EXPECT_NE(e.reason().find("visibility"), std::string::npos) << c.name << ": " << e.what();
    }
  }
}

TEST(VisibilitySection, ParametricCandidatesOutOfRangeOrOrderAreRejected) {
  VisibilityData p = sampleData();
  p.parametric_occluders = true;
  p.parametric_candidates = {3, 8, 9};
  const std::vector<uint8_t> good = encodeVisibility(p);
  const size_t list_at = good.size() - 12;
  auto rejected = [&](std::vector<uint8_t> bytes, uint64_t clusters, size_t offset,
                      const char* reason) {
    AlignedBytes a(bytes);
    try {
      parseCopy(a, clusters);
      ADD_FAILURE() << reason << ": accepted";
    } catch (const FormatError& e) {
      EXPECT_EQ(e.position(), kSectionOffset + offset) << e.what();
      EXPECT_NE(e.reason().find(reason), std::string::npos) << e.what();
    }
  };
  {
    std::vector<uint8_t> copy = good;
    AlignedBytes ok(copy);
    EXPECT_NO_THROW(parseCopy(ok, 200));
  }
  std::vector<uint8_t> bytes = good;
  std::memcpy(bytes.data() + list_at + 4, "\x02\0\0\0", 4);  // 3, 2, 9
  rejected(bytes, 200, list_at + 4, "parametric candidates are not strictly ascending");
  std::vector<uint8_t> big = good;
  const uint32_t past = 500;
  std::memcpy(big.data() + list_at + 8, &past, 4);
  rejected(big, 200, list_at + 8, "parametric candidate 500 is out of range (200 clusters)");
}

TEST(VisibilitySection, VisibleIdsOutOfOrderAndMisalignmentAreRejected) {
  VisibilityData d = sampleData();
  std::vector<uint8_t> bytes = encodeVisibility(d);
  // The first cell's visible ids are the first visible ids: swap its first two.
  size_t visible_total = 0;
  for (const auto& c : d.cells) visible_total += c.visible.size();
  const size_t first_visible = bytes.size() - 4 * visible_total;
  patch<uint32_t>(bytes, first_visible, d.cells[0].visible[1]);
  patch<uint32_t>(bytes, first_visible + 4, d.cells[0].visible[0]);
  AlignedBytes a(bytes);
  try {
    parseCopy(a);
    ADD_FAILURE() << "accepted";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.position(), kSectionOffset + first_visible + 4);
    EXPECT_NE(e.reason().find("cell 0 visible ids are not strictly ascending"), std::string::npos)
        << e.what();
  }
  // A span that does not start on an 8-byte boundary fails cleanly instead of reading misaligned.
  const std::vector<uint8_t> good = encodeVisibility(d);
  std::vector<uint64_t> storage(good.size() / 8 + 2);
  uint8_t* shifted = reinterpret_cast<uint8_t*>(storage.data()) + 4;
  std::memcpy(shifted, good.data(), good.size());
  try {
    VisibilityView::parse({shifted, good.size()}, "vis.bin", 64, kClusterCount);
    ADD_FAILURE() << "accepted";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.position(), 64u);
    EXPECT_NE(e.reason().find("not 8-byte aligned"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
// In a package.

// Boxes on a floor (several levels after simplification) and a few pipes (parametric clusters),
// preprocessed once per test program without a visibility section.
const fs::path& smallPackage() {
  static const fs::path path = [] {
    const fs::path dir = test::processScratchDir("visibility-section");
    const fs::path scene = dir / "scene.tws";
    TwsWriter writer(scene);
    writer.onLayer(0, {"structure", 0xff336699u});
    uint32_t id = 0;
    for (int gx = 0; gx < 4; ++gx)
      for (int gy = 0; gy < 3; ++gy) {
        SceneObject object;
        object.info.id = id++;
        object.info.name = "block " + std::to_string(id);
        object.info.transform.origin = {gx * 12.0 + 1000.0, gy * 12.0 + 2000.0, 3.0};
        object.geometry = test::subdividedBox(glm::vec3(3.0f, 3.0f, 3.0f), 10);
        writer.onObject(object);
      }
    for (int i = 0; i < 4; ++i) {
      SceneObject pipe;
      pipe.info.id = id++;
      pipe.info.name = "pipe " + std::to_string(i);
      pipe.info.transform.origin = {1000.0 + i * 6.0, 1995.0, 8.0};
      pipe.geometry = Primitive{Cylinder{0.2f, 10.0f, true}};
      writer.onObject(pipe);
    }
    writer.finish();
    PreprocessOptions options;
    options.inputs = {scene};
    options.output = dir / "small.twk";
    options.cluster_size = 128;
    options.visibility = false;
    runPreprocess(options);
    return options.output;
  }();
  return path;
}

// Visibility over the package's bounds, candidates from the front of `level`.
VisibilityData packageVisibility(const PackageView& view, uint32_t level) {
  const DagFront front = dagFront(view, level);
  const auto& h = view.header();
  VisibilityData d;
  d.grid_dims = {4, 3, 2};
  d.grid_min = glm::dvec3(h.bounds_min[0], h.bounds_min[1], h.bounds_min[2]) - 0.5;
  d.cell_size_m = 14.0;
  d.rays_per_cell = 64;
  d.candidate_level = level;
  d.candidate_triangles = front.triangles;
  d.visible_sets = true;
  d.solid_cells = 3;
  for (uint32_t g = 0; g < 24; g += 2) {
    VisibilityCell c;
    c.grid_index = g;
    c.occluders = {front.clusters[g % front.clusters.size()],
                   front.clusters[(g * 5 + 1) % front.clusters.size()]};
    for (size_t k = g % 3; k < front.clusters.size(); k += 2) c.visible.push_back(front.clusters[k]);
    c.occluder_coverage = 0.75f;
    c.hit_fraction = 0.5f;
    d.cells.push_back(c);
  }
  d.rays_cast = uint64_t{d.rays_per_cell} * d.cells.size();
  return d;
}

std::string sectionBytes(const std::string& file, const pkg::SectionEntry& e) {
  return file.substr(e.offset, pkg::storedBytes(e));
}

uint32_t firstParametricCluster(const PackageView& view) {
  for (uint32_t c = 0; c < view.clusters().size(); ++c)
    if (view.clusters()[c].kind == static_cast<uint8_t>(pkg::ClusterKind::Parametric)) return c;
  return pkg::kNone;
}

TEST(PackageRewrite, ReplacesTheVisibilitySectionAndKeepsEveryOtherByte) {
  const fs::path dir = test::scratchDir();
  const fs::path file = dir / "p.twk";
  fs::copy_file(smallPackage(), file);
  const std::string before = test::readFile(file);
  VisibilityData data;
  {
    const PackageView view = PackageView::open(file, PackageView::Verify::All);
    ASSERT_TRUE(view.visibilityCells().empty());
    ASSERT_GE(view.header().level_count, 2u);
    data = packageVisibility(view, 1);
  }
  const std::vector<uint8_t> bytes = encodeVisibility(data);
  replacePackageSection(file, pkg::SectionType::Visibility, bytes);
  EXPECT_FALSE(fs::exists(file.string() + ".tmp"));
  const std::string after = test::readFile(file);

  const PackageView old_view = PackageView::open(smallPackage(), PackageView::Verify::All);
  const PackageView view = PackageView::open(file, PackageView::Verify::All);
  EXPECT_EQ(view.fileBytes(), after.size());
  const auto& vis_entry = view.section(pkg::SectionType::Visibility);
  EXPECT_EQ(vis_entry.bytes, bytes.size());
  EXPECT_EQ(vis_entry.offset % pkg::kSectionAlignment, 0u);
  EXPECT_EQ(sectionBytes(after, vis_entry), std::string(bytes.begin(), bytes.end()));
  for (uint32_t i = 0; i < pkg::kSectionCount; ++i) {
    if (i == static_cast<uint32_t>(pkg::SectionType::Visibility)) continue;
    const auto type = static_cast<pkg::SectionType>(i);
    EXPECT_EQ(sectionBytes(after, view.section(type)), sectionBytes(before, old_view.section(type)))
        << pkg::kSectionNames[i];
    EXPECT_EQ(view.section(type).checksum, old_view.section(type).checksum);
  }
  // Page data stays last; the header changes only in size and checksum.
  EXPECT_EQ(view.section(pkg::SectionType::PageData).offset +
                view.section(pkg::SectionType::PageData).bytes,
            view.fileBytes());
  pkg::PackageHeader a = view.header(), b = old_view.header();
  a.file_bytes = b.file_bytes = 0;
  a.header_checksum = b.header_checksum = 0;
  EXPECT_EQ(std::memcmp(&a, &b, sizeof(a)), 0);

  // What was written is what the view hands out.
  const VisibilityView& cells = view.visibilityCells();
  ASSERT_FALSE(cells.empty());
  EXPECT_EQ(cells.header().candidate_level, 1u);
  ASSERT_EQ(cells.cells().size(), data.cells.size());
  for (const VisibilityCell& want : data.cells) {
    const VisibilityCellRecord* got = cells.cell(want.grid_index);
    ASSERT_NE(got, nullptr);
    auto occ = cells.occluders(*got);
    auto vis = cells.visible(*got);
    EXPECT_EQ(std::vector<uint32_t>(occ.begin(), occ.end()), want.occluders);
    EXPECT_EQ(std::vector<uint32_t>(vis.begin(), vis.end()), want.visible);
  }
  // A cell centre maps to its record through the package frame.
  const glm::dvec3 centre = data.grid_min + data.cell_size_m * glm::dvec3(2.5, 0.5, 0.5);
  ASSERT_NE(cells.cellAt(centre), nullptr);
  EXPECT_EQ(cells.cellAt(centre)->grid_index, 2u);

  // Replacing it with nothing again gives back the original file, byte for byte.
  replacePackageSection(file, pkg::SectionType::Visibility, {});
  EXPECT_EQ(test::readFile(file), before);
}

TEST(PackageRewrite, MovedViewKeepsItsVisibilityCells) {
  const fs::path file = test::scratchDir() / "p.twk";
  fs::copy_file(smallPackage(), file);
  {
    const PackageView view = PackageView::open(file);
    replacePackageSection(file, pkg::SectionType::Visibility,
                          encodeVisibility(packageVisibility(view, 0)));
  }
  PackageView first = PackageView::open(file);
  const auto* record = &first.visibilityCells().cells()[3];
  PackageView second = std::move(first);
  EXPECT_TRUE(first.visibilityCells().empty());
  ASSERT_FALSE(second.visibilityCells().empty());
  EXPECT_EQ(&second.visibilityCells().cells()[3], record);  // the mapping did not move
  EXPECT_EQ(second.visibilityCells().cell(record->grid_index), record);
  PackageView third = PackageView::open(smallPackage());
  third = std::move(second);
  EXPECT_EQ(third.visibilityCells().cells().size(), 12u);
  EXPECT_EQ(third.visibilityCells().occluders(*record).size(), 2u);
}

TEST(PackageRewrite, FailuresLeaveTheOriginalUntouched) {
  const fs::path dir = test::scratchDir();
  const fs::path file = dir / "p.twk";
  fs::copy_file(smallPackage(), file);
  const std::string before = test::readFile(file);
  auto untouched = [&](const char* what) {
    EXPECT_EQ(test::readFile(file), before) << what;
    EXPECT_FALSE(fs::exists(file.string() + ".tmp")) << what;
  };
  const PackageView view = PackageView::open(file);
  const VisibilityData good = packageVisibility(view, 1);

  // Bytes of the wrong record size for a record section.
  const std::vector<uint8_t> five(5, 0);
  EXPECT_THROW(replacePackageSection(file, pkg::SectionType::Clusters, five),
               std::invalid_argument);
  untouched("record size");
  EXPECT_THROW(replacePackageSection(file, static_cast<pkg::SectionType>(12), five),
               std::invalid_argument);
  untouched("section type");

  // A section the view would reject: an id past the clusters, a parametric candidate, a
  // candidate level the DAG does not have.
  auto rejectedWith = [&](const VisibilityData& d, const char* reason) {
    try {
      replacePackageSection(file, pkg::SectionType::Visibility, encodeVisibility(d));
      ADD_FAILURE() << reason << ": accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
    }
    untouched(reason);
  };
  VisibilityData bad = good;
  bad.cells[2].occluders.push_back(uint32_t(view.clusters().size()));
  rejectedWith(bad, "is out of range");
  const uint32_t parametric = firstParametricCluster(view);
  ASSERT_NE(parametric, pkg::kNone) << "the scene's pipes make parametric clusters";
  bad = good;
  bad.cells[4].occluders.push_back(parametric);
  rejectedWith(bad, "is not a mesh cluster");
  bad = good;
  bad.candidate_level = view.header().level_count;
  rejectedWith(bad, "candidate level");
  bad = good;
  bad.parametric_occluders = true;
  bad.parametric_candidates = {good.cells[0].occluders[0]};  // a mesh cluster
  rejectedWith(bad, "is not a parametric cluster");
  // With parametric candidates declared, the parametric occluder is accepted.
  VisibilityData parametric_ok = good;
  parametric_ok.parametric_occluders = true;
  parametric_ok.parametric_candidates = {parametric};
  parametric_ok.cells[4].occluders.push_back(parametric);
  replacePackageSection(file, pkg::SectionType::Visibility, encodeVisibility(parametric_ok));
  {
    const PackageView patched = PackageView::open(file, PackageView::Verify::All);
    const VisibilityView& v = patched.visibilityCells();
    EXPECT_NE(v.header().flags & pkg::kParametricCandidates, 0u);
    EXPECT_EQ(v.occluders(v.cells()[4]).back(), parametric);
  }
  test::writeFile(file, before);

  // No place to write the temporary file (root ignores permissions, so block the name instead).
  fs::create_directory(file.string() + ".tmp");
  EXPECT_THROW(replacePackageSection(file, pkg::SectionType::Visibility, encodeVisibility(good)),
               std::runtime_error);
  EXPECT_EQ(test::readFile(file), before);
  EXPECT_TRUE(fs::is_directory(file.string() + ".tmp"));
  fs::remove(file.string() + ".tmp");

  // A damaged package is refused before anything is written.
  const fs::path damaged = dir / "damaged.twk";
  std::string bytes = before;
  bytes[view.section(pkg::SectionType::Groups).offset + 3] ^= 0x40;
  test::writeFile(damaged, bytes);
  EXPECT_THROW(replacePackageSection(damaged, pkg::SectionType::Visibility, {}), FormatError);
  EXPECT_EQ(test::readFile(damaged), bytes);
  EXPECT_THROW(replacePackageSection(dir / "absent.twk", pkg::SectionType::Visibility, {}),
               FormatError);
}

// PackageView's own check of the section, on a file patched behind the writer's back (section and
// header checksums recomputed so only the visibility rules can catch it).
TEST(PackageRewrite, ViewRejectsAPatchedVisibilitySectionAtItsOffset) {
  const fs::path file = test::scratchDir() / "p.twk";
  fs::copy_file(smallPackage(), file);
  uint32_t parametric;
  {
    const PackageView view = PackageView::open(file);
    parametric = firstParametricCluster(view);
    replacePackageSection(file, pkg::SectionType::Visibility,
                          encodeVisibility(packageVisibility(view, 1)));
  }
  std::string bytes = test::readFile(file);
  pkg::PackageHeader h;
  std::memcpy(&h, bytes.data(), sizeof(h));
  std::vector<pkg::SectionEntry> table(h.section_count);
  std::memcpy(table.data(), bytes.data() + sizeof(h), table.size() * sizeof(pkg::SectionEntry));
  pkg::SectionEntry& e = table[static_cast<uint32_t>(pkg::SectionType::Visibility)];
  const uint64_t first_occluder =
      e.offset + sizeof(VisibilityHeader) + 12 * sizeof(VisibilityCellRecord);
  auto reseal = [&](std::string& b) {
    e.checksum = packageSectionChecksum(
        {reinterpret_cast<const uint8_t*>(b.data()) + e.offset, static_cast<size_t>(pkg::storedBytes(e))});
    std::memcpy(b.data() + sizeof(h), table.data(), table.size() * sizeof(pkg::SectionEntry));
    h.header_checksum = packageHeaderChecksum(h, table);
    std::memcpy(b.data(), &h, sizeof(h));
    test::writeFile(file, b);
  };
  std::string patched = bytes;
  std::memcpy(patched.data() + first_occluder, &parametric, 4);
  reseal(patched);
  try {
    PackageView::open(file);
    ADD_FAILURE() << "accepted";
  } catch (const FormatError& e2) {
    EXPECT_EQ(e2.position(), first_occluder);
    EXPECT_NE(e2.reason().find("is not a mesh cluster"), std::string::npos) << e2.what();
  }
  patched = bytes;
  patched[e.offset + 100] = 8;  // unknown flag
  reseal(patched);
  try {
    PackageView::open(file);
    ADD_FAILURE() << "accepted";
  } catch (const FormatError& e2) {
    EXPECT_EQ(e2.position(), e.offset + 100);
    EXPECT_NE(e2.reason().find("unknown flags"), std::string::npos) << e2.what();
  }
}

// Random damage inside the visibility section of a package, with the checksums resealed so that
// only the section's own rules stand between the bytes and the runtime: every open either succeeds
// with a view whose ids are all candidates (mesh clusters, or parametric ones when the flag says
// so) or throws a FormatError naming the file.
TEST(PackageRewrite, ResealedDamageInTheSectionIsRejectedCleanly) {
  const fs::path file = test::scratchDir() / "damaged-visibility.twk";
  fs::copy_file(smallPackage(), file);
  {
    const PackageView view = PackageView::open(file);
    replacePackageSection(file, pkg::SectionType::Visibility,
                          encodeVisibility(packageVisibility(view, 1)));
  }
  const std::string bytes = test::readFile(file);
  pkg::PackageHeader h;
  std::memcpy(&h, bytes.data(), sizeof(h));
  std::vector<pkg::SectionEntry> table(h.section_count);
  std::memcpy(table.data(), bytes.data() + sizeof(h), table.size() * sizeof(pkg::SectionEntry));
  pkg::SectionEntry& e = table[static_cast<uint32_t>(pkg::SectionType::Visibility)];
  std::mt19937 rng(99);
  int rejected = 0;
  for (int i = 0; i < 300; ++i) {
    std::string b = bytes;
    for (uint32_t hits = 1 + rng() % 4; hits > 0; --hits)
      b[e.offset + rng() % e.bytes] = static_cast<char>(rng() & 0xff);
    e.checksum = packageSectionChecksum(
        {reinterpret_cast<const uint8_t*>(b.data()) + e.offset, static_cast<size_t>(pkg::storedBytes(e))});
    std::memcpy(b.data() + sizeof(h), table.data(), table.size() * sizeof(pkg::SectionEntry));
    h.header_checksum = packageHeaderChecksum(h, table);
    std::memcpy(b.data(), &h, sizeof(h));
    test::writeFile(file, b);
    try {
      const PackageView view = PackageView::open(file);
      const VisibilityView& v = view.visibilityCells();
      const bool parametric =
          !v.empty() && (v.header().flags & pkg::kParametricCandidates) != 0;
      auto candidateKind = [&](uint32_t id) {
        const uint8_t kind = view.clusters()[id].kind;
        return kind == uint8_t(pkg::ClusterKind::Mesh) ||
               (parametric && kind == uint8_t(pkg::ClusterKind::Parametric));
      };
      for (const VisibilityCellRecord& c : v.cells()) {
        for (uint32_t id : v.occluders(c)) ASSERT_TRUE(candidateKind(id)) << id;
        for (uint32_t id : v.visible(c)) ASSERT_TRUE(candidateKind(id)) << id;
      }
    } catch (const FormatError& error) {
      ++rejected;
      EXPECT_NE(std::string(error.what()).find("damaged-visibility.twk"), std::string::npos);
      EXPECT_GE(error.position(), e.offset) << error.what();
      EXPECT_LT(error.position(), e.offset + e.bytes) << error.what();
    }
  }
  EXPECT_GT(rejected, 100);
}

TEST(PackageInfo, ReportsTheVisibilitySection) {
  const fs::path file = test::scratchDir() / "p.twk";
  fs::copy_file(smallPackage(), file);
  {
    const PackageSummary s = summarizePackage(PackageView::open(file));
    EXPECT_FALSE(s.visibility.present);
    EXPECT_EQ(s.visibility.bytes, 0u);
  }
  VisibilityData data;
  {
    const PackageView view = PackageView::open(file);
    data = packageVisibility(view, 1);
  }
  const std::vector<uint8_t> bytes = encodeVisibility(data);
  replacePackageSection(file, pkg::SectionType::Visibility, bytes);
  uint64_t occluders = 0, visible = 0;
  for (const VisibilityCell& c : data.cells) {
    occluders += c.occluders.size();
    visible += c.visible.size();
  }
  const PackageSummary s = summarizePackage(PackageView::open(file));
  const PackageSummary::Visibility& v = s.visibility;
  EXPECT_TRUE(v.present);
  EXPECT_EQ(v.bytes, bytes.size());
  EXPECT_EQ(v.cells, 12u);
  EXPECT_EQ(v.solid_cells, 3u);
  EXPECT_EQ(v.grid_dims, glm::uvec3(4, 3, 2));
  EXPECT_EQ(v.cell_size_m, 14.0);
  EXPECT_EQ(v.rays_cast, 64u * 12u);
  EXPECT_EQ(v.rays_per_cell, 64u);
  EXPECT_EQ(v.candidate_level, 1u);
  EXPECT_EQ(v.candidate_triangles, data.candidate_triangles);
  EXPECT_TRUE(v.visible_sets);
  EXPECT_DOUBLE_EQ(v.average_occluders, double(occluders) / 12.0);
  EXPECT_DOUBLE_EQ(v.average_visible, double(visible) / 12.0);
  EXPECT_NEAR(v.average_coverage, 0.75, 1e-6);
  EXPECT_EQ(s.section_bytes[static_cast<uint32_t>(pkg::SectionType::Visibility)], bytes.size());

  if (!fs::exists(TW_TERAWALK_EXE)) GTEST_SKIP() << "terawalk is not built: " << TW_TERAWALK_EXE;
  const test::CommandResult json = test::runTerawalk("info --json " + file.string());
  ASSERT_EQ(json.exit_code, 0) << json.output;
  const nlohmann::json j = nlohmann::json::parse(json.output);
  const nlohmann::json& jv = j.at("visibility");
  EXPECT_EQ(jv.at("present"), true);
  EXPECT_EQ(jv.at("cells"), 12);
  EXPECT_EQ(jv.at("solid_cells"), 3);
  EXPECT_EQ(jv.at("grid_dims"), nlohmann::json({4, 3, 2}));
  EXPECT_EQ(jv.at("cell_size_m"), 14.0);
  EXPECT_EQ(jv.at("rays_cast"), 768);
  EXPECT_EQ(jv.at("rays_per_cell"), 64);
  EXPECT_EQ(jv.at("candidate_level"), 1);
  EXPECT_EQ(jv.at("candidate_triangles"), data.candidate_triangles);
  EXPECT_DOUBLE_EQ(jv.at("average_occluders").get<double>(), double(occluders) / 12.0);
  EXPECT_DOUBLE_EQ(jv.at("average_visible").get<double>(), double(visible) / 12.0);
  EXPECT_EQ(jv.at("bytes"), bytes.size());
  EXPECT_EQ(j.at("section_bytes").at("visibility"), bytes.size());
  const test::CommandResult text = test::runTerawalk("info " + file.string());
  ASSERT_EQ(text.exit_code, 0) << text.output;
  EXPECT_NE(text.output.find("visibility  12 cells (3 solid) in a 4 x 3 x 2 grid of 14 m cells"),
            std::string::npos)
      << text.output;
  EXPECT_NE(text.output.find("rays 768 (64 per cell)"), std::string::npos) << text.output;

  const test::CommandResult none = test::runTerawalk("info " + smallPackage().string());
  EXPECT_NE(none.output.find("visibility  none"), std::string::npos) << none.output;
  const nlohmann::json jn = nlohmann::json::parse(
      test::runTerawalk("info --json " + smallPackage().string()).output);
  EXPECT_EQ(jn.at("visibility").at("present"), false);
  EXPECT_EQ(jn.at("visibility").at("cells"), 0);
}

}  // namespace
}  // namespace tw
