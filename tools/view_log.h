// What the viewer's tools say on stdout: one line per action, flushed at once, so a user sees it
// as it happens and a script's log (tests, demos) holds it before the window closes.
#pragma once

namespace tw {

void viewSay(const char* format, ...) __attribute__((format(printf, 1, 2)));

}  // namespace tw
