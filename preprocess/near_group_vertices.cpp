// Near-coincident vertices of different groups, by a hashed grid of tolerance-sized cells (see
// near_group_vertices.h).
#include "near_group_vertices.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "grid_weld.h"
#include "package_format.h"
#include "page_codec.h"

namespace tw {

float packageGridTolerance(const glm::vec3& extent, double position_step_m) {
  const glm::vec3 corners[2] = {glm::vec3(0.0f), extent};
  const uint32_t shift = std::min<uint32_t>(clusterPositionShift(corners, position_step_m),
                                            pkg::kMaxPositionShift);
  return float(2.0 * quantizationErrorM(position_step_m, shift));
}

void markVerticesNearOtherGroups(std::span<const glm::vec3> positions,
                                 std::span<const uint32_t> vertices,
                                 std::span<const uint32_t> owner, uint32_t multi,
                                 float tolerance, std::vector<uint8_t>& near) {
  if (!(tolerance > 0.0f)) return;
  struct Entry {
    int64_t x, y, z;
    uint32_t vertex;
    auto operator<=>(const Entry&) const = default;
  };
  std::vector<Entry> entries;
  entries.reserve(vertices.size());
  const double inv = 1.0 / double(tolerance);
  for (uint32_t v : vertices) {
    const glm::vec3& p = positions[v];
    if (!std::isfinite(p.x + p.y + p.z)) continue;
    entries.push_back({int64_t(std::floor(p.x * inv)), int64_t(std::floor(p.y * inv)),
                       int64_t(std::floor(p.z * inv)), v});
  }
  std::sort(entries.begin(), entries.end());
  // Each cell's first entry through a flat open-addressing table.
  size_t table_size = 16;
  while (table_size < 2 * entries.size()) table_size *= 2;
  constexpr uint32_t kEmpty = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> first(table_size, kEmpty);
  auto hash = [](int64_t x, int64_t y, int64_t z) {
    return size_t(uint64_t(x) * 0x9E3779B97F4A7C15ull ^ uint64_t(y) * 0xC2B2AE3D27D4EB4Full ^
                  uint64_t(z) * 0x165667B19E3779F9ull);
  };
  auto sameCell = [](const Entry& e, int64_t x, int64_t y, int64_t z) {
    return e.x == x && e.y == y && e.z == z;
  };
  auto slotOf = [&](int64_t x, int64_t y, int64_t z) {
    size_t i = hash(x, y, z) & (table_size - 1);
    while (first[i] != kEmpty && !sameCell(entries[first[i]], x, y, z)) i = (i + 1) & (table_size - 1);
    return i;
  };
  for (size_t i = 0; i < entries.size(); ++i)
    if (i == 0 || !sameCell(entries[i - 1], entries[i].x, entries[i].y, entries[i].z))
      first[slotOf(entries[i].x, entries[i].y, entries[i].z)] = uint32_t(i);
  for (const Entry& e : entries) {
    if (owner[e.vertex] == multi) continue;  // shared already: held anyway
    const glm::vec3& p = positions[e.vertex];
    bool found = false;
    for (int64_t z = e.z - 1; z <= e.z + 1 && !found; ++z)
      for (int64_t y = e.y - 1; y <= e.y + 1 && !found; ++y)
        for (int64_t x = e.x - 1; x <= e.x + 1 && !found; ++x) {
          const uint32_t start = first[slotOf(x, y, z)];
          if (start == kEmpty) continue;
          for (size_t i = start; i < entries.size() && sameCell(entries[i], x, y, z); ++i) {
            const uint32_t w = entries[i].vertex;
            if (owner[w] == owner[e.vertex]) continue;
            const glm::vec3 d = glm::abs(positions[w] - p);
            if (std::max({d.x, d.y, d.z}) <= tolerance) {
              found = true;
              break;
            }
          }
        }
    if (found) near[e.vertex] = 1;
  }
}

}  // namespace tw
