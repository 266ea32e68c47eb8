// checkPackage: the deep consistency check behind `terawalk verify` (docs/verify.md).
//
// PackageView::open already rejects anything that would make reading unsafe (sizes, ranges,
// per-record invariants). This goes further, over a package opened with Verify::Headers, and
// checks what the runtime silently relies on, in this order:
//   checksums   header, every section, every page, zero padding: any changed byte is caught
//   references  group <-> cluster links both ways, page cluster counts, encoded ranges not
//               overlapping, header totals (level count, level-0 triangles, largest cluster)
//   sealed runs in a package marked kHeaderSealedRunsMarked, every instance's sealed-run flags
//               are what findSealedRuns finds (sealed_pipe_runs.h)
//   box faces   in a package marked kHeaderCoveredFacesMarked, every box's covered-face flags
//               are what findCoveredBoxFaces finds (covered_box_faces.h)
//   errors      monotone toward the roots, group records agreeing with their clusters, lod
//               spheres shared by siblings and growing toward the roots
//   bounds      every decoded vertex inside its cluster's box and sphere (and produced
//               clusters' inside their group's lod sphere), every instance's box inside its
//               cluster's box; cluster boxes inside their group's and the header's; level-0
//               triangles inside their object's box
//   decode      pages decompress, clusters decode and match their records
//   cracks      for every group of level L, the edges its children share with the rest of the
//               level-L front keep their triangle counts in the produced clusters (the locked
//               border is identical at both levels), and the produced clusters show no new
//               boundary edge
// It stops at the first failure and says which check, which record, and the numbers. Positions
// are compared within the quantization error of the clusters concerned (quantizationErrorM).
//
// Pure over the view: no I/O beyond reading the mapping, no globals. Memory: the crack check
// holds the decoded geometry of one front and the next level at a time (about 60 bytes per
// triangle: 231 MB peak for a 4M-triangle package); the other checks stream page by page.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "package_view.h"
#include "progress.h"

namespace tw {

struct CheckOptions {
  bool cracks = true;  // the crack-freedom check (the one that needs two levels in memory)
  // Extra allowance (metres) on top of the quantization error when two decoded positions are
  // taken to be the same vertex, and when containment of decoded geometry is tested.
  double position_slack_m = 0.0;
};

// The first thing that is wrong.
struct CheckFailure {
  std::string check;  // "checksums", "references", "sealed runs", "errors", "bounds", "decode",
                      // "cracks"
  std::string what;          // one line naming the record and the numbers
  uint64_t file_offset = 0;  // byte in the file the failure is about (0 when not meaningful)
  uint32_t cluster = pkg::kNone;  // the cluster concerned, or kNone
  uint32_t group = pkg::kNone;    // the group concerned, or kNone
  uint32_t page = pkg::kNone;     // the page concerned, or kNone
};

// What was checked, for the summary line.
struct CheckCounts {
  uint64_t checksums = 0;  // header + sections + pages whose checksum was recomputed
  uint64_t pages = 0;
  uint64_t clusters = 0;  // clusters checked (records, decoded geometry or instances)
  uint64_t groups = 0;
  uint64_t vertices = 0;  // decoded vertices tested against their bounds
  uint64_t instances = 0;
  uint64_t border_edges = 0;    // edges a group shares with its level, compared across levels
  uint64_t boundary_edges = 0;  // boundary edges of produced clusters found in their children
};

struct CheckReport {
  CheckCounts counts;
  std::optional<CheckFailure> failure;  // empty: every check passed
  bool cancelled = false;               // progress->cancelled() stopped it early
  bool ok() const { return !failure && !cancelled; }
};

// Runs every check in the order above over `view`, reporting each stage to `progress` (may be
// nullptr). Never throws for bad data: a FormatError from reading a page becomes the failure.
CheckReport checkPackage(const PackageView& view, const CheckOptions& options = {},
                         Progress* progress = nullptr);

}  // namespace tw
