// A first-fit allocator of ranges in a fixed-size pool (offsets in elements, not bytes), with
// coalescing of freed neighbours. The GPU geometry pool is three big buffers (vertices, indices,
// triangle objects); the pager carves each page's share out of them with one of these, so the
// GL code never allocates and the budget is a hard limit.
#pragma once

#include <cstdint>
#include <map>
#include <optional>

namespace tw {

class RangeAllocator {
 public:
  explicit RangeAllocator(uint64_t capacity = 0);

  // Offset of a free range of `count` elements (count > 0), or nullopt when no free range is
  // large enough. Lowest address among the fitting ranges, so results are deterministic.
  std::optional<uint64_t> allocate(uint64_t count);
  // Returns a range given by allocate(); freeing anything else throws std::logic_error.
  void release(uint64_t offset);

  uint64_t capacity() const { return capacity_; }
  uint64_t used() const { return used_; }
  uint64_t largestFree() const;

 private:
  uint64_t capacity_ = 0;
  uint64_t used_ = 0;
  std::map<uint64_t, uint64_t> free_;  // offset -> count, non-adjacent
  std::map<uint64_t, uint64_t> live_;  // offset -> count
};

}  // namespace tw
