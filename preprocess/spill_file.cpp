// Spill files of the bricking passes. See spill_file.h.
#include "spill_file.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#define XXH_INLINE_ALL
#include <xxhash.h>

namespace tw {
namespace {

constexpr uint32_t kSpillMagic = 0x50535754u;    // "TWSP"
constexpr uint32_t kTrailerMagic = 0x45535754u;  // "TWSE"
constexpr uint32_t kSpillVersion = 2;  // 2: ObjectBounds records carry the surface kind

struct SpillHeader {
  uint32_t magic, version, kind, reserved;
};
struct SpillTrailer {
  uint32_t magic, reserved;
  uint64_t record_count, content_bytes, checksum;  // XXH3-64 of the content
};
static_assert(sizeof(SpillHeader) == 16 && sizeof(SpillTrailer) == 32);

[[noreturn]] void ioFail(const std::filesystem::path& path, const char* what) {
  throw std::runtime_error(path.string() + ": " + what + ": " + std::strerror(errno));
}

}  // namespace

struct SpillWriter::Checksum {
  XXH3_state_t state;
};

SpillWriter::SpillWriter(std::filesystem::path path, SpillKind kind)
    : path_(std::move(path)), checksum_(std::make_unique<Checksum>()) {
  XXH3_64bits_reset(&checksum_->state);
  std::FILE* f = std::fopen(path_.string().c_str(), "wb");
  if (!f) ioFail(path_, "cannot create");
  SpillHeader header{kSpillMagic, kSpillVersion, static_cast<uint32_t>(kind), 0};
  bool ok = std::fwrite(&header, sizeof header, 1, f) == 1;
  if (std::fclose(f) != 0 || !ok) ioFail(path_, "cannot write");
  bytes_written_ = sizeof header;
}

SpillWriter::~SpillWriter() = default;

void SpillWriter::append(const void* data, size_t bytes) {
  const auto* p = static_cast<const uint8_t*>(data);
  buffer_.insert(buffer_.end(), p, p + bytes);
  XXH3_64bits_update(&checksum_->state, data, bytes);
  content_bytes_ += bytes;
}

void SpillWriter::flush(bool release) {
  if (!buffer_.empty()) {
    std::FILE* f = std::fopen(path_.string().c_str(), "ab");
    if (!f) ioFail(path_, "cannot open");
    bool ok = std::fwrite(buffer_.data(), 1, buffer_.size(), f) == buffer_.size();
    if (std::fclose(f) != 0 || !ok) ioFail(path_, "cannot write");
    bytes_written_ += buffer_.size();
    buffer_.clear();
  }
  if (release) buffer_.shrink_to_fit();
}

void SpillWriter::finish() {
  SpillTrailer trailer{kTrailerMagic, 0, records_, content_bytes_,
                       XXH3_64bits_digest(&checksum_->state)};
  append(&trailer, sizeof trailer);
  content_bytes_ -= sizeof trailer;
  flush(true);
}

struct SpillReader::Checksum {
  XXH3_state_t state;
};

SpillReader::SpillReader(const std::filesystem::path& path, SpillKind kind)
    : reader_(path), checksum_(std::make_unique<Checksum>()) {
  if (reader_.size() < sizeof(SpillHeader) + sizeof(SpillTrailer))
    reader_.fail("spill file too short (" + std::to_string(reader_.size()) + " bytes)");
  auto header = reader_.readValue<SpillHeader>();
  if (header.magic != kSpillMagic) reader_.failAt(0, "not a spill file (bad magic)");
  if (header.version != kSpillVersion)
    reader_.failAt(4, "unsupported spill version " + std::to_string(header.version));
  if (header.kind != static_cast<uint32_t>(kind))
    reader_.failAt(8, "spill file of kind " + std::to_string(header.kind) + ", expected " +
                          std::to_string(static_cast<uint32_t>(kind)));
  if (header.reserved != 0) reader_.failAt(12, "reserved header field is not zero");
  const uint64_t trailer_at = reader_.size() - sizeof(SpillTrailer);
  reader_.seek(trailer_at);
  const auto trailer = reader_.readValue<SpillTrailer>();
  if (trailer.magic != kTrailerMagic)
    reader_.failAt(trailer_at, "missing trailer (truncated or unfinished spill file)");
  if (trailer.reserved != 0) reader_.failAt(trailer_at + 4, "reserved trailer field is not zero");
  if (trailer.content_bytes != trailer_at - sizeof(SpillHeader))
    reader_.failAt(trailer_at, "trailer says " + std::to_string(trailer.content_bytes) +
                                   " content bytes, file holds " +
                                   std::to_string(trailer_at - sizeof(SpillHeader)));
  record_count_ = trailer.record_count;
  expected_checksum_ = trailer.checksum;
  reader_.seek(sizeof(SpillHeader));
  XXH3_64bits_reset(&checksum_->state);
}

SpillReader::~SpillReader() = default;

uint64_t SpillReader::contentRemaining() const {
  return reader_.size() - sizeof(SpillTrailer) - reader_.offset();
}

void SpillReader::read(void* out, size_t bytes) {
  if (bytes > contentRemaining()) reader_.fail("record runs past the end of the content");
  reader_.read(out, bytes);
  XXH3_64bits_update(&checksum_->state, out, bytes);
}

void SpillReader::finish() {
  if (contentRemaining() != 0) reader_.fail("unexpected bytes after the last record");
  if (XXH3_64bits_digest(&checksum_->state) != expected_checksum_)
    reader_.failAt(sizeof(SpillHeader), "checksum mismatch (damaged spill file)");
}

}  // namespace tw
