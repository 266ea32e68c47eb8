// Whole-section zstd frames: how the package stores its instance, profile, object and string
// tables compressed (package_format.h, format 1.2).
//
// Why: those tables are mostly repeated bytes. A pipe's 96-byte instance record is largely zeros,
// ones and values its neighbours share, and object records and names follow a few patterns, so
// zstd keeps a tenth to a quarter of them. That is what makes parametric piping more than ten
// times smaller than its triangles (docs/parametrics.md, "Memory"). The runtime reads these
// tables whole at start (or, for strings, only for picking), so the view decompresses them once
// at open and the records stay plain structs everywhere else.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

struct ZSTD_CCtx_s;

namespace tw {

// One frame, fed in pieces (a spilled table's chunks, then its in-memory tail). The total size
// is declared up front, so the frame header records it and the view can check it before it
// allocates.
class SectionCompressor {
 public:
  SectionCompressor(uint64_t total_bytes, int level);
  ~SectionCompressor();
  SectionCompressor(const SectionCompressor&) = delete;
  SectionCompressor& operator=(const SectionCompressor&) = delete;

  // Throws std::runtime_error with zstd's reason on failure.
  void add(std::span<const uint8_t> bytes);
  // Ends the frame and hands it over; add() may not be called afterwards.
  std::vector<uint8_t> finish();

 private:
  void run(std::span<const uint8_t> bytes, bool end);

  ZSTD_CCtx_s* context_ = nullptr;
  std::vector<uint8_t> frame_;
};

// Decompresses `frame`, which must be exactly one zstd frame holding exactly `raw_bytes`, into
// `out`. Returns an empty string on success, otherwise the reason (for the caller's error, which
// names the file and the section's offset).
std::string decompressSection(std::span<const uint8_t> frame, uint64_t raw_bytes,
                              std::vector<uint8_t>& out);

}  // namespace tw
