// The visibility section: encoding from owning VisibilityData, and a zero-copy validating view.
//
// parse() checks identity and sizes first, then every count against the bytes that remain (in
// 64-bit arithmetic, before anything is indexed), then each cell record and every id. After it
// succeeds every span and every index a record holds is safe to use. See visibility_section.h.
#include "visibility_section.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "format_error.h"

namespace tw {
namespace {

using pkg::VisibilityCellRecord;
using pkg::VisibilityHeader;

constexpr uint32_t kAllFlags = pkg::kVisibleSetsPresent | pkg::kParametricCandidates;
// Grid indices are uint32 and UINT32_MAX means "outside", so a grid has fewer cells than that.
constexpr uint64_t kMaxGridCells = std::numeric_limits<uint32_t>::max();

std::string str(uint64_t v) { return std::to_string(v); }

uint64_t gridCells(const uint32_t dims[3]) {
  return uint64_t{dims[0]} * uint64_t{dims[1]} * uint64_t{dims[2]};  // each < 2^32: no overflow
}

bool isFraction(float v) { return std::isfinite(v) && v >= 0.0f && v <= 1.0f; }

}  // namespace

std::vector<uint8_t> encodeVisibility(const VisibilityData& data) {
  auto bad = [](const std::string& why) { throw std::invalid_argument("encodeVisibility: " + why); };
  const uint32_t dims[3] = {data.grid_dims.x, data.grid_dims.y, data.grid_dims.z};
  if (dims[0] == 0 || dims[1] == 0 || dims[2] == 0) bad("a grid dimension is zero");
  const uint64_t grid_cells = gridCells(dims);
  if (grid_cells > kMaxGridCells) bad("the grid has 2^32 - 1 cells or more");
  if (!(std::isfinite(data.cell_size_m) && data.cell_size_m > 0.0))
    bad("cell size must be finite and positive");
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(data.grid_min[a]) ||
        !std::isfinite(data.grid_min[a] + data.cell_size_m * double(dims[a])))
      bad("grid bounds are not finite");
  if (data.cells.size() > grid_cells) bad("more cells than the grid holds");
  if (uint64_t{data.solid_cells} + data.cells.size() > grid_cells)
    bad("stored cells plus solid cells exceed the grid");

  uint64_t occluder_ids = 0, visible_ids = 0;
  for (size_t i = 0; i < data.cells.size(); ++i) {
    const VisibilityCell& c = data.cells[i];
    if (c.grid_index >= grid_cells) bad("cell " + str(i) + " lies outside the grid");
    if (i > 0 && c.grid_index <= data.cells[i - 1].grid_index)
      bad("cell grid indices are not strictly increasing at cell " + str(i));
    if (!data.visible_sets && !c.visible.empty())
      bad("cell " + str(i) + " has visible ids but visible_sets is off");
    for (size_t k = 1; k < c.visible.size(); ++k)
      if (c.visible[k] <= c.visible[k - 1])
        bad("cell " + str(i) + " visible ids are not strictly ascending");
    if (!isFraction(c.occluder_coverage) || !isFraction(c.hit_fraction))
      bad("cell " + str(i) + " coverage or hit fraction is not in [0, 1]");
    occluder_ids += c.occluders.size();
    visible_ids += c.visible.size();
  }
  if (!data.parametric_occluders && !data.parametric_candidates.empty())
    bad("parametric candidates listed but parametric_occluders is off");
  for (size_t k = 1; k < data.parametric_candidates.size(); ++k)
    if (data.parametric_candidates[k] <= data.parametric_candidates[k - 1])
      bad("parametric candidates are not strictly ascending");
  // first_occluder / first_visible are uint32.
  if (occluder_ids > std::numeric_limits<uint32_t>::max() ||
      visible_ids > std::numeric_limits<uint32_t>::max())
    bad("more than 2^32 - 1 occluder or visible ids");

  VisibilityHeader h{};
  std::memcpy(h.magic, pkg::kVisibilityMagic, sizeof(h.magic));
  h.header_bytes = sizeof(VisibilityHeader);
  h.cell_record_bytes = sizeof(VisibilityCellRecord);
  for (int a = 0; a < 3; ++a) {
    h.grid_dims[a] = dims[a];
    h.grid_min[a] = data.grid_min[a];
  }
  h.cell_count = static_cast<uint32_t>(data.cells.size());
  h.cell_size_m = data.cell_size_m;
  h.occluder_id_count = occluder_ids;
  h.visible_id_count = visible_ids;
  h.rays_cast = data.rays_cast;
  h.rays_per_cell = data.rays_per_cell;
  h.candidate_level = data.candidate_level;
  h.solid_cells = data.solid_cells;
  h.flags = (data.visible_sets ? pkg::kVisibleSetsPresent : 0u) |
            (data.parametric_occluders ? pkg::kParametricCandidates : 0u);
  h.candidate_triangles = data.candidate_triangles;
  h.parametric_candidate_count = data.parametric_candidates.size();

  const size_t total =
      sizeof(VisibilityHeader) + data.cells.size() * sizeof(VisibilityCellRecord) +
      (occluder_ids + visible_ids + data.parametric_candidates.size()) * sizeof(uint32_t);
  std::vector<uint8_t> out(total);
  std::memcpy(out.data(), &h, sizeof(h));
  uint8_t* record_at = out.data() + sizeof(VisibilityHeader);
  uint8_t* occluder_at = record_at + data.cells.size() * sizeof(VisibilityCellRecord);
  uint8_t* visible_at = occluder_at + occluder_ids * sizeof(uint32_t);
  uint32_t next_occluder = 0, next_visible = 0;
  for (const VisibilityCell& c : data.cells) {
    VisibilityCellRecord r{};
    r.grid_index = c.grid_index;
    r.first_occluder = c.occluders.empty() ? 0 : next_occluder;
    r.occluder_count = static_cast<uint32_t>(c.occluders.size());
    r.first_visible = c.visible.empty() ? 0 : next_visible;
    r.visible_count = static_cast<uint32_t>(c.visible.size());
    r.occluder_coverage = c.occluder_coverage;
    r.hit_fraction = c.hit_fraction;
    std::memcpy(record_at, &r, sizeof(r));
    record_at += sizeof(r);
    if (!c.occluders.empty())
      std::memcpy(occluder_at + uint64_t{next_occluder} * sizeof(uint32_t), c.occluders.data(),
                  c.occluders.size() * sizeof(uint32_t));
    if (!c.visible.empty())
      std::memcpy(visible_at + uint64_t{next_visible} * sizeof(uint32_t), c.visible.data(),
                  c.visible.size() * sizeof(uint32_t));
    next_occluder += r.occluder_count;
    next_visible += r.visible_count;
  }
  if (!data.parametric_candidates.empty())
    std::memcpy(visible_at + visible_ids * sizeof(uint32_t), data.parametric_candidates.data(),
                data.parametric_candidates.size() * sizeof(uint32_t));
  return out;
}

VisibilityView VisibilityView::parse(std::span<const uint8_t> bytes, const std::string& file_name,
                                     uint64_t section_offset, uint64_t cluster_count) {
  VisibilityView view;
  if (bytes.empty()) return view;
  auto fail = [&](uint64_t offset, const std::string& reason) {
    throw FormatError::atByte(file_name, section_offset + offset, "visibility: " + reason);
  };
  if (reinterpret_cast<uintptr_t>(bytes.data()) % alignof(VisibilityHeader) != 0)
    fail(0, "section is not 8-byte aligned in memory");
  const uint64_t size = bytes.size();
  if (size < sizeof(VisibilityHeader))
    fail(size, "section of " + str(size) + " bytes is too small for its " +
                   str(sizeof(VisibilityHeader)) + "-byte header");
  const auto& h = *reinterpret_cast<const VisibilityHeader*>(bytes.data());
  auto at = [&](const void* field) {
    return static_cast<uint64_t>(static_cast<const uint8_t*>(field) - bytes.data());
  };

  // Identity and sizes.
  if (std::memcmp(h.magic, pkg::kVisibilityMagic, sizeof(h.magic)) != 0)
    fail(0, "bad magic (not a TWVIS001 section)");
  if (h.header_bytes != sizeof(VisibilityHeader))
    fail(at(&h.header_bytes),
         "header size " + str(h.header_bytes) + " != " + str(sizeof(VisibilityHeader)));
  if (h.cell_record_bytes != sizeof(VisibilityCellRecord))
    fail(at(&h.cell_record_bytes), "cell record size " + str(h.cell_record_bytes) +
                                       " != " + str(sizeof(VisibilityCellRecord)));
  if (h.flags & ~kAllFlags) fail(at(&h.flags), "unknown flags " + str(h.flags & ~kAllFlags));
  if (h.reserved != 0) fail(at(&h.reserved), "reserved header field is not zero");

  // Grid.
  if (h.grid_dims[0] == 0 || h.grid_dims[1] == 0 || h.grid_dims[2] == 0)
    fail(at(&h.grid_dims), "grid dimension is zero");
  const uint64_t grid_cells = gridCells(h.grid_dims);
  if (grid_cells > kMaxGridCells)
    fail(at(&h.grid_dims), "grid of " + str(grid_cells) + " cells is too large for 32-bit indices");
  if (!(std::isfinite(h.cell_size_m) && h.cell_size_m > 0.0))
    fail(at(&h.cell_size_m), "cell size is not finite and positive");
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(h.grid_min[a]) ||
        !std::isfinite(h.grid_min[a] + h.cell_size_m * double(h.grid_dims[a])))
      fail(at(&h.grid_min), "grid bounds are not finite");
  if (h.cell_count > grid_cells)
    fail(at(&h.cell_count), "cell count " + str(h.cell_count) + " exceeds the grid's " +
                                str(grid_cells) + " cells");
  if (uint64_t{h.solid_cells} + h.cell_count > grid_cells)
    fail(at(&h.solid_cells), "solid cells " + str(h.solid_cells) + " plus stored cells " +
                                 str(h.cell_count) + " exceed the grid's " + str(grid_cells));
  const bool has_visible = (h.flags & pkg::kVisibleSetsPresent) != 0;
  if (!has_visible && h.visible_id_count != 0)
    fail(at(&h.visible_id_count), "visible ids present but the visible-sets flag is off");
  const bool has_parametric = (h.flags & pkg::kParametricCandidates) != 0;
  if (!has_parametric && h.parametric_candidate_count != 0)
    fail(at(&h.parametric_candidate_count),
         "parametric candidates listed but the parametric flag is off");

  // Counts against the bytes that hold them, each before the next is used.
  uint64_t remaining = size - sizeof(VisibilityHeader);
  if (h.cell_count > remaining / sizeof(VisibilityCellRecord))
    fail(at(&h.cell_count), str(h.cell_count) + " cell records need more than the " +
                                str(remaining) + " bytes after the header");
  remaining -= uint64_t{h.cell_count} * sizeof(VisibilityCellRecord);
  if (h.occluder_id_count > remaining / sizeof(uint32_t))
    fail(at(&h.occluder_id_count), str(h.occluder_id_count) + " occluder ids need more than the " +
                                       str(remaining) + " bytes after the cell records");
  remaining -= h.occluder_id_count * sizeof(uint32_t);
  if (h.visible_id_count > remaining / sizeof(uint32_t))
    fail(at(&h.visible_id_count), str(h.visible_id_count) + " visible ids need more than the " +
                                      str(remaining) + " bytes after the occluder ids");
  remaining -= h.visible_id_count * sizeof(uint32_t);
  if (h.parametric_candidate_count > remaining / sizeof(uint32_t))
    fail(at(&h.parametric_candidate_count),
         str(h.parametric_candidate_count) + " parametric candidate ids need more than the " +
             str(remaining) + " bytes after the visible ids");
  remaining -= h.parametric_candidate_count * sizeof(uint32_t);
  if (remaining != 0)
    fail(size - remaining, str(remaining) + " trailing bytes after the last ids");

  const uint8_t* cells_at = bytes.data() + sizeof(VisibilityHeader);
  const uint8_t* occluders_at = cells_at + uint64_t{h.cell_count} * sizeof(VisibilityCellRecord);
  const uint8_t* visible_at = occluders_at + h.occluder_id_count * sizeof(uint32_t);
  std::span<const VisibilityCellRecord> cells(
      reinterpret_cast<const VisibilityCellRecord*>(cells_at), h.cell_count);
  std::span<const uint32_t> occluder_ids(reinterpret_cast<const uint32_t*>(occluders_at),
                                         h.occluder_id_count);
  std::span<const uint32_t> visible_ids(reinterpret_cast<const uint32_t*>(visible_at),
                                        h.visible_id_count);
  std::span<const uint32_t> parametric_ids(
      reinterpret_cast<const uint32_t*>(visible_at + h.visible_id_count * sizeof(uint32_t)),
      h.parametric_candidate_count);

  // Ids first (one pass each), so the per-cell checks below only look at ranges and order.
  for (const uint32_t& id : occluder_ids)
    if (id >= cluster_count)
      fail(at(&id), "occluder id " + str(id) + " is out of range (" + str(cluster_count) +
                        " clusters)");
  for (const uint32_t& id : visible_ids)
    if (id >= cluster_count)
      fail(at(&id), "visible id " + str(id) + " is out of range (" + str(cluster_count) +
                        " clusters)");
  for (size_t k = 0; k < parametric_ids.size(); ++k) {
    if (parametric_ids[k] >= cluster_count)
      fail(at(&parametric_ids[k]), "parametric candidate " + str(parametric_ids[k]) +
                                       " is out of range (" + str(cluster_count) + " clusters)");
    if (k > 0 && parametric_ids[k] <= parametric_ids[k - 1])
      fail(at(&parametric_ids[k]), "parametric candidates are not strictly ascending");
  }

  for (size_t i = 0; i < cells.size(); ++i) {
    const VisibilityCellRecord& c = cells[i];
    const std::string what = "cell " + str(i);
    if (c.grid_index >= grid_cells)
      fail(at(&c.grid_index), what + " grid index " + str(c.grid_index) + " is outside the " +
                                  str(grid_cells) + "-cell grid");
    if (i > 0 && c.grid_index <= cells[i - 1].grid_index)
      fail(at(&c.grid_index), what + " grid index " + str(c.grid_index) +
                                  " is not greater than the previous cell's " +
                                  str(cells[i - 1].grid_index));
    if (uint64_t{c.first_occluder} + c.occluder_count > occluder_ids.size())
      fail(at(&c.first_occluder), what + " occluders [" + str(c.first_occluder) + ", +" +
                                      str(c.occluder_count) + ") are not inside the " +
                                      str(occluder_ids.size()) + " occluder ids");
    if (!has_visible && (c.first_visible != 0 || c.visible_count != 0))
      fail(at(&c.first_visible), what + " has a visible set but the visible-sets flag is off");
    if (uint64_t{c.first_visible} + c.visible_count > visible_ids.size())
      fail(at(&c.first_visible), what + " visible ids [" + str(c.first_visible) + ", +" +
                                     str(c.visible_count) + ") are not inside the " +
                                     str(visible_ids.size()) + " visible ids");
    const auto visible = visible_ids.subspan(c.first_visible, c.visible_count);
    for (size_t k = 1; k < visible.size(); ++k)
      if (visible[k] <= visible[k - 1])
        fail(at(&visible[k]), what + " visible ids are not strictly ascending");
    if (!isFraction(c.occluder_coverage) || !isFraction(c.hit_fraction))
      fail(at(&c.occluder_coverage), what + " coverage or hit fraction is not in [0, 1]");
    if (c.reserved != 0) fail(at(&c.reserved), what + " reserved field is not zero");
  }

  view.header_ = &h;
  view.cells_ = cells;
  view.occluder_ids_ = occluder_ids;
  view.visible_ids_ = visible_ids;
  view.parametric_candidate_ids_ = parametric_ids;
  return view;
}

uint32_t VisibilityView::gridIndexAt(const glm::dvec3& p) const {
  constexpr uint32_t kOutside = std::numeric_limits<uint32_t>::max();
  if (empty()) return kOutside;
  const pkg::VisibilityHeader& h = *header_;
  uint64_t cell[3];
  for (int a = 0; a < 3; ++a) {
    const double t = std::floor((p[a] - h.grid_min[a]) / h.cell_size_m);
    // Written so that NaN fails too.
    if (!(t >= 0.0 && t < double(h.grid_dims[a]))) return kOutside;
    cell[a] = static_cast<uint64_t>(t);
  }
  return static_cast<uint32_t>(cell[0] + h.grid_dims[0] * (cell[1] + h.grid_dims[1] * cell[2]));
}

const pkg::VisibilityCellRecord* VisibilityView::cell(uint32_t grid_index) const {
  auto it = std::lower_bound(
      cells_.begin(), cells_.end(), grid_index,
      [](const pkg::VisibilityCellRecord& c, uint32_t index) { return c.grid_index < index; });
  if (it == cells_.end() || it->grid_index != grid_index) return nullptr;
  return &*it;
}

std::span<const uint32_t> VisibilityView::occluders(const pkg::VisibilityCellRecord& c) const {
  // Validated at parse for this view's records; the check keeps a foreign record harmless.
  if (uint64_t{c.first_occluder} + c.occluder_count > occluder_ids_.size()) return {};
  return occluder_ids_.subspan(c.first_occluder, c.occluder_count);
}

std::span<const uint32_t> VisibilityView::visible(const pkg::VisibilityCellRecord& c) const {
  if (uint64_t{c.first_visible} + c.visible_count > visible_ids_.size()) return {};
  return visible_ids_.subspan(c.first_visible, c.visible_count);
}

double VisibilityView::averageOccluders() const {
  if (cells_.empty()) return 0.0;
  uint64_t total = 0;
  for (const pkg::VisibilityCellRecord& c : cells_) total += c.occluder_count;
  return double(total) / double(cells_.size());
}

}  // namespace tw
