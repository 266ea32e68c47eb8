// The plan of a preprocessing run split into steps a scheduler runs: `plan` (survey, bricking,
// seams), one `brick` job per brick, and `merge` (upper levels, packing, the package). The plan
// step writes this manifest into the work directory; every later step reads its inputs and
// options from it, so a brick job or the merge needs nothing but the work directory.
//
// Why a file and not arguments: brick jobs run as separate processes (MPI ranks, Slurm array
// tasks, a person re-running one by hand), possibly on other machines sharing the work folder.
// Each must build exactly what the one-machine run builds; the run hash in the manifest, checked
// again by every step against the inputs as they are then, catches an input changed since the
// plan.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "preprocess_driver.h"

namespace tw {

// One brick's job: its index (the `brick --index` argument) and the work it takes.
struct BrickJob {
  uint32_t index = 0;
  uint64_t triangles = 0;  // the brick's input triangles: its expected cost
};

struct PreprocessPlan {
  // Everything that decides the package, as `plan` was given it; inputs absolute. `output`,
  // `resume`, `keep_work_dir`, `threads` and `progress` are not part of a plan.
  PreprocessOptions options;
  uint64_t run_hash = 0;        // of the inputs and options (brick_cache.h RunHash)
  std::vector<BrickJob> jobs;   // largest first (ties by index): the order a scheduler hands out
  uint64_t input_triangles = 0;
  uint64_t primitives = 0;
  uint64_t objects = 0;
};

// "manifest.json" in the work directory.
std::filesystem::path planPath(const std::filesystem::path& work_dir);

// Written to a temporary name and renamed into place. Throws std::runtime_error on I/O failure.
void writePreprocessPlan(const PreprocessPlan& plan, const std::filesystem::path& work_dir);
// Throws std::runtime_error naming the file and the reason (missing: run `plan` first; damaged;
// of another version of the preprocessor).
PreprocessPlan readPreprocessPlan(const std::filesystem::path& work_dir);

}  // namespace tw
