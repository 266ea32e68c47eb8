// The smallest --memory-budget the preprocessor can keep to for a given input, from the survey's
// counts, so a budget that cannot be honoured stops the run at once with a message naming the
// budget it needs, instead of being quietly exceeded (docs/preprocess.md, "Memory").
//
// What the budget B bounds: the bricking's write buffers (B / 8), the brick being built (at most
// B / 400 triangles, a few hundred bytes each), resident brick DAGs (B / 8), table tails
// (B / 1024) and the parametric sort's runs (B / 8). What does not shrink with B: the smallest
// brick (64K triangles unless --brick-triangles says fewer), the bricking's per-object table and
// the per-instance records of the parametric searches. Those terms are the input's floor; the
// process's own code, libraries and thread stacks (78 MiB) and the visibility stage's ray-tracing
// structures (capped by its candidate triangle limit: up to 190 MiB) are the documented constant
// on top, 272 MiB (docs/preprocess.md, "Memory"). A mesh reader's vertex table takes B / 8 and
// spills the rest (ReadOptions::vertex_memory_bytes).
#pragma once

#include <cstdint>
#include <string>

namespace tw {

struct MemoryNeed {
  uint64_t brick_build_bytes = 0;  // the smallest brick this run can build, being built
  uint64_t object_bytes = 0;       // per-object tables (bricking, covered-face search)
  uint64_t instance_bytes = 0;     // per-instance records of the parametric searches
  uint64_t fixed_bytes = 0;        // write buffers' and tails' floors

  uint64_t total() const { return brick_build_bytes + object_bytes + instance_bytes + fixed_bytes; }
  std::string explain() const;  // "brick build 25.0 MiB + objects 1.2 MiB + ..."
};

// Bytes a brick build takes per triangle (measured: docs/preprocess.md, "Memory").
constexpr uint64_t kBrickBuildBytesPerTriangle = 400;

// max_brick_triangles: the run's brick size (explicit, or derived from the budget).
MemoryNeed memoryNeed(uint64_t max_brick_triangles, uint64_t objects, uint64_t instances);

// Throws std::invalid_argument naming the smallest budget when `budget` is below need.total().
void requireMemoryBudget(uint64_t budget, const MemoryNeed& need);

// Below this no input can be built (the buffers' floors): checked before any input is read.
constexpr uint64_t kSmallestMemoryBudget = 1ull << 20;

}  // namespace tw
