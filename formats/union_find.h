// Disjoint sets over dense indices (union-find with path halving), for grouping things that
// touch: welded NURBS corners, connected triangles in a cluster group, pipe parts joined end to
// end. The smaller index stays the root, so the groups' roots do not depend on the order of the
// joins.
#pragma once

#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

namespace tw {

class UnionFind {
 public:
  explicit UnionFind(size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0u); }

  // The root of x's set.
  uint32_t find(uint32_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }

  void unite(uint32_t a, uint32_t b) {
    a = find(a);
    b = find(b);
    if (a < b)
      parent_[b] = a;
    else if (b < a)
      parent_[a] = b;
  }

 private:
  std::vector<uint32_t> parent_;
};

}  // namespace tw
