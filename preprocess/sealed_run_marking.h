// Sealed pipe runs (formats/sealed_pipe_runs.h) found once, by the preprocessor, and stored as
// instance flags, so that the runtime reads them instead of searching the whole instance table
// at every start (about 0.4 s of the 50M plant's first frame).
//
// The search joins instances anywhere in the model, so it sees all of them at once: one pass over
// the parametric stream makes each item's package-frame record (96 bytes, without profile points:
// the search reads none), then the search runs over them. Memory: about 100 bytes per instance
// for the records plus the search's own discs and holders; this is one of the terms that still
// grow with the input (docs/preprocess.md).
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "parametric_external_sort.h"
#include "sealed_pipe_runs.h"

namespace tw {

struct SealedRunMarking {
  std::vector<uint8_t> role_flags;  // by input item index: kInstanceSealedRun* bits
  SealedRunStats stats;
};

// Streams `stream` once (package origin `origin`) and searches its items for sealed runs. Throws
// std::invalid_argument for an item the package format refuses, as addInstance would.
SealedRunMarking markSealedRuns(const ParametricStream& stream, const glm::dvec3& origin);

}  // namespace tw
