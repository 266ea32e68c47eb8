// The preprocessor as the steps a scheduler runs: the plan, one job per brick, the merge. Any
// number of processes on any machines sharing the work directory may run the brick jobs, in any
// order, each at most once or again: a brick's result is renamed into place when finished, so a
// killed job leaves nothing half-written and re-running a finished one is a no-op. The package
// the merge writes is byte-identical to runPreprocess's for the same inputs and options (the
// merge reads the bricks exactly as a resumed one-machine run does).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>

#include "preprocess_driver.h"
#include "preprocess_plan.h"

namespace tw {

// What a step takes besides its plan.
struct StepOptions {
  uint32_t threads = 0;          // 0: all cores
  Progress* progress = nullptr;
  std::filesystem::path output;  // the merge's package
  bool keep_work_dir = false;    // the merge removes the work directory unless this is set
};

// 1. Survey, bricking and seams into options.work_dir (empty: "<output>.work"), then the
// manifest. A finished bricking of the same inputs and options found there is reused, as are
// bricks already built.
PreprocessPlan planPreprocess(const PreprocessOptions& options);

struct BrickJobReport {
  uint32_t index = 0;
  bool already_built = false;  // a finished result was found: nothing done
  uint64_t triangles = 0;
  uint64_t clusters = 0;
  double seconds = 0.0;
  // The process's resident high-water mark from the job's start (reset then to what the process
  // held, so a rank that built bricks before reports at least that).
  uint64_t peak_rss_bytes = 0;
};

// 2. The brick jobs of a plan: the bricking and seams are read once, then any brick is built.
class PlannedBricks {
 public:
  // Throws std::runtime_error when the work directory's bricking is missing or damaged, or the
  // inputs changed since the plan.
  PlannedBricks(const PreprocessPlan& plan, const StepOptions& step);
  ~PlannedBricks();
  PlannedBricks(const PlannedBricks&) = delete;
  PlannedBricks& operator=(const PlannedBricks&) = delete;

  uint32_t count() const;
  // Throws std::invalid_argument for an index not in the plan.
  BrickJobReport build(uint32_t index);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// 3. The upper levels, the packing, the package at step.output and its visibility. Every brick
// must be built: the error names the missing ones and the command that builds them.
PreprocessReport mergePreprocess(const PreprocessPlan& plan, const StepOptions& step);

}  // namespace tw
