// Per-interval aggregates of a long render. See soak_log.h.
#include "soak_log.h"

#include <algorithm>
#include <stdexcept>

namespace tw {
namespace {

// The q-quantile (0..1) of `v`, reordering it; 0 for none.
template <typename T>
double quantile(std::vector<T>& v, double q) {
  if (v.empty()) return 0.0;
  const size_t k = std::min(v.size() - 1, size_t(q * double(v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(k), v.end());
  return double(v[k]);
}

}  // namespace

SoakLog::SoakLog(const std::filesystem::path& csv, double interval_s)
    : path_(csv), interval_s_(interval_s) {
  if (!(interval_s > 0.0)) throw std::runtime_error("--soak-interval must be above 0 seconds");
  file_ = std::fopen(csv.string().c_str(), "w");
  if (!file_) throw std::runtime_error(csv.string() + ": cannot write");
  std::fprintf(file_,
               "wall_s,frames,frame_ms_median,frame_ms_p99,frame_ms_max,triangles_median,"
               "rss_bytes,rss_max_bytes,gpu_bytes_max,host_bytes_max,pages_requested_max,"
               "pages_loading_max,pages_ready_max,pages_loaded,pages_evicted,"
               "frames_with_eviction,pages_waiting_for_pool,frames_with_fallback,"
               "page_load_errors\n");
  std::fflush(file_);
  start_ = Clock::now();
  interval_end_ = start_ + std::chrono::duration_cast<Clock::duration>(
                               std::chrono::duration<double>(interval_s_));
}

SoakLog::~SoakLog() {
  if (file_) std::fclose(file_);
}

void SoakLog::add(const FrameStats& f) {
  ++frames_;
  frame_ms_.push_back(f.frame_ms);
  triangles_.push_back(f.triangles_drawn + f.parametric_triangles);
  last_ = f;
  rss_max_ = std::max(rss_max_, f.rss_bytes);
  peak_rss_ = std::max(peak_rss_, f.rss_bytes);
  gpu_max_ = std::max(gpu_max_, f.gpu_bytes_used);
  host_max_ = std::max(host_max_, f.host_bytes_used);
  requested_max_ = std::max(requested_max_, f.pages_requested);
  loading_max_ = std::max(loading_max_, f.pages_loading);
  ready_max_ = std::max(ready_max_, f.pages_ready);
  loaded_ += f.pages_loaded;
  evicted_ += f.pages_evicted;
  eviction_frames_ += f.pages_evicted > 0;
  waiting_for_pool_ += f.pages_waiting_for_pool;
  fallback_frames_ += f.ancestor_fallbacks > 0;
  const Clock::time_point now = Clock::now();
  if (now < interval_end_) return;
  writeRow();
  while (interval_end_ <= now)
    interval_end_ += std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(interval_s_));
}

void SoakLog::finish() {
  if (!frame_ms_.empty()) writeRow();
}

void SoakLog::writeRow() {
  const double wall_s = std::chrono::duration<double>(Clock::now() - start_).count();
  const size_t n = frame_ms_.size();
  const double median = quantile(frame_ms_, 0.5), p99 = quantile(frame_ms_, 0.99),
               most = quantile(frame_ms_, 1.0), triangles = quantile(triangles_, 0.5);
  std::fprintf(file_,
               "%.3f,%zu,%.4f,%.4f,%.4f,%.0f,%llu,%llu,%llu,%llu,%u,%u,%u,%llu,%llu,%llu,%llu,%llu,"
               "%llu\n",
               wall_s, n, median, p99, most, triangles, (unsigned long long)last_.rss_bytes,
               (unsigned long long)rss_max_, (unsigned long long)gpu_max_,
               (unsigned long long)host_max_, requested_max_, loading_max_, ready_max_,
               (unsigned long long)loaded_, (unsigned long long)evicted_,
               (unsigned long long)eviction_frames_, (unsigned long long)waiting_for_pool_,
               (unsigned long long)fallback_frames_,
               (unsigned long long)last_.page_load_errors);
  if (std::fflush(file_) != 0) throw std::runtime_error(path_.string() + ": cannot write");
  ++intervals_;
  frame_ms_.clear();
  triangles_.clear();
  rss_max_ = gpu_max_ = host_max_ = 0;
  requested_max_ = loading_max_ = ready_max_ = 0;
  loaded_ = evicted_ = eviction_frames_ = waiting_for_pool_ = fallback_frames_ = 0;
}

}  // namespace tw
