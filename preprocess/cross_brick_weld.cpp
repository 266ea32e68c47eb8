// Cross-brick weld of near-coincident rim vertices; see cross_brick_weld.h.
#include "cross_brick_weld.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <tuple>

namespace tw {

namespace {

bool finite(const glm::vec3& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

bool positionLess(const glm::vec3& a, const glm::vec3& b) {
  return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
}

// A distinct position and the bricks holding it (a range of the sorted candidates).
struct Entry {
  glm::vec3 position;
  uint32_t first, count;
};

}  // namespace

CrossBrickWeld CrossBrickWeld::build(std::vector<Candidate> candidates, float tolerance) {
  CrossBrickWeld weld;
  if (!(tolerance > 0.0f)) return weld;
  std::erase_if(candidates, [](const Candidate& c) { return !finite(c.position); });
  for (Candidate& c : candidates) c.position += 0.0f;  // -0 and +0 are one position
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    if (a.position != b.position) return positionLess(a.position, b.position);
    return a.brick < b.brick;
  });
  candidates.erase(std::unique(candidates.begin(), candidates.end(),
                               [](const Candidate& a, const Candidate& b) {
                                 return a.position == b.position && a.brick == b.brick;
                               }),
                   candidates.end());
  std::vector<Entry> entries;
  for (uint32_t i = 0; i < candidates.size(); ++i) {
    if (entries.empty() || entries.back().position != candidates[i].position)
      entries.push_back({candidates[i].position, i, 0});
    ++entries.back().count;
  }

  // Targets (positions that did not move) by grid cell of the tolerance: a target within it on
  // every axis lies in one of the 27 cells around a position's own.
  const double cell = tolerance;
  auto cellOf = [&](const glm::vec3& p) {
    return GridCellKey{int64_t(std::floor(double(p.x) / cell)),
                       int64_t(std::floor(double(p.y) / cell)),
                       int64_t(std::floor(double(p.z) / cell))};
  };
  std::unordered_map<GridCellKey, std::vector<uint32_t>, GridCellHash> targets;
  auto onlyOneSameBrick = [&](const Entry& a, const Entry& b) {
    return a.count == 1 && b.count == 1 &&
           candidates[a.first].brick == candidates[b.first].brick;
  };
  std::vector<uint32_t> bricks;
  for (uint32_t e = 0; e < entries.size(); ++e) {
    const Entry& entry = entries[e];
    const GridCellKey c = cellOf(entry.position);
    uint32_t best = std::numeric_limits<uint32_t>::max();
    for (int64_t dz = -1; dz <= 1; ++dz)
      for (int64_t dy = -1; dy <= 1; ++dy)
        for (int64_t dx = -1; dx <= 1; ++dx) {
          auto it = targets.find({c.x + dx, c.y + dy, c.z + dz});
          if (it == targets.end()) continue;
          for (uint32_t t : it->second) {
            const glm::vec3 d = glm::abs(entries[t].position - entry.position);
            // Two copies in one brick alone are the grid weld's to join.
            const bool near = std::max({d.x, d.y, d.z}) <= tolerance;
            if (near && t < best && !onlyOneSameBrick(entry, entries[t])) best = t;
          }
        }
    if (best == std::numeric_limits<uint32_t>::max()) {
      targets[c].push_back(e);
      continue;
    }
    weld.moved_.emplace(positionKeyOf(entry.position), entries[best].position);
    for (uint32_t i = entry.first; i < entry.first + entry.count; ++i)
      bricks.push_back(candidates[i].brick);
  }
  std::sort(bricks.begin(), bricks.end());
  bricks.erase(std::unique(bricks.begin(), bricks.end()), bricks.end());
  weld.bricks_ = std::move(bricks);
  return weld;
}

void CrossBrickWeld::apply(std::span<glm::vec3> positions) const {
  if (moved_.empty()) return;
  for (glm::vec3& p : positions) {
    auto it = moved_.find(positionKeyOf(p));
    if (it != moved_.end()) p = it->second;
  }
}

namespace {
struct StoredMove {
  glm::vec3 from, to;
};
}  // namespace

void CrossBrickWeld::write(ByteWriter& out) const {
  std::vector<StoredMove> moves;
  moves.reserve(moved_.size());
  for (const auto& [key, to] : moved_)
    moves.push_back(StoredMove{glm::vec3(std::bit_cast<float>(key.x), std::bit_cast<float>(key.y),
                               std::bit_cast<float>(key.z)),
                     to});
  std::sort(moves.begin(), moves.end(),
            [](const StoredMove& a, const StoredMove& b) { return positionLess(a.from, b.from); });
  out.putArray(moves);
  out.putArray(bricks_);
}

CrossBrickWeld CrossBrickWeld::read(ByteReader& in) {
  CrossBrickWeld weld;
  for (const StoredMove& move : in.getArray<StoredMove>()) weld.moved_[positionKeyOf(move.from)] = move.to;
  weld.bricks_ = in.getArray<uint32_t>();
  return weld;
}

}  // namespace tw
