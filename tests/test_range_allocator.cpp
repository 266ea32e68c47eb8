// The range allocator that carves the GPU pool: first fit at the lowest address, coalescing,
// exhaustion, bad releases, and a long random run checked against a bitmap model.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <stdexcept>
#include <vector>

#include "range_allocator.h"

namespace tw {
namespace {


TEST(RangeAllocator, FillsInAddressOrderAndReportsExhaustion) {
  RangeAllocator a(100);
  for (uint64_t i = 0; i < 10; ++i) {
    auto offset = a.allocate(10);
    ASSERT_TRUE(offset.has_value());
    EXPECT_EQ(*offset, i * 10);
  }
  EXPECT_EQ(a.used(), 100u);
  EXPECT_EQ(a.largestFree(), 0u);
  EXPECT_FALSE(a.allocate(1).has_value());

  RangeAllocator empty;
  EXPECT_EQ(empty.capacity(), 0u);
  EXPECT_FALSE(empty.allocate(1).has_value());
  RangeAllocator small(5);
  EXPECT_FALSE(small.allocate(6).has_value());
  EXPECT_EQ(small.used(), 0u);
}

TEST(RangeAllocator, ReusesTheLowestFittingHoleAfterFragmentation) {
  RangeAllocator a(100);
  std::vector<uint64_t> offsets;
  for (int i = 0; i < 10; ++i) offsets.push_back(*a.allocate(10));
  a.release(offsets[1]);  // hole [10, 20)
  a.release(offsets[3]);  // hole [30, 40)
  a.release(offsets[6]);  // hole [60, 70)
  EXPECT_EQ(a.used(), 70u);
  EXPECT_EQ(a.largestFree(), 10u);
  EXPECT_FALSE(a.allocate(11).has_value()) << "30 free elements, but no 11 in a row";
  EXPECT_EQ(*a.allocate(4), 10u);
  EXPECT_EQ(*a.allocate(7), 30u) << "the first hole has 6 left: too small";
  EXPECT_EQ(*a.allocate(6), 14u);
  EXPECT_EQ(*a.allocate(3), 37u);
  EXPECT_EQ(*a.allocate(10), 60u);
  EXPECT_EQ(a.used(), 100u);
}

TEST(RangeAllocator, CoalescesFreedNeighbours) {
  RangeAllocator a(90);
  uint64_t x = *a.allocate(30), y = *a.allocate(30), z = *a.allocate(30);
  a.release(x);
  a.release(z);
  EXPECT_EQ(a.largestFree(), 30u);
  EXPECT_FALSE(a.allocate(31).has_value());
  a.release(y);  // merges with both neighbours
  EXPECT_EQ(a.largestFree(), 90u);
  EXPECT_EQ(a.used(), 0u);
  EXPECT_EQ(*a.allocate(90), 0u);
  a.release(0);
  // Merge with the left neighbour only, then the right only.
  uint64_t p = *a.allocate(20), q = *a.allocate(20), r = *a.allocate(20);
  a.release(p);
  a.release(q);
  EXPECT_EQ(a.largestFree(), 40u);
  a.release(r);
  EXPECT_EQ(a.largestFree(), 90u);
}

TEST(RangeAllocator, RejectsBadReleaseAndZeroCount) {
  RangeAllocator a(50);
  uint64_t x = *a.allocate(10);
  EXPECT_THROW(a.release(x + 1), std::logic_error) << "inside a live range";
  EXPECT_THROW(a.release(40), std::logic_error) << "free space";
  EXPECT_THROW(a.release(1000), std::logic_error) << "outside the pool";
  EXPECT_THROW(a.allocate(0), std::invalid_argument);
  a.release(x);
  EXPECT_THROW(a.release(x), std::logic_error) << "double release";
  EXPECT_EQ(a.used(), 0u);
  EXPECT_EQ(a.largestFree(), 50u);
}

// First-fit-lowest-address allocation over a bitmap: the allocator must agree with it exactly.
TEST(RangeAllocator, MatchesABitmapModelUnderRandomUse) {
  constexpr uint64_t kCapacity = 400;
  RangeAllocator a(kCapacity);
  std::vector<bool> used(kCapacity, false);
  std::map<uint64_t, uint64_t> live;
  std::mt19937 rng(99);
  auto modelFirstFit = [&](uint64_t count) -> std::optional<uint64_t> {
    uint64_t run = 0;
    for (uint64_t i = 0; i < kCapacity; ++i) {
      run = used[i] ? 0 : run + 1;
      if (run == count) return i + 1 - count;
    }
    return std::nullopt;
  };
  auto modelLargest = [&] {
    uint64_t run = 0, best = 0;
    for (uint64_t i = 0; i < kCapacity; ++i) {
      run = used[i] ? 0 : run + 1;
      best = std::max(best, run);
    }
    return best;
  };
  int failures = 0;
  for (int step = 0; step < 20000; ++step) {
    if (live.empty() || rng() % 100 < 55) {
      const uint64_t count = 1 + rng() % (rng() % 4 == 0 ? 120 : 16);
      auto expected = modelFirstFit(count);
      auto got = a.allocate(count);
      ASSERT_EQ(got, expected) << "step " << step << " count " << count;
      if (got) {
        for (uint64_t i = *got; i < *got + count; ++i) used[i] = true;
        live[*got] = count;
      } else {
        ++failures;
      }
    } else {
      auto it = live.begin();
      std::advance(it, rng() % live.size());
      a.release(it->first);
      for (uint64_t i = it->first; i < it->first + it->second; ++i) used[i] = false;
      live.erase(it);
    }
    uint64_t used_count = static_cast<uint64_t>(std::count(used.begin(), used.end(), true));
    ASSERT_EQ(a.used(), used_count) << "step " << step;
    if (step % 16 == 0) {
      ASSERT_EQ(a.largestFree(), modelLargest()) << "step " << step;
    }
  }
  EXPECT_GT(failures, 100) << "the run should reach exhaustion often";
  for (const auto& [offset, count] : live) a.release(offset);
  EXPECT_EQ(a.largestFree(), kCapacity);
}

}  // namespace
}  // namespace tw
