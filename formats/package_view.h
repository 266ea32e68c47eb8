// PackageView: a .twk package opened for reading, with every record validated.
//
// open() reads the header, the section table and every table section into memory and checks,
// before anything is used: magic, version, struct sizes, header checksum, the section table
// (aligned, inside the file, non-overlapping, sizes matching record counts), the checksum of every
// table section, and every cross-reference (cluster -> group, page and object range; page -> page
// data; object -> layer and strings; instance -> object and profile points; layer -> strings)
// plus the LOD invariants, and the visibility section when there is one (visibility_section.h;
// its ids must be mesh clusters). After a successful open the spans below are safe to index with
// any index the records contain.
//
// Copy-on-read, not a mapping: the tables are copies made at open, and each page is read from the
// open file (pread) when it is loaded, its checksum checked. So a package truncated, overwritten
// in place or replaced while a viewer has it open never crashes it (a mapping would take SIGBUS on
// a page past the new end, and could see validated tables change): the tables stay as validated,
// a page that cannot be read whole, or no longer matches its checksum, is a FormatError at its
// offset, and a package replaced by a rename (as `preprocess` writes) keeps being read from the
// file that was opened. docs/reliability.md, "Faults".
//
// Verify::Headers (the default) leaves the page data unread, so opening a package of many GB costs
// a pass over its tables only; each page's checksum is then checked by readPage when it is loaded.
// Verify::All also checks the page data checksum, every page checksum, decompresses and decodes
// every cluster and compares it with its record, and requires the gaps between sections to be
// zero, so any changed byte is caught (`terawalk verify` uses it).
//
// Every failure throws FormatError::atByte(file, offset, reason). The view owns the open file and
// the tables; it is move-only, and spans it hands out live as long as it does. Page reads may run
// on several threads at once.
#pragma once

#include <cstdint>
#include <filesystem>
#include <glm/glm.hpp>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "format_error.h"
#include "package_format.h"
#include "page_codec.h"
#include "visibility_section.h"

namespace tw {

// XXH3-64 of a header (its header_checksum field read as 0) followed by its section table: the
// value PackageHeader::header_checksum holds. Exposed for the writer and for tests that patch
// headers.
uint64_t packageHeaderChecksum(const pkg::PackageHeader& header,
                               std::span<const pkg::SectionEntry> table);
// XXH3-64 (seed 0) of a section's bytes: the value SectionEntry::checksum holds.
uint64_t packageSectionChecksum(std::span<const uint8_t> bytes);

class PackageView {
 public:
  enum class Verify { Headers, All };

  static PackageView open(const std::filesystem::path& path, Verify verify = Verify::Headers);

  PackageView(PackageView&& other) noexcept;
  PackageView& operator=(PackageView&& other) noexcept;
  PackageView(const PackageView&) = delete;
  PackageView& operator=(const PackageView&) = delete;
  ~PackageView();

  const std::string& fileName() const { return name_; }
  uint64_t fileBytes() const { return size_; }
  const pkg::PackageHeader& header() const { return header_; }
  const pkg::SectionEntry& section(pkg::SectionType type) const {
    return sections_[static_cast<uint32_t>(type)];
  }
  glm::dvec3 origin() const;
  double positionStepM() const { return header_.position_step_m; }

  std::span<const pkg::ClusterRecord> clusters() const { return clusters_; }
  std::span<const pkg::GroupRecord> groups() const { return groups_; }
  std::span<const pkg::PageRecord> pages() const { return pages_; }
  std::span<const pkg::InstanceRecord> instances() const { return instances_; }
  std::span<const glm::vec2> profilePoints() const { return profiles_; }
  std::span<const pkg::ObjectRecord> objects() const { return objects_; }
  std::span<const pkg::LayerRecord> layers() const { return layers_; }
  std::string_view strings() const { return strings_; }
  std::span<const uint8_t> visibility() const { return visibility_; }
  // The visibility section, validated at open (ids are mesh clusters of this package, the
  // candidate level is below level_count); empty() when the package has none.
  const VisibilityView& visibilityCells() const { return visibility_cells_; }

  // Strings of validated records (offsets were checked at open).
  std::string_view objectName(uint32_t object) const;
  std::string_view objectDbKey(uint32_t object) const;
  // The project database the preprocessor was told of, as stored (relative to the package's
  // folder unless absolute); empty when none.
  std::string_view databasePath() const;
  std::string_view layerName(uint32_t layer) const;

  // The stored (possibly compressed) bytes of a page, read from the file into `bytes`. Throws
  // FormatError when the file no longer holds them.
  std::span<const uint8_t> pageStored(uint32_t page, std::vector<uint8_t>& bytes) const;
  // Reads the page, checks its checksum, then decompresses it if needed into `raw` (resized to
  // raw_bytes). Throws FormatError at the page's file offset when it cannot be read whole, on a
  // checksum or on a decompression failure.
  void readPage(uint32_t page, std::vector<uint8_t>& raw) const;
  // As readPage, returning the raw bytes, which are in `scratch` (valid until scratch changes).
  std::span<const uint8_t> loadPage(uint32_t page, std::vector<uint8_t>& scratch) const;
  // The whole section table, as read and validated at open.
  std::span<const pkg::SectionEntry> sectionTable() const { return sections_; }
  // Bytes [offset, offset + bytes) of the file, read now into `out` (the package check's pass
  // over every byte); throws FormatError when the file no longer holds them.
  void readFileBytes(uint64_t offset, uint64_t bytes, uint8_t* out) const;
  // XXH3-64 of the file's bytes [offset, offset + bytes), read now in chunks; throws as above.
  uint64_t fileChecksum(uint64_t offset, uint64_t bytes) const;

  // Decodes mesh cluster `cluster` from the raw bytes of its page (from readPage) and checks it
  // against its record. Throws FormatError on any mismatch or decoding failure.
  void decodeCluster(uint32_t cluster, std::span<const uint8_t> raw_page,
                     DecodedCluster& out) const;

 private:
  PackageView() = default;
  void validate(Verify verify);
  void validateHeader();
  void validateSectionTable();
  void verifySectionChecksums(Verify verify) const;
  void decompressSections();
  void mapSections();
  void validateNamedRecords() const;
  void validateInstances() const;
  void validatePages() const;
  void validateGroups() const;
  void validateClusters() const;
  uint64_t sectionTableEnd() const;
  void readSections();
  uint64_t pageFileOffset(uint32_t page) const;
  std::span<const uint8_t> storedSection(uint32_t index) const;  // as stored (maybe compressed)
  std::span<const uint8_t> sectionBytes(pkg::SectionType type) const;  // as read
  void verifyAll();
  void validateVisibility();
  [[noreturn]] void fail(uint64_t offset, const std::string& reason) const;
  // File offset of a byte of the header or of a record: inside a section read as stored, its own
  // offset; inside a section decompressed at open, the offset of that section's frame (the file
  // has no finer address).
  uint64_t offsetOf(const void* p) const;
  void release();

  std::string name_;
  int fd_ = -1;  // open for page reads
  uint64_t size_ = 0;
  pkg::PackageHeader header_{};
  std::vector<pkg::SectionEntry> sections_;  // copied: the table is small
  std::span<const pkg::ClusterRecord> clusters_;
  std::span<const pkg::GroupRecord> groups_;
  std::span<const pkg::PageRecord> pages_;
  std::span<const pkg::InstanceRecord> instances_;
  std::span<const glm::vec2> profiles_;
  std::span<const pkg::ObjectRecord> objects_;
  std::span<const pkg::LayerRecord> layers_;
  std::string_view strings_;
  std::span<const uint8_t> visibility_;
  VisibilityView visibility_cells_;  // spans into stored_ or decompressed_
  // Every section but the page data as stored in the file, read at open; and the sections stored
  // compressed (format 1.2) decompressed at open (empty for the others). The spans above point
  // into these, and a move keeps the vectors' buffers where they are.
  std::vector<std::vector<uint8_t>> stored_;
  std::vector<std::vector<uint8_t>> decompressed_;
};

}  // namespace tw
