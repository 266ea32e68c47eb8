// Parsers for option values several verbs share (sizes in bytes, image sizes), with errors that
// name the option.
#pragma once

#include <cstdint>
#include <string>

namespace tw {

// "2G", "512M", "1.5GiB", "800000000" -> bytes (powers of 1024 for suffixes). Throws
// std::runtime_error naming `option` on anything else.
uint64_t parseByteSize(const std::string& text, const std::string& option);

// "1280x720" -> width, height (each 1..16384). Throws std::runtime_error naming `option`.
void parseImageSize(const std::string& text, const std::string& option, int& width, int& height);

}  // namespace tw
