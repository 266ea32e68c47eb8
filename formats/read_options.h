// Options common to every scene reader.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "progress.h"
#include "up_axis.h"

namespace tw {

// How the CAD importers turn a B-rep into the scene model; the defaults keep what they can.
struct CadOptions {
  // Solids that are primitives of the scene model stay primitives; false meshes everything (to
  // compare what keeping them saves).
  bool primitives = true;
  // The meshing's chordal tolerance in metres; 0: the importer's own rule.
  double tolerance_m = 0.0;
  // B-spline and Bézier faces by the conforming NURBS tessellator (STEP); false leaves them to
  // OpenCASCADE's own mesher, as a reference to compare against.
  bool conforming_bspline = true;
};

struct ReadOptions {
  Progress* progress = nullptr;  // reports bytes read; may be nullptr
  // Large meshes are handed to the sink in parts of at most this many triangles, so a reader's
  // memory stays bounded whatever the file size. Parts of one object share its ObjectInfo.
  uint32_t max_part_triangles = 1u << 16;
  // Objects of the layers with these names are left out (layer_filter_sink.h); the layer table
  // still lists them.
  std::vector<std::string> exclude_layers;
  // The file's up axis (up_axis.h); readScene turns Y-up files Z up. Auto: Y for glTF, Z for
  // everything else.
  UpAxis up = UpAxis::Auto;
  // What the CAD importers (STEP, IFC) keep and how they mesh the rest.
  CadOptions cad;
  // Where a reader reports what it skipped and read on past ("file: entity #12: reason"): a
  // product whose geometry failed, an entity the file garbled. Empty: one line on stderr each.
  std::function<void(const std::string&)> warn;
  // Mesh readers keep every vertex until the last face that may use it (OBJ, PLY): past this
  // many bytes of them, the rest go to an unlinked temporary file in spill_dir and come back
  // through a cache (spilled_array.h). 0, or no spill_dir: all in memory.
  uint64_t vertex_memory_bytes = 0;
  std::filesystem::path spill_dir;
  // Where a CAD importer tells what it made that the scene does not show ("B-spline faces 189:
  // 84 tessellated conforming ..."). Empty: dropped.
  std::function<void(const std::string&)> note;
};

// Reports `message` through options.warn, or on stderr.
inline void readWarning(const ReadOptions& options, const std::string& message) {
  if (options.warn) options.warn(message);
  else std::fprintf(stderr, "warning: %s\n", message.c_str());
}

}  // namespace tw
