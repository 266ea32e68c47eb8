// Parametric clustering out of core. clusterPrimitives (parametric_clusters.h) sorts every
// primitive of the model in memory, which caps the model size at the memory budget: a
// billion-triangle plant has tens of millions of pipes. This produces the same clusters, in the
// same order, with the same instance and cluster records (byte for byte), while holding at most
// `memory_budget_bytes` of items: items are streamed twice (pass 1: the bounds of their box
// centres and the count per type; pass 2: keys), sorted in runs that fit the budget, written to
// run files in `work_dir`, and merged k ways into PackageStorage::addInstance /
// addParametricCluster.
//
// Disk: run files take about 90 bytes per item plus 8 per profile point (a merge of some of the
// runs briefly holds its inputs and its output). Time: about 1.5x the in-memory path for 2M items
// at a 16 MiB budget, runs in the page cache (pass 2 recomputes each box centre; runs are written
// and read once per merge level).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>

#include "package_writer.h"
#include "parametric_clusters.h"

namespace tw {

// Streams every item, in input order, to `sink` in batches; must give the same items each time
// it is called (it is called exactly twice; a second pass that differs in count or types throws
// std::invalid_argument). Exceptions it throws pass through (run files are removed).
using ParametricStream =
    std::function<void(const std::function<void(std::span<const ParametricItem>)>& sink)>;

struct ParametricSortOptions {
  // Run files go here (created if missing, only when a run is needed); they are removed after,
  // the directory is left. Must not be empty (std::invalid_argument), even when everything fits.
  std::filesystem::path work_dir;
  // Items + keys held at once while sorting, then read buffers + current items while merging;
  // at least 1 MiB. Not counted: the caller's batches, `storage` itself, a scratch copy of one
  // item, the items of the cluster being filled (at most max_per_cluster), and a few hundred
  // bytes per run.
  uint64_t memory_budget_bytes = 64ull << 20;
  uint32_t max_per_cluster = 256;           // as clusterPrimitives
  // By input item index: role flags for PackageStorage::addInstance (sealed runs, covered box
  // faces: instance_flag_marking.h), or empty for none. Another size throws std::invalid_argument.
  std::span<const uint16_t> instance_role_flags;
};

struct ParametricSortStats {
  uint64_t items = 0;
  uint32_t clusters = 0;
  uint32_t runs = 0;           // sorted runs written (0: everything fit, sorted in memory)
  uint64_t run_bytes = 0;      // bytes written to run files (intermediate merges included)
  uint32_t merges = 0;         // k-way merges of run files (0 without runs; 1: all in one merge)
  // Most bytes held at once by this function's own accounting: <= the budget, except when the
  // largest profiles (up to 512 KiB each) of two runs cannot share it.
  uint64_t peak_held_bytes = 0;
};

// Appends the instances and parametric clusters exactly as
//   addParametricClusters(items, clusterPrimitives(items, storage.origin, max_per_cluster),
//                         storage, instance_role_flags)
// would for the concatenation `items` of everything `stream` gives. Throws std::invalid_argument
// as those do (bad parameters, max_per_cluster 0; nothing is added then), and for a budget under
// 1 MiB or an empty work_dir; std::runtime_error on I/O failure (naming the file), FormatError
// (file and byte offset) for a run file damaged behind its back; run files are removed either way.
ParametricSortStats addParametricClustersOutOfCore(const ParametricStream& stream,
                                                   const ParametricSortOptions& options,
                                                   PackageStorage& storage);

}  // namespace tw
