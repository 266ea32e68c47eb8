// What a soak test watches over a long render (`render --soak-interval S`): resident memory,
// the pager's queues, evictions, loads and frame times, as one row per S seconds of wall time,
// appended to a CSV as each interval closes. Its memory does not grow with the run's length
// (the per-frame log of an ordinary render does), so a flat RSS is the renderer's own.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "frame_stats.h"

namespace tw {

class SoakLog {
 public:
  // Creates (truncates) `csv` and writes its header. Throws std::runtime_error if it cannot.
  SoakLog(const std::filesystem::path& csv, double interval_s);
  ~SoakLog();
  SoakLog(const SoakLog&) = delete;
  SoakLog& operator=(const SoakLog&) = delete;

  // Adds a rendered frame; closes the interval (writes its row) once its time is up.
  void add(const FrameStats& frame);
  // Writes the last, partial interval, if it holds a frame.
  void finish();
  uint64_t intervals() const { return intervals_; }
  uint64_t frames() const { return frames_; }
  uint64_t peakRssBytes() const { return peak_rss_; }

 private:
  using Clock = std::chrono::steady_clock;
  void writeRow();

  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  double interval_s_;
  Clock::time_point start_, interval_end_;
  uint64_t intervals_ = 0, frames_ = 0, peak_rss_ = 0;
  // The open interval.
  std::vector<double> frame_ms_;  // cleared, not freed: its capacity settles
  std::vector<uint64_t> triangles_;
  FrameStats last_;
  uint64_t rss_max_ = 0, gpu_max_ = 0, host_max_ = 0;
  uint32_t requested_max_ = 0, loading_max_ = 0, ready_max_ = 0;
  uint64_t loaded_ = 0, evicted_ = 0, eviction_frames_ = 0, waiting_for_pool_ = 0,
           fallback_frames_ = 0;
};

}  // namespace tw
