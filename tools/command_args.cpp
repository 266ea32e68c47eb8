// Shared option parsers; see command_args.h.
#include "command_args.h"

#include <cctype>
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
  int w = 0, h = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%dx%d%c", &w, &h, &tail) != 2 || w < 1 || h < 1 || w > 16384 ||
      h > 16384) {
    std::string message = option;
    message.append(": expected WIDTHxHEIGHT such as 1280x720, got '").append(text).append("'");
    throw std::runtime_error(message);
  }
  width = w;
  height = h;
}

}  // namespace tw
