// Shared option parsers; see command_args.h.
#include "command_args.h"

#include <cctype>
#include <charconv>
#include <cstdio>
#include <stdexcept>

namespace tw {

uint64_t parseByteSize(const std::string& text, const std::string& option) {
  size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  std::string suffix = text.substr(used);
  for (char& c : suffix) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  double scale = 0.0;
  if (suffix.empty() || suffix == "B") scale = 1.0;
  else if (suffix == "K" || suffix == "KB" || suffix == "KIB") scale = 1024.0;
  else if (suffix == "M" || suffix == "MB" || suffix == "MIB") scale = 1024.0 * 1024.0;
  else if (suffix == "G" || suffix == "GB" || suffix == "GIB") scale = 1024.0 * 1024.0 * 1024.0;
  if (used == 0 || scale == 0.0 || !(value > 0.0) || value * scale > 1e15) {
    std::string message = option;
    message.append(": expected a size such as 2G or 512M, got '").append(text).append("'");
    throw std::runtime_error(message);
  }
  return static_cast<uint64_t>(value * scale);
}

void parseImageSize(const std::string& text, const std::string& option, int& width, int& height) {
  auto fail = [&](const std::string& why) {
    std::string message = option;
    message.append(": expected WIDTHxHEIGHT such as 1280x720, got '").append(text).append("'");
    if (!why.empty()) message.append(": ").append(why);
    throw std::runtime_error(message);
  };
  // Whole decimal numbers only: from_chars reports overflow instead of wrapping.
  const char* begin = text.data();
  const char* end = begin + text.size();
  uint64_t w = 0, h = 0;
  auto [after_w, w_error] = std::from_chars(begin, end, w);
  if (w_error != std::errc() || after_w == end || *after_w != 'x') fail("");
  auto [after_h, h_error] = std::from_chars(after_w + 1, end, h);
  if (h_error != std::errc() || after_h != end) fail("");
  if (w < 1 || h < 1 || w > uint64_t(kMaxImageSide) || h > uint64_t(kMaxImageSide))
    fail("each side must be 1 to " + std::to_string(kMaxImageSide) + " pixels");
  if (w * h > kMaxImagePixels)
    fail("at most " + std::to_string(kMaxImagePixels) + " pixels (8192x4096) are rendered");
  width = int(w);
  height = int(h);
}

}  // namespace tw
