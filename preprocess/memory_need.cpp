// The input's memory floor and the check of --memory-budget against it (see memory_need.h).
#include "memory_need.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace tw {

namespace {

constexpr uint64_t kObjectBytes = 65 + 4;      // bricking table entry + its layer for the face search
constexpr uint64_t kInstanceBytes = 300;       // record + discs, holders and face keys
constexpr uint64_t kFixedBytes = kSmallestMemoryBudget;  // buffer and tail floors

// Tenths of a MiB, rounded up: a budget of the printed size is never short of the figure.
std::string mebibytes(uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f MiB",
                std::ceil(double(bytes) / double(1 << 20) * 10.0) / 10.0);
  return text;
}

}  // namespace

std::string MemoryNeed::explain() const {
  return "brick build " + mebibytes(brick_build_bytes) + " + objects " + mebibytes(object_bytes) +
         " + parametric instances " + mebibytes(instance_bytes) + " + buffers " +
         mebibytes(fixed_bytes);
}

MemoryNeed memoryNeed(uint64_t max_brick_triangles, uint64_t objects, uint64_t instances) {
  MemoryNeed need;
  need.brick_build_bytes = max_brick_triangles * kBrickBuildBytesPerTriangle;
  need.object_bytes = objects * kObjectBytes;
  need.instance_bytes = instances * kInstanceBytes;
  need.fixed_bytes = kFixedBytes;
  return need;
}

void requireMemoryBudget(uint64_t budget, const MemoryNeed& need) {
  if (budget >= need.total()) return;
  char given[32];
  if (budget < (1u << 20))
    std::snprintf(given, sizeof given, "%.1f KiB", double(budget) / 1024.0);
  else
    std::snprintf(given, sizeof given, "%.1f MiB", double(budget) / double(1 << 20));
  throw std::invalid_argument(std::string("--memory-budget ") + given +
                              " is below what this input needs: at least " +
                              mebibytes(need.total()) + " (" + need.explain() + ")");
}

}  // namespace tw
