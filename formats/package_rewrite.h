// Replacing one section of a finished package file, so a later preprocessing stage (visibility,
// computed from the written package) can add its section without rebuilding the rest.
//
// Why not keep everything in memory and write once: the visibility stage needs decoded geometry,
// which lives in the package's pages; reading it back through a PackageView and rewriting the
// file costs one sequential copy of the page data, and keeps the stages independent.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>

#include "package_format.h"

namespace tw {

// Rewrites `package` with section `type` holding `bytes` (a byte section: record_bytes 1; or a
// record section whose record size divides bytes.size()), every other section copied unchanged,
// offsets and checksums (section and header) recomputed, gaps zero. Writes `<package>.tmp` and
// renames it over the original on success, so the original is intact after any failure.
// Validates the input package first (PackageView::open, Verify::Headers). Throws FormatError for
// a bad package, std::invalid_argument for a bad type or size, std::runtime_error on I/O errors.
void replacePackageSection(const std::filesystem::path& package, pkg::SectionType type,
                           std::span<const uint8_t> bytes);

}  // namespace tw
