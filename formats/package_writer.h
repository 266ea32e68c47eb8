// PackageStorage, the owning form of a package the preprocessor fills, and writePackage.
//
// The preprocessor appends records to the vectors (through the helpers where they exist), then
// writePackage lays the sections out (docs/package-format.md), compresses pages, checksums each
// section with XXH3-64 and writes everything to "<path>.tmp-<pid>", which it re-opens with
// PackageView (so the writer never produces a file its reader rejects) and renames onto `path`.
// Memory: by default everything is held in memory. spillPagesTo() streams each finished page,
// compressed, to a spill file, and spillTablesTo() streams the older records of the tables
// (clusters, groups, instances, profile points, objects, strings) to files as well, so a build's
// memory does not grow with the model; writePackage then copies the files into the package in
// chunks, continuing each section's checksum over what is still in memory.
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "package_format.h"
#include "page_codec.h"
#include "scene.h"

namespace tw {

// LOD placement of a cluster in the DAG (see pkg::ClusterRecord for the selection rule).
struct ClusterLod {
  uint32_t group = pkg::kNone;
  uint32_t parent_group = pkg::kNone;
  uint16_t level = 0;
  float error = 0.0f;                                           // metres
  float parent_error = std::numeric_limits<float>::infinity();  // metres; +inf for roots
  glm::vec4 lod_sphere{0.0f};         // center xyz, radius w; radius 0 = use the cluster's bounds
  glm::vec4 parent_lod_sphere{0.0f};  // radius 0 = use lod_sphere
};

// Fills a cluster record's LOD fields from `lod`; a zero-radius lod sphere falls back to the
// given sphere (normally the cluster's bounds) and a zero-radius parent sphere to the lod sphere.
void setClusterLod(pkg::ClusterRecord& record, const ClusterLod& lod,
                   const glm::vec3& fallback_center, float fallback_radius);

struct PackageWriteOptions {
  bool zstd = true;  // compress pages; a page that does not shrink is stored raw
  int zstd_level = 9;
  // Store the instance, profile, object and string tables as one zstd frame each (format 1.2,
  // section_codec.h) when that shrinks them; false writes them as they are, as 1.1 did. The
  // frames are built in memory before the file is written: about a tenth of those tables' size.
  bool compress_tables = true;
};

class PageSpill;   // package_writer.cpp: finished pages, compressed, in a file
class TableSpill;  // package_writer.cpp: the tables' older records, in files

struct PackageStorage {
  // Build constants copied into the header.
  glm::dvec3 origin{0.0};  // world metres; all floats are relative to it
  double position_step_m = pkg::kDefaultPositionStepM;
  uint32_t target_page_bytes = pkg::kDefaultTargetPageBytes;
  uint64_t input_hash = 0;  // XXH3-64 of inputs and options, caller's
  // The instances carry the sealed-run search's roles (addInstance's role flags): the header gets
  // kHeaderSealedRunsMarked. Left false, no instance may have them (writePackage refuses).
  bool sealed_runs_marked = false;
  // Likewise the covered box faces (kInstanceCoveredFaces): kHeaderCoveredFacesMarked.
  bool covered_faces_marked = false;
  // The project database's path as the header names it (addString'd by setDatabasePath).
  uint64_t database_path_offset = 0;
  uint32_t database_path_bytes = 0;

  std::vector<pkg::ClusterRecord> clusters;
  std::vector<pkg::GroupRecord> groups;
  std::vector<std::vector<uint8_t>> pages;  // raw bytes: encoded clusters, 16-aligned
  std::vector<pkg::InstanceRecord> instances;
  std::vector<glm::vec2> profile_points;
  std::vector<pkg::ObjectRecord> objects;
  std::vector<pkg::LayerRecord> layers;
  std::string strings;              // the string pool
  std::vector<uint8_t> visibility;  // reserved: empty in format 1.0

  // Appends bytes to the string pool (no deduplication); returns their offset.
  uint64_t addString(std::string_view text);
  // Names the project database (a path relative to the package's folder, or absolute) in the
  // header; throws std::invalid_argument when it is longer than a string may be.
  void setDatabasePath(std::string_view path);
  // Appends a layer / object record with its strings; returns its index. `aabb_*` are the
  // object's level-0 bounds relative to origin.
  uint32_t addLayer(const Layer& layer);
  // `flags`: pkg::ObjectFlags (kObjectClosedSurface); throws std::invalid_argument for unknown bits.
  uint32_t addObject(const ObjectInfo& info, const glm::vec3& aabb_min, const glm::vec3& aabb_max,
                     uint32_t flags = 0);

  // Copies an encoded cluster into the current page, opening a new page when the current one would
  // grow past target_page_bytes; fills record.page, page_offset and encoded_bytes.
  void placeEncodedCluster(std::span<const uint8_t> encoded, pkg::ClusterRecord& record);

  // Streams pages out of memory: from now on, each page is compressed with `options` (exactly as
  // writePackage would) and appended to the file `spill_path` (created or truncated) as soon as
  // the next page opens, so `pages` keeps only the open page. Page numbers in cluster records stay
  // global: page i is the i-th page ever opened (spilled pages first, then `pages`). writePackage
  // copies the spilled bytes in chunks and must get the same options. Call before any page exists
  // (throws std::logic_error otherwise); throws std::runtime_error on I/O failure. The caller owns
  // the spill file and removes it (it belongs in a work directory); copies of the storage share it.
  void spillPagesTo(const std::filesystem::path& spill_path, const PackageWriteOptions& options = {});
  uint32_t pageCount() const;  // spilled + in memory
  uint64_t spilledPageBytes() const;  // page-data bytes already in the spill file
  std::shared_ptr<PageSpill> spill;  // null unless spillPagesTo was called

  // Streams the tables out of memory: from now on `clusters`, `groups`, `instances`,
  // `profile_points`, `objects` and `strings` keep only their newest entries (about `tail_bytes`
  // each at most) and move older ones to files in `dir` (created if missing; the caller removes
  // it). Indices stay global: use the counts and readers below rather than the vectors' sizes.
  // Call before any record exists (throws std::logic_error otherwise; layers stay in memory);
  // throws std::runtime_error on I/O failure.
  void spillTablesTo(const std::filesystem::path& dir, uint64_t tail_bytes = 1u << 20);
  std::shared_ptr<TableSpill> tables;  // null unless spillTablesTo was called

  // Spilled + in memory.
  uint32_t clusterCount() const;
  uint32_t groupCount() const;
  uint32_t instanceCount() const;
  uint64_t profilePointCount() const;
  uint32_t objectCount() const;
  uint64_t stringBytes() const;
  // One record, wherever it is; throws std::out_of_range for a bad index.
  pkg::ClusterRecord clusterRecord(uint32_t index) const;
  pkg::InstanceRecord instanceRecord(uint32_t index) const;
  // Profile points [first, first + count) into `out` (replaced); throws std::out_of_range.
  void readProfilePoints(uint64_t first, uint32_t count, std::vector<glm::vec2>& out) const;
  // Append finished records; return their index.
  uint32_t appendCluster(const pkg::ClusterRecord& record);
  uint32_t appendGroup(const pkg::GroupRecord& record);

  // Encodes `geometry` (page_codec.h) with this package's step, places it in a page and appends
  // its cluster record with bounds from the decoded positions; returns the cluster index.
  // Throws std::invalid_argument on bad geometry.
  uint32_t addMeshCluster(const ClusterGeometryInput& geometry, const ClusterLod& lod,
                          bool optimize = true);

  // Appends `primitive`, placed by `transform` (its origin is world metres; stored relative to
  // this package's origin), as an instance of object index `object`, with its profile points;
  // returns the instance index. `role_flags`: kInstanceSealedRunMember / Closer (see
  // sealed_runs_marked), kInstanceCoveredFaces on a box (see covered_faces_marked). Throws
  // std::invalid_argument for parameters the format forbids and for other role bits.
  uint32_t addInstance(const Primitive& primitive, const Transform& transform, uint32_t object,
                       uint32_t role_flags = 0);
  // Appends a parametric cluster over instances [first_instance, first_instance + count), which
  // must share one primitive type, with bounds from their parameters; returns the cluster index.
  uint32_t addParametricCluster(uint32_t first_instance, uint32_t count, const ClusterLod& lod);
};

// Conservative box of an instance in the package frame (its parameters' local box, transformed).
void instanceBounds(const pkg::InstanceRecord& instance, std::span<const glm::vec2> profile_points,
                    glm::vec3& aabb_min, glm::vec3& aabb_max);

// What was written, for reports.
struct PackageWriteStats {
  uint64_t file_bytes = 0;
  uint64_t section_bytes[pkg::kSectionCount] = {};
  uint64_t page_raw_bytes = 0;  // before compression
};

// Writes `storage` to `path` atomically (temporary file, then rename). Throws
// std::invalid_argument when the storage is inconsistent (the check is PackageView's, with its
// reason), std::runtime_error on I/O failure; the temporary file is removed either way.
// The record addInstance would append for `primitive` placed by `transform` as object `object`
// in a package whose origin is `origin`, without its profile points (profile_first and
// profile_count 0): what whole-model passes over the instances (the sealed-run search) read.
// Throws std::invalid_argument as addInstance.
pkg::InstanceRecord placedInstanceRecord(const Primitive& primitive, const Transform& transform,
                                         uint32_t object, const glm::dvec3& origin);

PackageWriteStats writePackage(const PackageStorage& storage, const std::filesystem::path& path,
                               const PackageWriteOptions& options = {});

}  // namespace tw
