// Whole-section zstd frames (section_codec.h).
#include "section_codec.h"

#include <zstd.h>

#include <new>
#include <stdexcept>

namespace tw {

SectionCompressor::SectionCompressor(uint64_t total_bytes, int level) : context_(ZSTD_createCCtx()) {
  if (!context_) throw std::runtime_error("zstd: cannot create a compression context");
  auto check = [this](size_t result) {
    if (ZSTD_isError(result)) {
      ZSTD_freeCCtx(context_);
      throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(result));
    }
  };
  check(ZSTD_CCtx_setParameter(context_, ZSTD_c_compressionLevel, level));
  check(ZSTD_CCtx_setParameter(context_, ZSTD_c_checksumFlag, 0));  // the section has its own
  check(ZSTD_CCtx_setPledgedSrcSize(context_, total_bytes));
}

SectionCompressor::~SectionCompressor() { ZSTD_freeCCtx(context_); }

void SectionCompressor::run(std::span<const uint8_t> bytes, bool end) {
  ZSTD_inBuffer in{bytes.data(), bytes.size(), 0};
  const size_t step = ZSTD_CStreamOutSize();
  for (;;) {
    const size_t used = frame_.size();
    frame_.resize(used + step);
    ZSTD_outBuffer out{frame_.data() + used, step, 0};
    const size_t left = ZSTD_compressStream2(context_, &out, &in, end ? ZSTD_e_end : ZSTD_e_continue);
    frame_.resize(used + out.pos);
    if (ZSTD_isError(left)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(left));
    if (end ? left == 0 : in.pos == in.size) return;
  }
}

void SectionCompressor::add(std::span<const uint8_t> bytes) {
  if (!bytes.empty()) run(bytes, false);
}

std::vector<uint8_t> SectionCompressor::finish() {
  run({}, true);
  return std::move(frame_);
}

std::string decompressSection(std::span<const uint8_t> frame, uint64_t raw_bytes,
                              std::vector<uint8_t>& out) {
  const size_t frame_bytes = ZSTD_findFrameCompressedSize(frame.data(), frame.size());
  if (ZSTD_isError(frame_bytes))
    return std::string("is not a zstd frame (") + ZSTD_getErrorName(frame_bytes) + ")";
  if (frame_bytes != frame.size())
    return "holds " + std::to_string(frame.size() - frame_bytes) + " bytes after its zstd frame";
  const unsigned long long content = ZSTD_getFrameContentSize(frame.data(), frame.size());
  if (content == ZSTD_CONTENTSIZE_ERROR || content == ZSTD_CONTENTSIZE_UNKNOWN)
    return "zstd frame does not record its size";
  if (content != raw_bytes)
    return "zstd frame holds " + std::to_string(content) + " bytes, the table says " +
           std::to_string(raw_bytes);
  try {
    out.resize(raw_bytes);
  } catch (const std::bad_alloc&) {
    return "cannot allocate " + std::to_string(raw_bytes) + " bytes to decompress it";
  } catch (const std::length_error&) {
    return "cannot allocate " + std::to_string(raw_bytes) + " bytes to decompress it";
  }
  const size_t got = ZSTD_decompress(out.data(), out.size(), frame.data(), frame.size());
  if (ZSTD_isError(got)) return std::string("zstd frame is corrupt (") + ZSTD_getErrorName(got) + ")";
  if (got != raw_bytes)
    return "zstd frame decompressed to " + std::to_string(got) + " bytes, expected " +
           std::to_string(raw_bytes);
  return {};
}

}  // namespace tw
