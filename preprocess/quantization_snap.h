// Quantization snapping of a LOD DAG that is delivered in pieces (the preprocessor's bricks, then
// the merged upper levels), so the package can be assembled with one piece in memory at a time.
//
// Why snapping: clusters pick their quantization shift by extent (cell = step * 2^shift), and
// clusters of different levels share locked border vertices, so a shared vertex would decode
// differently in a fine and a coarse cluster. Every distinct position is snapped to the grid of
// the coarsest shift among the clusters that use it (nested power-of-two grids: exact for every
// finer cluster); then all clusters decode it identically and a cut closed in the DAG stays closed
// in the package. Snapping can widen a cluster past its shift; its shift then grows and the snap is
// redone, until nothing changes (shifts only grow and are bounded).
//
// Pieces: a position used by one piece only needs that piece's clusters; a position several pieces
// use (a brick seam, a brick root's vertex that merged levels reuse) needs all of them. Those
// shared positions, declared by each piece (SharedPositions), live in one table (position ->
// coarsest shift so far). solve() runs a piece's fixpoint against the table and raises the
// table's entries; a piece whose shared entries were later raised by another piece is stale and
// is solved again, until no piece is stale. snap() then gives each piece its final positions.
// The result depends only on the pieces and the order they are first solved in, never on thread
// timing. A single piece declaring nothing shared is exactly the whole-DAG computation.
//
// Memory: per piece one byte per cluster and 5 bytes per shared vertex; the table about 40 bytes
// per shared position. A piece's own geometry is only borrowed during solve() and snap().
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <unordered_map>
#include <vector>

#include <functional>

#include <glm/glm.hpp>

#include "cluster_dag.h"
#include "position_key.h"

namespace tw {

enum class SharedPositions : uint8_t {
  None,           // nothing shared: the piece is the whole DAG
  SeamsAndRoots,  // a brick: the vertices of its level-0 edges not used exactly twice (seams and
                  // the model's open or non-manifold edges), and every vertex of `exported`
                  // clusters (its roots, reused by the merged levels)
  All,            // every vertex (the merged levels, made of brick roots' vertices)
};

struct SnapPiece {
  std::span<const DagCluster> clusters;
  std::span<const uint8_t> exported;  // SeamsAndRoots: one per cluster, nonzero = shared
  SharedPositions shared = SharedPositions::None;
  // SeamsAndRoots: whether a position could also be another piece's (it lies within another
  // brick's bounds). The vertices of edges not used twice are shared only where it holds, so
  // the model's own open edges far from other bricks stay out of the shared table, which would
  // otherwise grow with the model (uncapped pipes: most of the plant's open edges). Empty: all.
  std::function<bool(const glm::vec3&)> may_be_elsewhere;
};

class QuantizationSnapper {
 public:
  explicit QuantizationSnapper(double position_step_m) : step_m_(position_step_m) {}

  // The piece's fixpoint against the shared table; raises the table's entries for its shared
  // positions. The same piece must always be given the same input. With keep_weld, the piece's
  // weld (about 5 bytes per cluster vertex) is kept for its snap(), which then skips redoing it.
  // Throws std::invalid_argument when `exported` does not match the clusters.
  void solve(uint32_t piece, const SnapPiece& input, bool keep_weld = false);
  // Solved pieces whose shared positions another piece has since raised; solve them again.
  std::vector<uint32_t> stalePieces() const;
  // The package's positions for a solved, non-stale piece: per cluster, its vertices snapped;
  // `shifts` gets each cluster's quantization shift (the encoder's min_shift, which it will keep).
  // Releases a weld kept by solve().
  std::vector<std::vector<glm::vec3>> snap(uint32_t piece, const SnapPiece& input,
                                           std::vector<uint32_t>& shifts);

  uint32_t maxShift() const;          // coarsest grid any vertex snaps to
  uint64_t coarsenedVertices() const;  // distinct positions snapped coarser than their finest user
  size_t sharedPositions() const { return table_shift_.size(); }

 private:
  struct Weld;  // a piece's distinct positions (quantization_snap.cpp)
  static Weld weldPiece(const SnapPiece& input);
  struct PieceState {
    std::shared_ptr<const Weld> weld;  // kept by solve(keep_weld) until snap()
    bool solved = false;
    std::vector<uint8_t> shifts;       // per cluster
    std::vector<uint32_t> shared_ids;  // table index per shared vertex, in local vertex order
    std::vector<uint8_t> published;    // the shift it left in the table, per shared vertex
    uint32_t max_vertex_shift = 0;
    uint64_t coarsened_local = 0;      // unshared positions only; shared ones counted globally
  };
  double step_m_;
  std::vector<PieceState> pieces_;
  std::unordered_map<PositionKey, uint32_t, PositionHash> table_index_;
  std::vector<uint8_t> table_shift_;
  std::vector<uint8_t> table_finest_;
};

}  // namespace tw
