// `terawalk preprocess --mpi`: the split preprocessor (preprocess_steps.h) run by Open MPI's
// ranks over a work directory they all share. Rank 0 plans; every rank builds bricks, asking
// rank 0 for the next one (largest first) when it has finished one; rank 0 merges once every
// brick is built. MPI carries only brick numbers and statuses: the bricks' results go through
// the shared work directory, as they do for Slurm array tasks and hand-run steps, so a run that
// loses a rank is finished by running the same command again.
#pragma once

#include <cstdint>
#include <functional>

#include "preprocess_driver.h"
#include "preprocess_steps.h"

namespace tw {

struct MpiPreprocessHooks {
  std::function<void(PreprocessPlan&)> before_merge;           // rank 0, before the merge
  std::function<void(const PreprocessReport&)> report;         // rank 0, after it
  std::function<void(const BrickJobReport&, uint32_t count, int rank)> brick;  // each brick
};

// Whether this terawalk was built with MPI.
bool haveMpi();

// Runs this rank's part and returns its exit status (0: the package is written). Errors are
// printed with the rank that met them; every rank returns non-zero when any step failed.
int runPreprocessOverMpi(const PreprocessOptions& options, const MpiPreprocessHooks& hooks);

}  // namespace tw
