// Instance flags that searches over the whole model find, run once by the preprocessor and stored
// in the package, so that the runtime reads them instead of searching the instance table at
// every start: sealed pipe runs (formats/sealed_pipe_runs.h; the search took about 0.4 s of the
// 50M plant's first frame) and box faces covered by another box (formats/covered_box_faces.h).
//
// Both searches join instances anywhere in the model, so they see all of them at once: one pass
// over the parametric stream makes each item's package-frame record (96 bytes, without profile
// points: neither search reads them), then the searches run over them. Memory: about 100 bytes
// per instance for the records plus the searches' own indexes; this is one of the terms that
// still grow with the input (docs/preprocess.md).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "covered_box_faces.h"
#include "parametric_external_sort.h"
#include "sealed_pipe_runs.h"

namespace tw {

struct InstanceFlagMarking {
  // By input item index: kInstanceSealedRun* and kInstanceCoveredFaces bits.
  std::vector<uint16_t> role_flags;
  SealedRunStats sealed;
  CoveredFaceStats covered;
};

// Streams `stream` once (package origin `origin`) and runs both searches over its items;
// `object_layers` holds each object's layer (covered faces pair only within one). Throws
// std::invalid_argument for an item the package format refuses, as addInstance would.
InstanceFlagMarking markInstanceFlags(const ParametricStream& stream, const glm::dvec3& origin,
                                      std::span<const uint32_t> object_layers);

}  // namespace tw
