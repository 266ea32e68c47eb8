// Seam edges between bricks; see brick_seams.h.
#include "brick_seams.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include <xxhash.h>

#include "position_key.h"

namespace tw {

SeamEdgeKey seamEdgeKey(const glm::vec3& a, const glm::vec3& b) {
  const PositionKey ka = positionKeyOf(a), kb = positionKeyOf(b);
  const std::array<uint32_t, 3> pa{ka.x, ka.y, ka.z}, pb{kb.x, kb.y, kb.z};
  return pa < pb ? SeamEdgeKey{pa[0], pa[1], pa[2], pb[0], pb[1], pb[2]}
                 : SeamEdgeKey{pb[0], pb[1], pb[2], pa[0], pa[1], pa[2]};
}

uint64_t seamEdgeHash(const SeamEdgeKey& key) { return XXH3_64bits(key.data(), sizeof key); }

namespace {

// Every edge of every valid triangle, sorted, with repeats (one entry per triangle side).
std::vector<SeamEdgeKey> sortedEdgeKeys(std::span<const glm::vec3> positions,
                                        std::span<const uint32_t> indices) {
  auto finite = [](const glm::vec3& p) {
    return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  };
  std::vector<SeamEdgeKey> edges;
  edges.reserve(indices.size());
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    if (indices[t] >= positions.size() || indices[t + 1] >= positions.size() ||
        indices[t + 2] >= positions.size())
      continue;
    const glm::vec3 p[3] = {positions[indices[t]], positions[indices[t + 1]],
                            positions[indices[t + 2]]};
    if (!finite(p[0]) || !finite(p[1]) || !finite(p[2])) continue;
    const PositionKey k0 = positionKeyOf(p[0]), k1 = positionKeyOf(p[1]), k2 = positionKeyOf(p[2]);
    if (k0 == k1 || k1 == k2 || k0 == k2) continue;  // degenerate after welding
    for (int e = 0; e < 3; ++e) edges.push_back(seamEdgeKey(p[e], p[(e + 1) % 3]));
  }
  std::sort(edges.begin(), edges.end());
  return edges;
}

// Keeps each key once; with `only_single`, only keys that appeared exactly once.
std::vector<SeamEdgeKey> distinct(const std::vector<SeamEdgeKey>& sorted, bool only_single) {
  std::vector<SeamEdgeKey> out;
  for (size_t i = 0; i < sorted.size();) {
    size_t j = i + 1;
    while (j < sorted.size() && sorted[j] == sorted[i]) ++j;
    if (!only_single || j - i == 1) out.push_back(sorted[i]);
    i = j;
  }
  return out;
}

}  // namespace

std::vector<SeamEdgeKey> openEdgeKeys(std::span<const glm::vec3> positions,
                                      std::span<const uint32_t> indices) {
  return distinct(sortedEdgeKeys(positions, indices), true);
}

std::vector<SeamEdgeKey> edgeKeys(std::span<const glm::vec3> positions,
                                  std::span<const uint32_t> indices) {
  return distinct(sortedEdgeKeys(positions, indices), false);
}

BrickSeams BrickSeams::fromOpenEdges(std::vector<std::vector<SeamEdgeKey>> per_brick) {
  std::vector<std::vector<uint64_t>> hashes(per_brick.size());
  for (size_t b = 0; b < per_brick.size(); ++b) {
    for (const SeamEdgeKey& key : per_brick[b]) hashes[b].push_back(seamEdgeHash(key));
    per_brick[b] = {};
    std::sort(hashes[b].begin(), hashes[b].end());
    hashes[b].erase(std::unique(hashes[b].begin(), hashes[b].end()), hashes[b].end());
  }
  return fromSortedHashes(hashes);
}

BrickSeams BrickSeams::fromSortedHashes(const std::vector<std::vector<uint64_t>>& per_brick) {
  // Each list is sorted and unique, so a hash at the head of two or more lists at once is in two
  // or more bricks. A merge of the heads (smallest first) finds them without a concatenated copy
  // of every list, which at 100M triangles was the stage's peak (about 0.5 GB on top of them).
  using Head = std::pair<const uint64_t*, const uint64_t*>;  // next, end
  auto later = [](const Head& a, const Head& b) { return *b.first < *a.first; };
  std::vector<Head> heads;
  for (const auto& list : per_brick)
    if (!list.empty()) heads.push_back({list.data(), list.data() + list.size()});
  std::make_heap(heads.begin(), heads.end(), later);
  BrickSeams seams;
  while (!heads.empty()) {
    const uint64_t hash = *heads.front().first;
    size_t lists = 0;
    while (!heads.empty() && *heads.front().first == hash) {
      std::pop_heap(heads.begin(), heads.end(), later);
      Head& head = heads.back();
      ++lists;
      if (++head.first == head.second)
        heads.pop_back();
      else
        std::push_heap(heads.begin(), heads.end(), later);
    }
    if (lists >= 2) seams.hashes_.push_back(hash);
  }
  return seams;
}

BrickSeams BrickSeams::find(const BrickedScene& scene, float weld_tolerance, Progress* progress) {
  if (scene.bricks.size() <= 1) return {};
  // A seam edge has triangles in both bricks, so it lies inside the bounds of both. Keeping only
  // the edges inside some other brick's bounds (padded by a hair against rounding) is therefore
  // exact, and keeps this small whatever the model's size. All edges are kept, not only the open
  // ones: an edge used twice in one brick and once in another (non-manifold input) is open in
  // the second only, and must still be locked there.
  const size_t n = scene.bricks.size();
  auto overlaps = [](const BrickInfo& a, const BrickInfo& b) {
    const glm::vec3 pad = 1e-5f * (glm::abs(b.bounds_min) + glm::abs(b.bounds_max)) + 1e-6f;
    return glm::all(glm::lessThanEqual(a.bounds_min, b.bounds_max + pad)) &&
           glm::all(glm::lessThanEqual(b.bounds_min - pad, a.bounds_max));
  };
  auto inside = [](const BrickInfo& box, const glm::vec3& p) {
    const glm::vec3 pad = 1e-5f * (glm::abs(box.bounds_min) + glm::abs(box.bounds_max)) + 1e-6f;
    return glm::all(glm::lessThanEqual(box.bounds_min - pad, p)) &&
           glm::all(glm::lessThanEqual(p, box.bounds_max + pad));
  };
  std::vector<std::vector<uint32_t>> neighbours(n);
  for (uint32_t b = 0; b < n; ++b)
    for (uint32_t o = 0; o < n; ++o)
      if (o != b && overlaps(scene.bricks[b], scene.bricks[o])) neighbours[b].push_back(o);

  // One brick's seam candidates: the hashes of its edges inside another brick and, when asked,
  // the end vertices of its rim edges (used other than twice) there, for the weld.
  std::vector<std::vector<uint64_t>> per_brick(n);
  std::vector<CrossBrickWeld::Candidate> rims;
  auto readBrick = [&](uint32_t b, const CrossBrickWeld* weld) {
    BrickMesh mesh = loadBrick(scene, b);
    if (weld) weld->apply(mesh.positions);
    const std::vector<SeamEdgeKey> edges = sortedEdgeKeys(mesh.positions, mesh.indices);
    mesh = BrickMesh{};
    per_brick[b].clear();
    for (size_t i = 0; i < edges.size();) {
      size_t j = i + 1;
      while (j < edges.size() && edges[j] == edges[i]) ++j;
      const SeamEdgeKey& key = edges[i];
      const glm::vec3 p0 = glm::vec3(std::bit_cast<float>(key[0]), std::bit_cast<float>(key[1]),
                                     std::bit_cast<float>(key[2]));
      const glm::vec3 p1 = glm::vec3(std::bit_cast<float>(key[3]), std::bit_cast<float>(key[4]),
                                     std::bit_cast<float>(key[5]));
      for (uint32_t o : neighbours[b])
        if (inside(scene.bricks[o], p0) && inside(scene.bricks[o], p1)) {
          per_brick[b].push_back(seamEdgeHash(key));
          if (!weld && weld_tolerance > 0.0f && j - i != 2) {
            rims.push_back({p0, b});
            rims.push_back({p1, b});
          }
          break;
        }
      i = j;
    }
    std::sort(per_brick[b].begin(), per_brick[b].end());
    per_brick[b].erase(std::unique(per_brick[b].begin(), per_brick[b].end()), per_brick[b].end());
    per_brick[b].shrink_to_fit();  // held until every brick is read
  };

  beginStage(progress, "find seams", n);
  for (uint32_t b = 0; b < n; ++b) {
    if (!neighbours[b].empty()) readBrick(b, nullptr);
    updateProgress(progress, b + 1);
  }
  endStage(progress);
  BrickSeams seams;
  seams.weld_ = CrossBrickWeld::build(std::move(rims), weld_tolerance);
  rims = {};
  const std::vector<uint32_t>& moved = seams.weld_.bricksWithMoves();
  if (!moved.empty()) {
    beginStage(progress, "weld across bricks", moved.size());
    for (size_t i = 0; i < moved.size(); ++i) {
      readBrick(moved[i], &seams.weld_);
      updateProgress(progress, i + 1);
    }
    endStage(progress);
  }
  seams.hashes_ = fromSortedHashes(per_brick).hashes_;
  return seams;
}

bool BrickSeams::contains(const glm::vec3& a, const glm::vec3& b) const {
  return std::binary_search(hashes_.begin(), hashes_.end(), seamEdgeHash(seamEdgeKey(a, b)));
}

namespace {
constexpr uint32_t kSeamsBlobVersion = 1;
}

std::vector<uint8_t> BrickSeams::serialize() const {
  ByteWriter out;
  out.put(kSeamsBlobVersion);
  out.putArray(hashes_);
  weld_.write(out);
  return std::move(out.bytes);
}

BrickSeams BrickSeams::deserialize(std::span<const uint8_t> bytes, const std::string& source) {
  ByteReader in(bytes, source);
  if (const uint32_t version = in.get<uint32_t>(); version != kSeamsBlobVersion)
    in.fail("seams blob version " + std::to_string(version) + ", expected " +
            std::to_string(kSeamsBlobVersion));
  BrickSeams seams;
  seams.hashes_ = in.getArray<uint64_t>();
  if (!std::is_sorted(seams.hashes_.begin(), seams.hashes_.end()))
    in.fail("the seam edges are not sorted");
  seams.weld_ = CrossBrickWeld::read(in);
  if (!in.atEnd()) in.fail("bytes after the seams");
  return seams;
}

}  // namespace tw
