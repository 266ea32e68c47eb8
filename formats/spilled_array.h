// A growing array of plain values, appended in order and read at random, that keeps at most a
// memory limit of itself in memory: past the limit, full blocks go to an unlinked temporary file
// and come back through a small cache of blocks.
//
// Why: mesh formats index their vertices globally (OBJ by the order of `v` lines, PLY into its
// vertex element), so a reader must keep every vertex until the last face is read: 16 bytes per
// vertex, 1.7 GB for the 100M-triangle plant PLY, whatever --memory-budget says. Faces mostly use
// vertices written near them, so a few cached blocks serve nearly every lookup.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

namespace tw {

// The untyped store behind SpilledArray: blocks of kBlockValues values of `value_bytes` each.
class SpilledBlocks {
 public:
  static constexpr uint32_t kBlockShift = 12;
  static constexpr uint64_t kBlockValues = uint64_t{1} << kBlockShift;

  // memory_limit 0, or an empty spill_dir: everything stays in memory.
  SpilledBlocks(uint32_t value_bytes, uint64_t memory_limit, std::filesystem::path spill_dir);
  ~SpilledBlocks();
  SpilledBlocks(const SpilledBlocks&) = delete;
  SpilledBlocks& operator=(const SpilledBlocks&) = delete;
  SpilledBlocks(SpilledBlocks&& other) noexcept { *this = std::move(other); }
  SpilledBlocks& operator=(SpilledBlocks&& other) noexcept;

  uint64_t size() const { return size_; }
  bool spilled() const { return fd_ >= 0; }
  uint64_t spilledBytes() const { return spilled_blocks_ * block_bytes_; }

  // Room for the next value: appended in order. The first spill creates the folder when it is
  // missing. Throws std::runtime_error naming the spill folder when the temporary file cannot
  // be created or written.
  void* appendSlot();
  // The value at i < size(), valid until the next call.
  const void* at(uint64_t i) const;

 private:
  void spillFullBlocks();
  const uint8_t* cachedBlock(uint64_t block) const;

  uint32_t value_bytes_ = 0;
  uint64_t block_bytes_ = 0;
  uint64_t memory_limit_ = 0;
  std::filesystem::path spill_dir_;
  uint64_t size_ = 0;
  // In memory: every block (not spilled), or only the block being filled (spilled).
  std::vector<std::unique_ptr<uint8_t[]>> blocks_;
  int fd_ = -1;
  uint64_t spilled_blocks_ = 0;
  // Direct-mapped cache of spilled blocks: slot = block % slots.
  mutable std::vector<std::unique_ptr<uint8_t[]>> cache_;
  mutable std::vector<uint64_t> cache_block_;
};

template <typename T>
class SpilledArray {
  static_assert(std::is_trivially_copyable_v<T>);

 public:
  SpilledArray() : blocks_(sizeof(T), 0, {}) {}
  SpilledArray(uint64_t memory_limit, std::filesystem::path spill_dir)
      : blocks_(sizeof(T), memory_limit, std::move(spill_dir)) {}

  uint64_t size() const { return blocks_.size(); }
  bool empty() const { return size() == 0; }
  bool spilled() const { return blocks_.spilled(); }
  uint64_t spilledBytes() const { return blocks_.spilledBytes(); }

  void push_back(const T& value) { std::memcpy(blocks_.appendSlot(), &value, sizeof(T)); }
  T operator[](uint64_t i) const {
    T value;
    std::memcpy(&value, blocks_.at(i), sizeof(T));
    return value;
  }

 private:
  SpilledBlocks blocks_;
};

}  // namespace tw
