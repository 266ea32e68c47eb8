// .bcfzip archives: the zip (through libzip) around BCF's documents, read into the topic model
// and written from it as BCF 2.1 or 3.0.
//
// Reading is for files other tools wrote: an archive that is not a readable zip is an error
// naming the file and libzip's reason; an item that cannot be taken (a markup or visualisation
// that does not parse, a reference to an entry the archive lacks, a snapshot over the size limit,
// a damaged entry) is skipped with a warning naming the entry and why, and the rest is read.
// Nothing is extracted to disk. Writing goes to a temporary file renamed over the target, so a
// failure leaves what was there before.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "bcf_topics.h"

namespace tw::bcf {

struct ReadLimits {
  uint64_t max_xml_bytes = 16ull << 20;       // a markup or visualisation document
  uint64_t max_snapshot_bytes = 32ull << 20;  // a snapshot image
  uint64_t max_entries = 200000;
};

// Throws FormatError when the archive cannot be opened as a zip, or none of its topics can be
// read while it has some; appends a line to `warnings` for each item skipped.
Archive readArchive(const std::filesystem::path& path, std::vector<std::string>& warnings,
                    const ReadLimits& limits = {});

// Writes every topic, viewpoint (with its snapshot) and comment; `notes` gets what the version
// cannot say (bcf_xml.h). Throws std::runtime_error naming the file when it cannot be written.
void writeArchive(const std::filesystem::path& path, const Archive& archive, Version version,
                  std::vector<std::string>& notes);

// Width / height of a PNG from its header; 0 when the bytes are not a PNG.
double pngAspectRatio(const std::vector<uint8_t>& png);

}  // namespace tw::bcf
