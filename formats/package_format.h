// On-disk layout of the TeraWalk package (.twk), shared by its writer, its view and the runtime.
//
// docs/package-format.md is the normative spec; this header mirrors it field for field. Every
// struct is plain, fixed-width, little-endian and static_asserted for size, so the runtime reads
// the records in place from a read-only memory mapping (PackageView) and the preprocessor writes
// them from owning vectors (PackageStorage).
//
// Version history (kVersion.kMinorVersion):
//   1.0 (2026-11) first version: flat cluster DAG (Nanite-style: each cluster carries its own and
//       its parent group's error), groups, pages of meshopt-encoded clusters with optional zstd,
//       parametric instances, objects, layers, string pool, empty visibility section.
//   1.1 (2026-11) the visibility section filled: view cells with occluder sets and sampled
//       visible sets (visibility_section.h). 1.0 packages (empty section) stay valid.
//   1.2 (2026-11) the instance, profile, object and string sections may be stored as one zstd
//       frame each (SectionEntry::stored_bytes, which was reserved and 0 before). Earlier
//       packages stay valid; a 1.1 view rejects a compressed section (its reserved field).
//   1.3 (2026-11) ObjectRecord::flags (was reserved and 0): kObjectClosedSurface marks objects
//       whose mesh triangles bound a solid, so the runtime may cull their back faces. Earlier
//       packages stay valid (no object is marked); a 1.2 view rejects a marked object.
//   1.4 (2026-11) sealed pipe runs found by the preprocessor (sealed_pipe_runs.h): instance flags
//       kInstanceSealedRunMember and kInstanceSealedRunCloser, and header flag
//       kHeaderSealedRunsMarked saying the search ran (the runtime no longer runs it at start-up;
//       without the mark it still does). Earlier packages stay valid; a 1.3 view rejects them.
//   1.5 (2026-11) box faces covered by another box's face (covered_box_faces.h): instance flags
//       kInstanceCoveredFaces, and header flag kHeaderCoveredFacesMarked saying the search ran.
//       Earlier packages stay valid (nothing is marked); a 1.4 view rejects marked ones.
//   1.6 (2026-12) the project database's path (PackageHeader::database_path_*, in the string
//       pool; relative to the package's folder unless absolute), taken from two reserved fields;
//       ClusterRecord::flags kClusterFarProxy marks the clusters of far-proxy groups. Earlier
//       packages stay valid (no path, no cluster marked); a 1.5 view rejects a package that names
//       a database or marks a cluster.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>

namespace tw::pkg {

static_assert(std::endian::native == std::endian::little,
              ".twk is little-endian; the writer and the view use structs as they are");

// Bumped for incompatible changes; a view rejects any other version.
inline constexpr uint32_t kVersion = 1;
// Bumped for compatible additions (new sections appended to the table); informational.
inline constexpr uint32_t kMinorVersion = 6;

inline constexpr char kMagic[8] = {'T', 'W', 'P', 'A', 'C', 'K', 'G', '\0'};

// Every section starts at a multiple of this (a cache line), so records can be read in place.
inline constexpr uint64_t kSectionAlignment = 64;
// Encoded clusters start at multiples of this within a page's raw (decompressed) bytes.
inline constexpr uint32_t kClusterAlignment = 16;
inline constexpr uint64_t alignUp(uint64_t value, uint64_t alignment) {
  return (value + alignment - 1) / alignment * alignment;
}

// "No such index" for group, parent_group and page fields.
inline constexpr uint32_t kNone = 0xffffffffu;

// Limits a view enforces before it allocates anything from a count in the file.
inline constexpr uint32_t kMaxPageRawBytes = 16u << 20;  // one decompressed page
inline constexpr uint32_t kMaxClusterVertices = 65535;
inline constexpr uint32_t kMaxClusterTriangles = 65535;
inline constexpr uint32_t kMaxStringBytes = 65535;       // one name or database key
inline constexpr uint32_t kMaxProfilePoints = 1u << 16;  // one extrusion/revolution profile

// Accepted range of PackageHeader::position_step_m (keeps every decoded position finite).
inline constexpr double kMinPositionStepM = 1e-9;
inline constexpr double kMaxPositionStepM = 1.0;

// Defaults the writer uses when the caller does not choose (build constants, see PackageHeader).
inline constexpr double kDefaultPositionStepM = 1.0 / 65536.0;  // 15.3 um; +-32 km of int32 grid
inline constexpr uint32_t kDefaultTargetPageBytes = 128u << 10;

// Sections, in the order of the section table (entry i has type i). The file stores them in this
// order too, with page data last so that the resident tables form one contiguous prefix.
enum class SectionType : uint32_t {
  Clusters = 0,    // ClusterRecord[]
  Groups = 1,      // GroupRecord[]
  Pages = 2,       // PageRecord[] (the page table)
  Instances = 3,   // InstanceRecord[] (parametric primitives)
  Profiles = 4,    // float[2][] profile points of extrusion and revolution instances
  Objects = 5,     // ObjectRecord[]
  Layers = 6,      // LayerRecord[]
  Strings = 7,     // UTF-8 string pool, no terminators
  Visibility = 8,  // view cells and occluder sets (visibility_section.h); may be empty
  PageData = 9,    // stored (maybe compressed) pages, addressed by PageRecord
};
inline constexpr uint32_t kSectionCount = 10;

// The first 256 bytes of the file. The section table (section_count entries) follows at
// header_bytes. header_checksum covers the header (with header_checksum read as 0) and the table.
struct PackageHeader {
  char magic[8];                 // kMagic
  uint32_t version;              // kVersion
  uint32_t minor_version;        // kMinorVersion of the writer
  uint32_t header_bytes;         // sizeof(PackageHeader) == 256
  uint32_t section_entry_bytes;  // sizeof(SectionEntry) == 48
  uint32_t section_count;        // >= kSectionCount; entries past it are bounds-checked, ignored
  uint32_t flags;                // kHeaderSealedRunsMarked, kHeaderCoveredFacesMarked; a view
                                 // rejects bits it does not know
  uint64_t file_bytes;           // size of the whole file: a truncated file fails at once
  uint64_t input_hash;           // XXH3-64 of the inputs and options, from the preprocessor
  // Struct sizes, so a mismatched build fails loudly rather than misreading records.
  uint32_t cluster_record_bytes;          // 128
  uint32_t group_record_bytes;            // 64
  uint32_t page_record_bytes;             // 32
  uint32_t instance_record_bytes;         // 96
  uint32_t object_record_bytes;           // 64
  uint32_t layer_record_bytes;            // 16
  uint32_t encoded_cluster_header_bytes;  // 48
  uint32_t reserved0;                     // 0
  // Build constants.
  double origin[3];        // world position (metres) all float positions are relative to
  double position_step_m;  // base quantization step, metres, in [1e-9, 1]
  float bounds_min[3];     // of all geometry, relative to origin
  float bounds_max[3];
  uint32_t level_count;            // 1 + the largest cluster level
  uint32_t target_page_bytes;      // the packer's raw page target
  uint32_t max_cluster_triangles;  // largest triangle_count of any cluster
  uint32_t reserved1;              // 0
  uint64_t total_triangles;        // sum over level-0 mesh clusters (the input triangle count)
  // The project database (SQLite) the package's object keys refer to, in the string pool;
  // 0 bytes: none named. Relative to the package's folder unless absolute.
  uint64_t database_path_offset;
  uint32_t database_path_bytes;    // <= kMaxStringBytes
  uint32_t reserved3;              // 0
  uint64_t reserved2[9];           // 0
  uint64_t header_checksum;        // XXH3-64 of header (this field as 0) + section table
};
static_assert(sizeof(PackageHeader) == 256);
static_assert(offsetof(PackageHeader, origin) == 80 && offsetof(PackageHeader, level_count) == 136);
static_assert(offsetof(PackageHeader, header_checksum) == 248);

// PackageHeader::flags. Sealed runs marked: every instance's kInstanceSealedRun* bits are the
// search's result (sealed_pipe_runs.h), none set meaning "not in a sealed run"; without this bit
// the instances carry none and a reader that wants the roles searches itself.
inline constexpr uint32_t kHeaderSealedRunsMarked = 1u << 0;
// Covered box faces marked: every Box instance's kInstanceCoveredFaces bits are the search's
// (covered_box_faces.h).
inline constexpr uint32_t kHeaderCoveredFacesMarked = 1u << 1;
inline constexpr uint32_t kKnownHeaderFlags = kHeaderSealedRunsMarked | kHeaderCoveredFacesMarked;

// One entry of the section table.
struct SectionEntry {
  uint32_t type;          // SectionType; entry i has type i for i < kSectionCount
  uint32_t record_bytes;  // sizeof the section's record, or 1 for byte sections
  uint64_t offset;        // from the file start, multiple of kSectionAlignment
  uint64_t bytes;         // of the section's records: == count * record_bytes
  uint64_t count;         // records (bytes for byte sections)
  uint64_t checksum;      // XXH3-64 (seed 0) of the bytes the file stores (the frame, if any)
  // 0: the records are stored as they are, `bytes` at `offset`. Otherwise the file stores one
  // zstd frame of stored_bytes bytes at `offset` that decompresses to exactly `bytes` (1.2; only
  // sections for which sectionMayBeCompressed holds: the view decompresses them at open).
  uint64_t stored_bytes;
};
static_assert(sizeof(SectionEntry) == 48);

// Bytes a section occupies in the file.
inline constexpr uint64_t storedBytes(const SectionEntry& e) {
  return e.stored_bytes != 0 ? e.stored_bytes : e.bytes;
}

// Cluster kinds.
enum class ClusterKind : uint8_t { Mesh = 0, Parametric = 1 };

// One node of the LOD DAG. The DAG is stored flat (Nanite / meshopt clusterlod style): the
// runtime may test every cluster independently and draws it when
//   errorPx(error, lod_sphere) <= tau < errorPx(parent_error, parent_lod_sphere).
// A group is one simplification step: it replaces some clusters of level <= L (its children,
// whose parent_group it is) with the clusters of level L + 1 it produced (whose group it is).
// Siblings share error and lod sphere, and children carry their parent group's error and sphere,
// so every cluster of a group takes the same decision and the selected cut is crack-free.
// Invariants (checked by the view): 0 <= error <= parent_error; parent_error is +inf exactly for
// roots (parent_group == kNone); a produced cluster has level == group level + 1 and error ==
// group error; a child has level <= parent group level (equal except where merged brick roots of
// different depths share a group, see dag_merge.h) and parent_error == parent group error. So
// levels and errors grow strictly toward the roots and the DAG has no cycles. Positions are
// metres relative to PackageHeader::origin.
struct ClusterRecord {
  float center[3];  // bounding sphere of the decoded geometry (or instances)
  float radius;
  float aabb_min[3];  // box of the decoded geometry
  float error;        // object-space error of this cluster (its group's), metres
  float aabb_max[3];
  float parent_error;   // error of the parent group, metres; +inf for roots
  float lod_center[3];  // sphere the runtime projects `error` with (the group's)
  float lod_radius;
  float parent_lod_center[3];  // sphere the runtime projects `parent_error` with (parent group's)
  float parent_lod_radius;
  uint32_t group;           // group that produced this cluster, or kNone (level 0)
  uint32_t parent_group;    // group that simplifies this cluster, or kNone (root)
  uint16_t level;           // 0 = full resolution
  uint8_t kind;             // ClusterKind
  uint8_t flags;            // ClusterFlags (1.6; 0 before); a view rejects bits it does not know
  uint32_t page;            // Mesh: PageRecord index; Parametric: kNone
  uint32_t page_offset;     // Mesh: offset of the encoded cluster in the raw page (multiple of 16)
  uint32_t encoded_bytes;   // Mesh: bytes of the encoded cluster
  uint32_t triangle_count;  // Mesh
  uint32_t vertex_count;    // Mesh
  uint32_t object_min;      // smallest object index of any triangle/instance (< object count)
  uint32_t object_max;      // largest; object_min <= object_max
  uint32_t instance_first;  // Parametric: first InstanceRecord; Mesh: 0
  uint32_t instance_count;  // Parametric: instances, all of one primitive type; Mesh: 0
};
static_assert(sizeof(ClusterRecord) == 128);
static_assert(offsetof(ClusterRecord, group) == 80 && offsetof(ClusterRecord, page) == 92);

// ClusterRecord::flags. A far proxy: the cluster was made by a group that remeshed its free
// parts into one closed shell (preprocess/far_proxy.h), so its triangles stand for whole parts
// rather than simplify them; set on mesh clusters above level 0 only.
inline constexpr uint8_t kClusterFarProxy = 1u << 0;
inline constexpr uint8_t kKnownClusterFlags = kClusterFarProxy;

// One simplification step. The clusters it produced are stored contiguously in the cluster table
// (possibly none, when it dropped small parts), so the runtime can test a whole group (frustum,
// errorPx(error, lod sphere) > tau) before its clusters. Its children are the clusters whose
// parent_group it is.
struct GroupRecord {
  float lod_center[3];  // encloses the children's lod spheres and the produced clusters
  float lod_radius;
  float aabb_min[3];  // of the produced clusters (the children's when none)
  float error;        // of the produced clusters == parent_error of the children, metres
  float aabb_max[3];
  float max_parent_error;  // largest parent_error of a produced cluster (+inf if one is a
                           // root); == error when it produced none
  uint32_t first_cluster;  // produced clusters
  uint32_t cluster_count;  // may be 0; first_cluster + cluster_count <= cluster count
  uint32_t level;          // highest level of the children; produced clusters are level + 1
  uint32_t reserved;       // 0
};
static_assert(sizeof(GroupRecord) == 64);

enum class PageCodec : uint32_t { None = 0, Zstd = 1 };

// One geometry page: the streaming unit. Its raw bytes are the concatenation of encoded clusters
// (page_codec.h), each at a multiple of kClusterAlignment, zero padding in between.
struct PageRecord {
  uint64_t offset;         // of the stored bytes, from the start of the PageData section
  uint32_t stored_bytes;   // bytes in the file
  uint32_t raw_bytes;      // after decompression, <= kMaxPageRawBytes; == stored for None
  uint32_t codec;          // PageCodec
  uint32_t cluster_count;  // encoded clusters in the page (informational)
  uint64_t checksum;       // XXH3-64 of the stored bytes, checked by PackageView::readPage
};
static_assert(sizeof(PageRecord) == 32);

// Primitive types: the index of the alternative in tw::Primitive (scene.h).
enum class PrimitiveType : uint32_t {
  Cylinder = 0,
  Cone = 1,
  Sphere = 2,
  TorusSegment = 3,
  Box = 4,
  Extrusion = 5,
  Revolution = 6,
};
inline constexpr uint32_t kPrimitiveTypeCount = 7;
inline constexpr uint32_t kInstanceCapped = 1u << 0;  // Cylinder and Cone
// Roles in a sealed pipe run (sealed_pipe_runs.h; only with kHeaderSealedRunsMarked): an open
// tube, cone or elbow of the run, and a capped cylinder that closes one of its ends.
inline constexpr uint32_t kInstanceSealedRunMember = 1u << 1;
inline constexpr uint32_t kInstanceSealedRunCloser = 1u << 2;
// Faces of a box covered by another box's face (covered_box_faces.h; Box only, and only with
// kHeaderCoveredFacesMarked): bit 3 + f for face f of -X, +X, -Y, +Y, -Z, +Z.
inline constexpr uint32_t kInstanceCoveredFaceShift = 3;
inline constexpr uint32_t kInstanceCoveredFaces = 0x3fu << kInstanceCoveredFaceShift;
// The flags the preprocessor's searches set (PackageStorage::addInstance's role flags).
inline constexpr uint32_t kInstanceSearchedFlags =
    kInstanceSealedRunMember | kInstanceSealedRunCloser | kInstanceCoveredFaces;
inline constexpr uint32_t kKnownInstanceFlags = kInstanceCapped | kInstanceSearchedFlags;

// One parametric primitive, placed by an affine map from its canonical frame (scene.h) into the
// package frame. params by type (unused = 0), as in the .tws format:
//   Cylinder  radius, height                 Cone       radius_bottom, radius_top, height
//   Sphere    radius                         Torus      major_radius, minor_radius, sweep_rad
//   Box       half_extents x, y, z           Extrusion  height (profile >= 3 points)
//   Revolution sweep_rad (profile >= 2 (radius, z) points)
struct InstanceRecord {
  float origin[3];  // metres, relative to PackageHeader::origin
  float linear[9];  // column-major 3x3
  float params[6];
  uint32_t type;           // PrimitiveType
  uint32_t flags;          // kInstanceCapped, kInstanceSealedRunMember, kInstanceSealedRunCloser
  uint32_t object;         // ObjectRecord index
  uint32_t profile_first;  // first point in the Profiles section
  uint32_t profile_count;  // 0 except Extrusion and Revolution; <= kMaxProfilePoints
  uint32_t reserved;       // 0
};
static_assert(sizeof(InstanceRecord) == 96);

// One scene object. Triangles and instances refer to objects by their index in this table.
struct ObjectRecord {
  uint32_t id;             // the scene's object id (ObjectInfo::id)
  uint32_t layer;          // LayerRecord index
  uint32_t color_rgba;     // 0xAABBGGRR; 0 = the layer's colour
  uint32_t name_bytes;     // <= kMaxStringBytes
  uint64_t name_offset;    // in the string pool
  uint64_t db_key_offset;  // in the string pool
  uint32_t db_key_bytes;   // <= kMaxStringBytes; 0 = no database record
  uint32_t flags;          // ObjectFlags; a view rejects bits it does not know (0 before 1.3)
  float aabb_min[3];       // of the object's level-0 geometry, relative to origin
  float aabb_max[3];
};
static_assert(sizeof(ObjectRecord) == 64);

// ObjectRecord::flags.
// The object has mesh triangles, and all of them together bound a solid that faces outward
// (preprocess/closed_surface.h): from an eye outside its box, none of its back faces can show.
inline constexpr uint32_t kObjectClosedSurface = 1u << 0;
inline constexpr uint32_t kKnownObjectFlags = kObjectClosedSurface;

struct LayerRecord {
  uint64_t name_offset;  // in the string pool
  uint32_t name_bytes;   // <= kMaxStringBytes
  uint32_t color_rgba;   // 0xAABBGGRR
};
static_assert(sizeof(LayerRecord) == 16);

// Start of every encoded cluster in a raw page (page_codec.h). The three streams follow in order:
//   vertices  meshopt_encodeVertexBuffer of vertex_count EncodedVertex (8 bytes each)
//   indices   meshopt_encodeIndexBuffer (format version 1) of 3 * triangle_count indices
//   objects   uint32 object[run_count], then uint16 run_length[run_count]: triangles are sorted by
//             object, so run r covers the next run_length[r] triangles (sum == triangle_count)
// Position of vertex q: (grid_origin + q.xyz) * position_step_m * 2^shift, relative to origin.
struct EncodedClusterHeader {
  uint32_t magic;           // kEncodedClusterMagic
  uint16_t vertex_count;    // <= kMaxClusterVertices
  uint16_t triangle_count;  // <= kMaxClusterTriangles
  uint8_t flags;            // kEncodedHasNormals
  uint8_t shift;            // <= kMaxPositionShift
  uint16_t run_count;       // object runs, 1..triangle_count (0 only when no triangles)
  int32_t grid_origin[3];   // in units of position_step_m * 2^shift
  uint32_t vertex_stream_bytes;
  uint32_t index_stream_bytes;
  uint32_t object_stream_bytes;  // == align4(6 * run_count)
  uint32_t reserved[3];          // 0
};
static_assert(sizeof(EncodedClusterHeader) == 48);
inline constexpr uint32_t kEncodedClusterMagic = 0x4c435754;  // "TWCL"
inline constexpr uint8_t kEncodedHasNormals = 1u << 0;
inline constexpr uint8_t kMaxPositionShift = 30;

// Vertex as encoded (and as a GPU may consume it): quantized position, octahedral normal.
struct EncodedVertex {
  uint16_t q[3];  // grid units from grid_origin
  int8_t oct[2];  // octahedral unit normal, snorm8; 0,0 when the cluster has none
};
static_assert(sizeof(EncodedVertex) == 8);

// Record sizes by section, 1 for byte sections; indexed by SectionType.
inline constexpr uint32_t kSectionRecordBytes[kSectionCount] = {sizeof(ClusterRecord),
                                                                sizeof(GroupRecord),
                                                                sizeof(PageRecord),
                                                                sizeof(InstanceRecord),
                                                                8,
                                                                sizeof(ObjectRecord),
                                                                sizeof(LayerRecord),
                                                                1,
                                                                1,
                                                                1};

// Sections the writer may store zstd-compressed: tables the runtime reads whole at start anyway
// (instances, profiles, objects) or only for picking and reports (strings). Clusters, groups and
// pages are read in place from the mapping, page data is compressed page by page, and the
// visibility section is read cell by cell.
inline constexpr bool sectionMayBeCompressed(uint32_t type) {
  return type == static_cast<uint32_t>(SectionType::Instances) ||
         type == static_cast<uint32_t>(SectionType::Profiles) ||
         type == static_cast<uint32_t>(SectionType::Objects) ||
         type == static_cast<uint32_t>(SectionType::Strings);
}

inline constexpr const char* kSectionNames[kSectionCount] = {
    "clusters", "groups", "pages",   "instances",  "profiles",
    "objects",  "layers", "strings", "visibility", "page data"};

}  // namespace tw::pkg
