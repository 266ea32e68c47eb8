// The viewer's lines on stdout (view_log.h).
#include "view_log.h"

#include <cstdarg>
#include <cstdio>

namespace tw {

void viewSay(const char* format, ...) {
  va_list args;
  va_start(args, format);
  std::vprintf(format, args);
  va_end(args);
  std::fflush(stdout);
}

}  // namespace tw
