// Which open tubes, cones and elbows belong to a sealed run: a chain of them joined end to end
// whose every remaining end is closed by a solid (a flange, a capped cylinder).
//
// Why: an open tube's inside can be seen through its ends, so the tessellated parametrics
// (parametric_instance_meshes.h) draw open tubes seen from beyond an end plane, and every elbow,
// with both faces, about half of the parametric triangles a plant walk rasterizes. In a pipe run
// the spools, elbows and reducers meet exactly and the run ends at flanges, so from anywhere
// outside the run's solids no ray reaches an inside wall without first crossing an outside one:
// a ray that enters a member through an end disc comes from the next member's inside (and
// before that through that member's wall or its other end) or from inside the solid that closes
// the end, which it entered through that solid's surface. The renderer may then cull the
// members' back faces, as long as the eye (and the near plane that could cut a member open) is
// outside every member and every closing solid of every sealed run.
// How: the end discs of every open tube, cone and partial torus whose transform is a rotation
// with one uniform scale (mirroring allowed) are indexed by grid cell (sorted cell keys). Two
// discs seal each other when their centres and radii agree within kJoinToleranceM and they face
// each other; a disc without a partner is closed when it lies wholly inside a capped cylinder or
// a box, and joins the run of an open cylinder whose solid holds it. Joined instances form runs
// (union-find); a run is sealed when all its discs are.
// Positions are the package frame's (InstanceRecord::origin), where one run's coordinates agree
// to float rounding.
// Who runs it: the preprocessor, once, storing the roles as instance flags
// (preprocess/parametrics/instance_flag_marking.h); the runtime only for packages without them.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "package_format.h"

namespace tw {

// Roles, per instance.
inline constexpr uint8_t kSealedRunMember = 1;  // open tube, cone or elbow of a sealed run
inline constexpr uint8_t kSealedRunCloser = 2;  // capped cylinder that closes a sealed run's end

// Ends that count as joined or closed may be this far apart (metres): float rounding of the
// package frame, far below a pixel of anything a walkthrough shows.
inline constexpr double kJoinToleranceM = 2e-4;

struct SealedRunStats {
  uint64_t open_parts = 0;      // open tubes, cones and partial tori with a usable transform
  uint64_t runs = 0;            // joined groups of them
  uint64_t sealed_runs = 0;
  uint64_t sealed_members = 0;  // instances marked kSealedRunMember
  uint64_t closers = 0;         // instances marked kSealedRunCloser
};

// One role byte per instance (0: neither).
std::vector<uint8_t> findSealedRuns(std::span<const pkg::InstanceRecord> instances,
                                    SealedRunStats* stats = nullptr);

// A role byte as instance flags (pkg::kInstanceSealedRunMember, kInstanceSealedRunCloser), the
// way packages marked kHeaderSealedRunsMarked store it, and back.
inline uint32_t sealedRunInstanceFlags(uint8_t role) {
  return ((role & kSealedRunMember) ? pkg::kInstanceSealedRunMember : 0u) |
         ((role & kSealedRunCloser) ? pkg::kInstanceSealedRunCloser : 0u);
}
inline uint8_t sealedRunRole(uint32_t instance_flags) {
  return uint8_t(((instance_flags & pkg::kInstanceSealedRunMember) ? kSealedRunMember : 0) |
                 ((instance_flags & pkg::kInstanceSealedRunCloser) ? kSealedRunCloser : 0));
}

}  // namespace tw
