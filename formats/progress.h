// Progress reporting and cancellation for long operations (reading, generating, preprocessing).
//
// Long operations take a Progress* (nullptr means "nobody is watching") and report work done in
// whatever unit suits them, usually bytes or triangles. The command line turns reports into a
// progress bar with an ETA; tests pass nullptr or a recorder.
#pragma once

#include <cstdint>
#include <string_view>

namespace tw {

class Progress {
 public:
  virtual ~Progress() = default;

  // Starts a named stage expecting `total` units of work (0 when unknown).
  virtual void beginStage(std::string_view name, uint64_t total) = 0;
  // Reports that `done` units of the current stage are complete (absolute, not a delta).
  virtual void update(uint64_t done) = 0;
  // Ends the current stage.
  virtual void endStage() = 0;
  // Long operations poll this and stop early, leaving no partial output, when it returns true.
  virtual bool cancelled() const { return false; }
};

// Small helpers so that callers need not check for nullptr at every report.
inline void beginStage(Progress* p, std::string_view name, uint64_t total) {
  if (p) p->beginStage(name, total);
}
inline void updateProgress(Progress* p, uint64_t done) {
  if (p) p->update(done);
}
inline void endStage(Progress* p) {
  if (p) p->endStage();
}

}  // namespace tw
