// Blocks of an append-in-order array kept in memory up to a limit, the rest in an unlinked
// temporary file (see spilled_array.h).
#include "spilled_array.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <stdexcept>
#include <string>

namespace tw {
namespace {

[[noreturn]] void spillFail(const std::filesystem::path& dir, const char* what) {
  throw std::runtime_error("vertex spill file in " + dir.string() + ": " + what + ": " +
                           std::strerror(errno));
}

enum class Direction { kRead, kWrite };

// All `bytes` at `offset` read into, or written from, `data`: resumed after short counts and
// signals. False on an error or an early end of file.
bool transfer(Direction direction, int fd, uint8_t* data, uint64_t bytes, uint64_t offset) {
  while (bytes > 0) {
    const ssize_t n = direction == Direction::kRead ? ::pread(fd, data, bytes, off_t(offset))
                                                    : ::pwrite(fd, data, bytes, off_t(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data += n;
    offset += uint64_t(n);
    bytes -= uint64_t(n);
  }
  return true;
}

}  // namespace

SpilledBlocks::SpilledBlocks(uint32_t value_bytes, uint64_t memory_limit,
                             std::filesystem::path spill_dir)
    : value_bytes_(value_bytes),
      block_bytes_(uint64_t{value_bytes} * kBlockValues),
      memory_limit_(spill_dir.empty() ? 0 : memory_limit),
      spill_dir_(std::move(spill_dir)) {}

SpilledBlocks::~SpilledBlocks() {
  if (fd_ >= 0) ::close(fd_);
}

SpilledBlocks& SpilledBlocks::operator=(SpilledBlocks&& other) noexcept {
  if (this == &other) return *this;
  if (fd_ >= 0) ::close(fd_);
  value_bytes_ = other.value_bytes_;
  block_bytes_ = other.block_bytes_;
  memory_limit_ = other.memory_limit_;
  spill_dir_ = std::move(other.spill_dir_);
  size_ = std::exchange(other.size_, 0);
  blocks_ = std::move(other.blocks_);
  fd_ = std::exchange(other.fd_, -1);
  spilled_blocks_ = std::exchange(other.spilled_blocks_, 0);
  cache_ = std::move(other.cache_);
  cache_block_ = std::move(other.cache_block_);
  return *this;
}

void* SpilledBlocks::appendSlot() {
  const uint64_t in_block = size_ & (kBlockValues - 1);
  if (in_block == 0) {
    if (memory_limit_ > 0 && !spilled() && (blocks_.size() + 1) * block_bytes_ > memory_limit_)
      spillFullBlocks();
    else if (spilled() && !blocks_.empty())
      spillFullBlocks();
    blocks_.push_back(std::make_unique<uint8_t[]>(block_bytes_));
  }
  ++size_;
  return blocks_.back().get() + in_block * value_bytes_;
}

// Writes every full block in memory to the file (creating it, unlinked, on first use) and frees
// them; the cache gets half the memory limit, at least 4 blocks.
void SpilledBlocks::spillFullBlocks() {
  if (fd_ < 0) {
    std::error_code made;
    std::filesystem::create_directories(spill_dir_, made);  // a failure shows in mkstemp
    std::string pattern = (spill_dir_ / "vertices-XXXXXX").string();
    fd_ = ::mkstemp(pattern.data());
    if (fd_ < 0) spillFail(spill_dir_, "cannot create it");
    ::unlink(pattern.c_str());  // nothing is left behind, whatever happens to the process
    const uint64_t slots = std::max<uint64_t>(4, memory_limit_ / 2 / block_bytes_);
    cache_.resize(slots);
    cache_block_.assign(slots, UINT64_MAX);
  }
  for (std::unique_ptr<uint8_t[]>& block : blocks_) {
    if (!transfer(Direction::kWrite, fd_, block.get(), block_bytes_, spilled_blocks_ * block_bytes_))
      spillFail(spill_dir_, "write failed");
    ++spilled_blocks_;
  }
  blocks_.clear();
}

const uint8_t* SpilledBlocks::cachedBlock(uint64_t block) const {
  const size_t slot = size_t(block % cache_.size());
  if (cache_block_[slot] != block) {
    if (!cache_[slot]) cache_[slot] = std::make_unique<uint8_t[]>(block_bytes_);
    if (!transfer(Direction::kRead, fd_, cache_[slot].get(), block_bytes_, block * block_bytes_))
      spillFail(spill_dir_, "read failed");
    cache_block_[slot] = block;
  }
  return cache_[slot].get();
}

const void* SpilledBlocks::at(uint64_t i) const {
  const uint64_t block = i >> kBlockShift;
  const uint64_t offset = (i & (kBlockValues - 1)) * value_bytes_;
  if (!spilled()) return blocks_[block].get() + offset;
  if (block >= spilled_blocks_) return blocks_.back().get() + offset;  // the block being filled
  return cachedBlock(block) + offset;
}

}  // namespace tw
