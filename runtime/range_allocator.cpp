// First-fit range allocation over ordered maps: the free map is kept coalesced (no two free
// ranges touch), so a release merges with at most one neighbour on each side and first fit is a
// walk in address order. Pools hold a few thousand pages at most, so a linear walk is cheap next
// to the page decode that precedes every allocation.
#include "range_allocator.h"

#include <iterator>
#include <stdexcept>
#include <string>

namespace tw {

RangeAllocator::RangeAllocator(uint64_t capacity) : capacity_(capacity) {
  if (capacity_ > 0) free_.emplace(0, capacity_);
}

std::optional<uint64_t> RangeAllocator::allocate(uint64_t count) {
  if (count == 0) throw std::invalid_argument("RangeAllocator::allocate: count must be > 0");
  for (auto it = free_.begin(); it != free_.end(); ++it) {
    if (it->second < count) continue;
    const uint64_t offset = it->first;
    const uint64_t remaining = it->second - count;
    free_.erase(it);
    if (remaining > 0) free_.emplace(offset + count, remaining);
    live_.emplace(offset, count);
    used_ += count;
    return offset;
  }
  return std::nullopt;
}

void RangeAllocator::release(uint64_t offset) {
  auto live = live_.find(offset);
  if (live == live_.end())
    throw std::logic_error("RangeAllocator::release: offset " + std::to_string(offset) +
                           " is not an allocated range");
  uint64_t start = offset;
  uint64_t end = offset + live->second;
  used_ -= live->second;
  live_.erase(live);

  // Merge with the free range that starts where this one ends, then with the one that ends
  // where this one starts.
  auto next = free_.lower_bound(end);
  if (next != free_.end() && next->first == end) {
    end += next->second;
    next = free_.erase(next);
  }
  if (next != free_.begin()) {
    auto prev = std::prev(next);
    if (prev->first + prev->second == start) {
      start = prev->first;
      free_.erase(prev);
    }
  }
  free_.emplace(start, end - start);
}

uint64_t RangeAllocator::largestFree() const {
  uint64_t largest = 0;
  for (const auto& [offset, count] : free_)
    if (count > largest) largest = count;
  return largest;
}

}  // namespace tw
