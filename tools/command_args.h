// Parsers for option values several verbs share (sizes in bytes, image sizes), with errors that
// name the option.
#pragma once

#include <cstdint>
#include <string>

namespace tw {

// "2G", "512M", "1.5GiB", "800000000" -> bytes (powers of 1024 for suffixes). Throws
// std::runtime_error naming `option` on anything else.
uint64_t parseByteSize(const std::string& text, const std::string& option);

// The largest image a verb renders: each frame holds colour, depth, ids and their read-back
// copies (about 22 bytes a pixel), so 16384x16384 would take 5.8 GB.
constexpr int kMaxImageSide = 16384;
constexpr uint64_t kMaxImagePixels = uint64_t(8192) * 4096;

// "1280x720" -> width, height (each side 1..kMaxImageSide, at most kMaxImagePixels in all).
// Throws std::runtime_error naming `option`.
void parseImageSize(const std::string& text, const std::string& option, int& width, int& height);

}  // namespace tw
