// Piecewise quantization snapping: a local weld per piece, a table for shared positions, and the
// grow-and-resnap fixpoint. See quantization_snap.h for the contract.
#include "quantization_snap.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "edge_counts.h"
#include "grid_weld.h"
#include "package_format.h"

namespace tw {

namespace {

constexpr uint32_t kNotShared = std::numeric_limits<uint32_t>::max();
constexpr uint32_t kTooCoarse = pkg::kMaxPositionShift + 1;

void snapPositions(std::span<const glm::vec3> in, std::span<const uint32_t> local,
                   const std::vector<uint32_t>& vertex_shift, double step,
                   std::vector<glm::vec3>& out) {
  out.resize(in.size());
  for (size_t v = 0; v < in.size(); ++v) {
    const double cell = std::ldexp(step, int(vertex_shift[local[v]]));
    for (int a = 0; a < 3; ++a) out[v][a] = float(std::nearbyint(double(in[v][a]) / cell) * cell);
  }
}

// Exact-position -> id map for one piece's weld: open addressing with linear probing over flat
// slots, several times cheaper than std::unordered_map's node per entry (the weld is most of the
// snapping's time). Grows by doubling past half full.
class FlatPositionIndex {
 public:
  explicit FlatPositionIndex(size_t expected) {
    size_t capacity = 16;
    while (capacity < expected) capacity *= 2;  // distinct positions are usually < half the uses
    slots_.assign(capacity, Slot{});
  }
  // The id of `key`, inserting `id` if absent; second is true when inserted.
  std::pair<uint32_t, bool> insert(const PositionKey& key, uint32_t id) {
    if (2 * (count_ + 1) > slots_.size()) grow();
    const size_t mask = slots_.size() - 1;
    for (size_t i = PositionHash{}(key) & mask;; i = (i + 1) & mask) {
      Slot& slot = slots_[i];
      if (slot.id == kEmpty) {
        slot = {key, id};
        ++count_;
        return {id, true};
      }
      if (slot.key == key) return {slot.id, false};
    }
  }

 private:
  static constexpr uint32_t kEmpty = std::numeric_limits<uint32_t>::max();
  struct Slot {
    PositionKey key{0, 0, 0};
    uint32_t id = kEmpty;
  };
  void grow() {
    std::vector<Slot> old = std::move(slots_);
    slots_.assign(old.size() * 2, Slot{});
    const size_t mask = slots_.size() - 1;
    for (const Slot& slot : old) {
      if (slot.id == kEmpty) continue;
      size_t i = PositionHash{}(slot.key) & mask;
      while (slots_[i].id != kEmpty) i = (i + 1) & mask;
      slots_[i] = slot;
    }
  }
  std::vector<Slot> slots_;
  size_t count_ = 0;
};

// Per local vertex: the coarsest shift among its clusters and, if shared, the table's entry.
template <typename WeldT>
void vertexShifts(const WeldT& w, const std::vector<uint8_t>& shifts,
                  const std::vector<uint32_t>& table_of_local,
                  const std::vector<uint8_t>& table_shift, std::vector<uint32_t>& vertex_shift) {
  vertex_shift.assign(w.count, 0);
  for (size_t c = 0; c + 1 < w.offsets.size(); ++c)
    for (uint32_t id : w.of(c)) vertex_shift[id] = std::max<uint32_t>(vertex_shift[id], shifts[c]);
  for (uint32_t id = 0; id < w.count; ++id)
    if (table_of_local[id] != kNotShared)
      vertex_shift[id] = std::max<uint32_t>(vertex_shift[id], table_shift[table_of_local[id]]);
}

}  // namespace

// A piece's distinct positions: cluster c's vertex v is local vertex ids[offsets[c] + v]; shared
// local vertices are flagged.
struct QuantizationSnapper::Weld {
  std::vector<uint32_t> offsets;
  std::vector<uint32_t> ids;
  uint32_t count = 0;
  std::vector<uint8_t> shared;  // per local vertex
  std::vector<glm::vec3> first_position;  // per local vertex (for the shared table's key)

  std::span<const uint32_t> of(size_t c) const {
    return {ids.data() + offsets[c], offsets[c + 1] - offsets[c]};
  }
};

QuantizationSnapper::Weld QuantizationSnapper::weldPiece(const SnapPiece& input) {
  const std::span<const DagCluster> clusters = input.clusters;
  if (input.shared == SharedPositions::SeamsAndRoots && input.exported.size() != clusters.size())
    throw std::invalid_argument("QuantizationSnapper: one export flag per cluster");
  Weld w;
  w.offsets.resize(clusters.size() + 1, 0);
  for (size_t c = 0; c < clusters.size(); ++c)
    w.offsets[c + 1] = w.offsets[c] + uint32_t(clusters[c].positions.size());
  w.ids.resize(w.offsets.back());
  FlatPositionIndex index(w.ids.size() / 2);
  for (size_t c = 0; c < clusters.size(); ++c) {
    const std::vector<glm::vec3>& positions = clusters[c].positions;
    for (size_t v = 0; v < positions.size(); ++v) {
      auto [id, inserted] = index.insert(positionKeyOf(positions[v]), w.count);
      if (inserted) {
        ++w.count;
        if (input.shared != SharedPositions::None) w.first_position.push_back(positions[v]);
      }
      w.ids[w.offsets[c] + v] = id;
    }
  }
  w.shared.assign(w.count, input.shared == SharedPositions::All ? 1 : 0);
  if (input.shared == SharedPositions::SeamsAndRoots) {
    std::vector<uint64_t> unsorted;
    for (size_t c = 0; c < clusters.size(); ++c) {
      if (input.exported[c])
        for (uint32_t id : w.of(c)) w.shared[id] = 1;
      const DagCluster& cl = clusters[c];
      if (cl.level != 0 || cl.group != kNoGroup) continue;
      const std::span<const uint32_t> ids = w.of(c);
      for (size_t i = 0; i + 2 < cl.indices.size(); i += 3)
        for (int k = 0; k < 3; ++k)
          unsorted.push_back(edgeKey(ids[cl.indices[i + k]], ids[cl.indices[i + (k + 1) % 3]]));
    }
    std::vector<uint64_t> edges;
    {
      std::vector<uint32_t> offsets;
      bucketSortEdgeKeys(unsorted, w.count, edges, offsets);
      unsorted = {};
    }
    for (size_t i = 0; i < edges.size();) {
      size_t j = i + 1;
      while (j < edges.size() && edges[j] == edges[i]) ++j;
      if (j - i != 2)
        for (uint32_t id : {uint32_t(edges[i] >> 32), uint32_t(edges[i])})
          if (!input.may_be_elsewhere || input.may_be_elsewhere(w.first_position[id]))
            w.shared[id] = 1;
      i = j;
    }
  }
  return w;
}

void QuantizationSnapper::solve(uint32_t piece, const SnapPiece& input, bool keep_weld) {
  if (piece >= pieces_.size()) pieces_.resize(piece + 1);
  PieceState& state = pieces_[piece];
  const size_t n = input.clusters.size();
  auto kept = std::make_shared<Weld>(weldPiece(input));
  const Weld& w = *kept;

  // Table entries for the shared vertices (created on the first solve, in local order).
  std::vector<uint32_t> table_of_local(w.count, kNotShared);
  if (!state.solved) {
    state.shared_ids.clear();
    for (uint32_t id = 0; id < w.count; ++id) {
      if (!w.shared[id]) continue;
      auto [it, inserted] =
          table_index_.emplace(positionKeyOf(w.first_position[id]), uint32_t(table_shift_.size()));
      if (inserted) {
        table_shift_.push_back(0);
        table_finest_.push_back(kTooCoarse);
      }
      state.shared_ids.push_back(it->second);
    }
  }
  {
    size_t s = 0;
    for (uint32_t id = 0; id < w.count; ++id)
      if (w.shared[id]) {
        if (s >= state.shared_ids.size())
          throw std::invalid_argument("QuantizationSnapper: a piece changed between solves");
        table_of_local[id] = state.shared_ids[s++];
      }
  }

  // Shifts by extent; a piece solved again resumes from its grown shifts (they only grow).
  std::vector<uint8_t> initial(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 64), [&](const auto& range) {
    for (size_t c = range.begin(); c != range.end(); ++c)
      initial[c] = uint8_t(clusterPositionShift(input.clusters[c].positions, step_m_, 0));
  });
  std::vector<uint8_t> shifts = state.solved ? state.shifts : initial;
  if (shifts.size() != n)
    throw std::invalid_argument("QuantizationSnapper: a piece changed between solves");

  std::vector<uint32_t> vertex_shift;
  for (bool changed = true; changed;) {
    vertexShifts(w, shifts, table_of_local, table_shift_, vertex_shift);
    std::vector<uint8_t> grew(n, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 64), [&](const auto& range) {
      std::vector<glm::vec3> snapped;
      for (size_t c = range.begin(); c != range.end(); ++c) {
        snapPositions(input.clusters[c].positions, w.of(c), vertex_shift, step_m_, snapped);
        const uint32_t shift = clusterPositionShift(snapped, step_m_, shifts[c]);
        if (shift > pkg::kMaxPositionShift) continue;  // the encoder reports it
        if (shift != shifts[c]) {
          shifts[c] = uint8_t(shift);
          grew[c] = 1;
        }
      }
    });
    changed = std::find(grew.begin(), grew.end(), uint8_t{1}) != grew.end();
  }

  // Publish, and count what snapped coarser than its finest user.
  std::vector<uint32_t> finest(w.count, kTooCoarse);
  for (size_t c = 0; c < n; ++c)
    for (uint32_t id : w.of(c)) finest[id] = std::min<uint32_t>(finest[id], initial[c]);
  state.published.resize(state.shared_ids.size());
  state.max_vertex_shift = 0;
  state.coarsened_local = 0;
  size_t s = 0;
  for (uint32_t id = 0; id < w.count; ++id) {
    state.max_vertex_shift = std::max(state.max_vertex_shift, vertex_shift[id]);
    if (table_of_local[id] == kNotShared) {
      state.coarsened_local += vertex_shift[id] > finest[id];
      continue;
    }
    const uint32_t t = table_of_local[id];
    table_shift_[t] = uint8_t(vertex_shift[id]);  // >= the entry: it was a lower bound
    table_finest_[t] = uint8_t(std::min<uint32_t>(table_finest_[t], finest[id]));
    state.published[s++] = uint8_t(vertex_shift[id]);
  }
  state.shifts = std::move(shifts);
  state.solved = true;
  state.weld = keep_weld ? std::move(kept) : nullptr;
}

std::vector<uint32_t> QuantizationSnapper::stalePieces() const {
  std::vector<uint32_t> stale;
  for (uint32_t p = 0; p < pieces_.size(); ++p) {
    const PieceState& state = pieces_[p];
    for (size_t s = 0; s < state.shared_ids.size(); ++s)
      if (table_shift_[state.shared_ids[s]] != state.published[s]) {
        stale.push_back(p);
        break;
      }
  }
  return stale;
}

std::vector<std::vector<glm::vec3>> QuantizationSnapper::snap(uint32_t piece,
                                                              const SnapPiece& input,
                                                              std::vector<uint32_t>& shifts) {
  if (piece >= pieces_.size() || !pieces_[piece].solved)
    throw std::logic_error("QuantizationSnapper: snap of a piece never solved");
  PieceState& state = pieces_[piece];
  const size_t n = input.clusters.size();
  if (state.shifts.size() != n)
    throw std::invalid_argument("QuantizationSnapper: a piece changed between solve and snap");
  std::shared_ptr<const Weld> kept = std::move(state.weld);
  if (!kept) kept = std::make_shared<Weld>(weldPiece(input));
  const Weld& w = *kept;
  if (w.offsets.size() != n + 1)
    throw std::invalid_argument("QuantizationSnapper: a piece changed between solve and snap");
  std::vector<uint32_t> table_of_local(w.count, kNotShared);
  size_t s = 0;
  for (uint32_t id = 0; id < w.count; ++id)
    if (w.shared[id]) {
      if (s >= state.shared_ids.size())
        throw std::invalid_argument("QuantizationSnapper: a piece changed between solve and snap");
      table_of_local[id] = state.shared_ids[s++];
    }
  std::vector<uint32_t> vertex_shift;
  vertexShifts(w, state.shifts, table_of_local, table_shift_, vertex_shift);
  std::vector<std::vector<glm::vec3>> out(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 64), [&](const auto& range) {
    for (size_t c = range.begin(); c != range.end(); ++c)
      snapPositions(input.clusters[c].positions, w.of(c), vertex_shift, step_m_, out[c]);
  });
  shifts.assign(state.shifts.begin(), state.shifts.end());
  return out;
}

uint32_t QuantizationSnapper::maxShift() const {
  uint32_t shift = 0;
  for (const PieceState& state : pieces_) shift = std::max(shift, state.max_vertex_shift);
  return shift;
}

uint64_t QuantizationSnapper::coarsenedVertices() const {
  uint64_t count = 0;
  for (const PieceState& state : pieces_) count += state.coarsened_local;
  for (size_t t = 0; t < table_shift_.size(); ++t) count += table_shift_[t] > table_finest_[t];
  return count;
}

}  // namespace tw
