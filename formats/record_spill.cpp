// RecordSpill: see record_spill.h.
#include "record_spill.h"

#include <fcntl.h>
#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

namespace tw {

RecordSpill::RecordSpill(const std::filesystem::path& path, uint32_t record_bytes,
                         const char* what)
    : path_(path), record_bytes_(record_bytes), what_(what) {
  if (record_bytes == 0) throw std::invalid_argument("RecordSpill: record size 0");
  hash_ = XXH3_createState();
  if (!hash_) throw std::bad_alloc();
  XXH3_64bits_reset(hash_);
  file_ = std::fopen(path.c_str(), "w+b");
  if (!file_) {
    XXH3_freeState(hash_);
    throw std::runtime_error(path.string() + ": cannot create the " + what + " spill file: " +
                             std::strerror(errno));
  }
}

RecordSpill::~RecordSpill() {
  if (file_) std::fclose(file_);
  XXH3_freeState(hash_);
}

void RecordSpill::ioFail(const char* what) const {
  throw std::runtime_error(path_.string() + ": " + what + " the " + what_ + " spill file: " +
                           std::strerror(errno));
}

void RecordSpill::append(const void* records, uint64_t count) {
  const uint64_t n = count * record_bytes_;
  if (n == 0) return;
  if (std::fwrite(records, 1, n, file_) != n) ioFail("cannot write");
  XXH3_64bits_update(hash_, records, n);
  bytes_ += n;
}

void RecordSpill::flush() const {
  if (std::fflush(file_) != 0) ioFail("cannot write");
}

void RecordSpill::read(uint64_t first, uint64_t count, void* out) const {
  if (first > this->count() || count > this->count() - first)
    throw std::out_of_range(std::string("RecordSpill: read past the end of the ") + what_);
  flush();
  const int fd = ::fileno(file_);
  uint8_t* dst = static_cast<uint8_t*>(out);
  uint64_t offset = first * record_bytes_, left = count * record_bytes_;
  while (left > 0) {
    const ssize_t got = ::pread(fd, dst, left, off_t(offset));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) ioFail("cannot read");
    dst += got;
    offset += uint64_t(got);
    left -= uint64_t(got);
  }
}

void RecordSpill::forEachChunk(uint64_t chunk_bytes,
                               const std::function<void(std::span<const uint8_t>)>& fn) const {
  const uint64_t records_per_chunk = std::max<uint64_t>(1, chunk_bytes / record_bytes_);
  std::vector<uint8_t> chunk(std::min(records_per_chunk, count()) * record_bytes_);
  for (uint64_t first = 0; first < count(); first += records_per_chunk) {
    const uint64_t n = std::min(records_per_chunk, count() - first);
    read(first, n, chunk.data());
    fn({chunk.data(), size_t(n * record_bytes_)});
  }
}

uint64_t RecordSpill::checksumWith(std::span<const uint8_t> tail) const {
  XXH3_state_t* copy = XXH3_createState();
  if (!copy) throw std::bad_alloc();
  XXH3_copyState(copy, hash_);
  if (!tail.empty()) XXH3_64bits_update(copy, tail.data(), tail.size());
  const uint64_t sum = XXH3_64bits_digest(copy);
  XXH3_freeState(copy);
  return sum;
}

}  // namespace tw
