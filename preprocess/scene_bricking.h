// Out-of-core bricking: the first stage of the preprocessor. It streams any number of input
// scenes twice and leaves their triangles binned into spatial bricks on disk, so that every later
// stage works on one brick in memory at a time and memory stays bounded by --memory-budget
// whatever the input size. Bricks are also the unit of resume (brick_cache.h).
//
// Pass 1, surveyScene: world bounds and counts, nothing kept.
// Pass 2, brickScene: chooses a double-precision package origin and a regular grid whose expected
//   triangles per cell (uniform density) are <= the brick limit; streams every mesh and NURBS
//   triangle (transformed to world in double, stored relative to the origin as float) into the
//   spill file of the cell holding its centroid, through small per-brick write buffers with a
//   global cap. Cells that still hold more than the limit (dense areas) are split by streaming
//   passes over just their file (halving the centroid bounds along the longest axis) until no
//   brick exceeds the limit. Parametric primitives are not tessellated: they go to a spill file
//   as (object, primitive, transform) records. Objects go to a spill file in order of first
//   appearance with dense indices 0..N-1; layers of all inputs are merged by name.
//
// Memory of pass 2: write buffers of at most max(budget / 8 (at least 64 KiB), 1 KiB per grid cell
// (<= 16 MiB)), 1 MiB for each side file, about 65 bytes per object (per-object bounds, and the id
// map of the current input), and the largest single object part (readers split big meshes). The
// splitting passes hold 1 MiB per output file. No brick is ever held whole in memory here.
//
// Spill files are our own format (header, records, trailer with count and XXH3 checksum); they are
// read back with FileReader and a truncated or damaged file (a run killed while writing) throws
// FormatError. Output depends only on the inputs and the options, never on timing or hash order.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "bounds.h"
#include "progress.h"
#include "read_options.h"
#include "scene.h"
#include "tessellate.h"
#include "up_axis.h"

namespace tw {

struct BrickingOptions {
  std::filesystem::path work_dir;  // spill files go here (created if missing); caller removes it
  uint64_t memory_budget_bytes = 2ull << 30;
  // 0: derived from the budget, about budget / 400 bytes, clamped to [64K, 4M] (a brick's later
  // in-memory build needs a few hundred bytes per triangle).
  uint64_t max_brick_triangles = 0;
  float nurbs_tolerance = kDefaultChordalTolerance;  // chordal, scene units
  // Triangle vertices are stored on this grid (metres, relative to the origin; 0: as computed).
  // The package's base position step: vertices of touching parts that differ by float noise (a
  // pipe's end and its elbow's, one ulp apart) become one position, so a brick's DAG and the
  // brick seams see them as one vertex, as the package will store them (grid_weld.h).
  double position_step_m = 0.0;
  Progress* progress = nullptr;
  std::vector<std::string> exclude_layers;  // objects of these layers are left out (by name)
  UpAxis up = UpAxis::Auto;                 // the inputs' up axis (ReadOptions::up)
  CadOptions cad;                           // ReadOptions::cad
};

// The brick limit actually used for `options` (resolves max_brick_triangles == 0).
uint64_t effectiveMaxBrickTriangles(const BrickingOptions& options);

// The smallest brick a budget-derived brick size goes down to.
constexpr uint64_t kMinBrickTriangles = 64 * 1024;

// Pass 1 result. Counts are summed over all inputs.
struct SceneSurvey {
  Aabb bounds;           // world bounds of all geometry (primitives: transformed local box)
  Aabb triangle_bounds;  // world bounds of mesh triangles and NURBS control hulls
  uint64_t mesh_triangles = 0;
  uint64_t nurbs_triangles = 0;  // tessellated at the survey's tolerance
  uint64_t primitives = 0;       // parametric objects (parts), not tessellated
  uint64_t objects = 0;          // distinct (input, object id) pairs
  uint64_t input_bytes = 0;      // sum of the input file sizes
  uint64_t triangles() const { return mesh_triangles + nurbs_triangles; }
};

// Reads every input with readScene. Throws FormatError for unreadable input,
// std::runtime_error("cancelled") when `progress` asks to stop. vertex_memory_bytes and
// spill_dir: ReadOptions' (a reader creates spill_dir when it first spills).
SceneSurvey surveyScene(const std::vector<std::filesystem::path>& inputs,
                        float nurbs_tolerance = kDefaultChordalTolerance,
                        Progress* progress = nullptr,
                        const std::vector<std::string>& exclude_layers = {},
                        UpAxis up = UpAxis::Auto, const CadOptions& cad = {},
                        uint64_t vertex_memory_bytes = 0,
                        const std::filesystem::path& spill_dir = {});

// The share of the memory budget a mesh reader may keep its vertex table in before it spills
// them to the work folder (ReadOptions::vertex_memory_bytes): an eighth.
constexpr uint64_t readerVertexBytes(uint64_t memory_budget_bytes) {
  return memory_budget_bytes / 8;
}

// One non-empty brick. Brick files live in BrickedScene::work_dir.
struct BrickInfo {
  uint32_t index = 0;
  glm::vec3 bounds_min{0.0f};  // bounds of the brick's triangles, relative to the origin
  glm::vec3 bounds_max{0.0f};
  uint64_t triangle_count = 0;
  std::string file;  // file name inside work_dir
};

// Memory and I/O figures of a bricking run (not part of the deterministic output).
struct BrickingStats {
  uint64_t buffer_cap_bytes = 0;     // global cap on buffered spill bytes
  uint64_t peak_buffered_bytes = 0;  // largest total held in write buffers at any time
  uint64_t flushes = 0;
  uint64_t spill_bytes_written = 0;  // all spill files, split passes included
  uint32_t grid_cells = 0;           // cells of the initial grid
  uint32_t cells_split = 0;          // over-full bricks split by extra passes
  uint32_t split_passes = 0;         // streaming passes over brick files during splitting
  uint64_t object_table_bytes = 0;   // in-memory per-object state (id map and bounds)
};

struct BrickedScene {
  std::filesystem::path work_dir;
  glm::dvec3 origin{0.0};  // package origin (world, metres): positions are relative
  uint64_t max_brick_triangles = 0;
  glm::uvec3 grid{1u};             // initial grid cells per axis
  std::vector<BrickInfo> bricks;   // non-empty bricks, index == position
  std::vector<Layer> layers;       // merged by name, in order of first appearance
  std::string objects_file;        // object identities, in dense-index order
  std::string object_bounds_file;  // per-object bounds, same order
  uint64_t object_count = 0;
  std::string parametrics_file;
  uint64_t parametric_count = 0;
  uint64_t triangle_count = 0;  // sum over bricks
  uint64_t triangles_turned = 0;  // wound against their piece, reversed (consistent_winding.h)
  uint64_t triangles_repeated = 0;  // exact copies of another, dropped (repeated_triangles.h)
  // The largest vertex coordinate as the readers stored it, in metres: its distance from its
  // object's placement origin along an axis. A CAD export's noise is a float step of this (a
  // PLY written at 290 m is noisy at 3e-5 m), not of the world position (a part placed 7,000 km
  // from the world origin with small local coordinates is exact to micrometres).
  double stored_coordinate_extent = 0.0;
  BrickingStats stats;
};

// Pass 2. Reads the inputs again (they must not have changed since the survey) and writes spill
// files into options.work_dir, replacing any left there. Throws FormatError for unreadable
// input, std::runtime_error for I/O failure or cancellation.
BrickedScene brickScene(const std::vector<std::filesystem::path>& inputs, const SceneSurvey& survey,
                        const BrickingOptions& options);

// One brick in memory, ready to pass as DagInput: positions relative to the package origin,
// welded by exact position (first appearance order), three indices per triangle, one dense object
// index per triangle. Triangles keep their input order.
struct BrickMesh {
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;
  std::vector<uint32_t> triangle_object_ids;
  uint64_t triangleCount() const { return triangle_object_ids.size(); }
};

// Throws FormatError for a missing, truncated or damaged brick file (bad trailer, size or
// checksum, count different from the description) and std::out_of_range for a bad index.
BrickMesh loadBrick(const BrickedScene& scene, uint32_t brick);

// Cheap integrity check of every spill file the description names (header, trailer, size; with
// `full`, also every checksum). Returns false instead of throwing. For --resume.
bool verifyBrickedScene(const BrickedScene& scene, bool full);

// A merged object: the package object table is built from these.
struct BrickedObject {
  uint32_t index = 0;      // dense, 0..object_count-1
  uint32_t input = 0;      // which input file (position in the inputs list)
  uint32_t source_id = 0;  // ObjectInfo::id in that file
  uint32_t layer = 0;      // index into BrickedScene::layers
  uint32_t color_rgba = 0;
  std::string name;
  std::string db_key;
  glm::vec3 bounds_min{0.0f};  // relative to the origin; empty (min > max) if no geometry
  glm::vec3 bounds_max{0.0f};
  // Its mesh geometry bounds a solid seen from outside (closed_surface.h): it has some, and
  // every mesh piece passed. Back faces of its triangles may then be culled from outside.
  bool closed_surface = false;
};

// Streams the objects back in index order. Throws FormatError for damaged files.
void forEachObject(const BrickedScene& scene, const std::function<void(const BrickedObject&)>& fn);

// A parametric primitive, untessellated, with its world transform (double origin).
struct ParametricRecord {
  uint32_t object = 0;  // dense object index
  Primitive primitive;
  Transform transform;
};

// Streams parametric records back in input order, in batches of at most `batch_size`.
// Throws FormatError for damaged files.
void forEachParametricBatch(const BrickedScene& scene, size_t batch_size,
                            const std::function<void(std::span<const ParametricRecord>)>& fn);

}  // namespace tw
