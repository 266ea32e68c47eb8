// The command line's Progress: a redrawn bar with an ETA on a terminal, one plain line per stage
// (and every few seconds) otherwise, nothing with --quiet.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>

#include "command.h"

namespace tw {
namespace {

using Clock = std::chrono::steady_clock;

std::string formatSeconds(double s) {
  char buf[32];
  if (s < 60) std::snprintf(buf, sizeof buf, "%.0fs", s);
  else if (s < 3600) std::snprintf(buf, sizeof buf, "%dm%02ds", int(s) / 60, int(s) % 60);
  else std::snprintf(buf, sizeof buf, "%dh%02dm", int(s) / 3600, (int(s) / 60) % 60);
  return buf;
}

class QuietProgress : public Progress {
 public:
  void beginStage(std::string_view, uint64_t) override {}
  void update(uint64_t) override {}
  void endStage() override {}
};

class TerminalProgress : public Progress {
 public:
  explicit TerminalProgress(bool tty) : tty_(tty) {}

  void beginStage(std::string_view name, uint64_t total) override {
    name_ = name;
    total_ = total;
    done_ = 0;
    start_ = Clock::now();
    last_draw_ = start_;
    if (!tty_) std::fprintf(stderr, "%s...\n", name_.c_str());
  }

  void update(uint64_t done) override {
    done_ = done;
    auto now = Clock::now();
    double since_draw = std::chrono::duration<double>(now - last_draw_).count();
    // Redraw at 10 Hz on a terminal; log every 5 s otherwise.
    if (since_draw < (tty_ ? 0.1 : 5.0)) return;
    last_draw_ = now;
    draw(false);
  }

  void endStage() override {
    done_ = total_ ? total_ : done_;
    draw(true);
  }

 private:
  void draw(bool final) {
    double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
    double fraction = total_ ? double(done_) / double(total_) : 0.0;
    if (fraction > 1.0) fraction = 1.0;
    std::string eta;
    if (final) eta = "done in " + formatSeconds(elapsed);
    else if (fraction > 0.01) eta = "ETA " + formatSeconds(elapsed / fraction - elapsed);
    else eta = formatSeconds(elapsed);
    if (tty_) {
      constexpr int kWidth = 30;
      int filled = static_cast<int>(fraction * kWidth);
      std::string bar(static_cast<size_t>(filled), '#');
      bar.resize(kWidth, '.');
      if (total_)
        std::fprintf(stderr, "\r%-24s [%s] %5.1f%%  %-16s", name_.c_str(), bar.c_str(),
                     fraction * 100.0, eta.c_str());
      else
        std::fprintf(stderr, "\r%-24s %llu  %-16s", name_.c_str(),
                     static_cast<unsigned long long>(done_), eta.c_str());
      if (final) std::fputc('\n', stderr);
    } else {
      if (total_)
        std::fprintf(stderr, "%s: %.1f%% %s\n", name_.c_str(), fraction * 100.0, eta.c_str());
      else
        std::fprintf(stderr, "%s: %llu %s\n", name_.c_str(),
                     static_cast<unsigned long long>(done_), eta.c_str());
    }
    std::fflush(stderr);
  }

  bool tty_;
  std::string name_;
  uint64_t total_ = 0;
  uint64_t done_ = 0;
  Clock::time_point start_;
  Clock::time_point last_draw_;
};

}  // namespace

std::unique_ptr<Progress> makeCommandProgress(const GlobalOptions& global) {
  if (global.quiet) return std::make_unique<QuietProgress>();
  return std::make_unique<TerminalProgress>(isatty(STDERR_FILENO) == 1);
}

}  // namespace tw
