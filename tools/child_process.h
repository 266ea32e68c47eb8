// Runs another program as a child process and measures it the way a benchmark report needs:
// wall time, user and system CPU time and peak resident memory of that process alone (from
// wait4's rusage), with its stdout and stderr written to a log file.
//
// Why a child and not a call: `terawalk bench` measures preprocess and render runs one at a time;
// in one process their peak memories would add up and their threads would overlap.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace tw {

struct ChildResult {
  int exit_code = -1;  // 128 + signal when killed by a signal
  double wall_s = 0.0;
  double user_s = 0.0;
  double system_s = 0.0;
  uint64_t peak_rss_bytes = 0;
};

// Runs argv[0] (a path, not searched in PATH) with argv, stdout and stderr to `log` (created or
// truncated). Throws std::runtime_error when the log cannot be opened or the process cannot be
// started; a program that fails is reported through exit_code, not thrown.
ChildResult runChild(const std::vector<std::string>& argv, const std::filesystem::path& log);

// This executable's path (/proc/self/exe), so bench can run its sibling verbs.
std::filesystem::path selfExecutable();

}  // namespace tw
