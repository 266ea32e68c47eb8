// The pager: brings geometry pages from the memory-mapped package into the GPU pool without the
// render thread ever waiting.
//
// Each page goes through: Absent -> Requested (queued) -> Loading (a loader thread reads and
// decodes it into host staging) -> Ready (decoded, waiting for upload) -> Resident (ranges in the
// GPU pool, handed to the renderer once by takeUploads) -> Evicted (ranges freed; may be
// requested again). The render thread calls request/beginFrame/takeUploads/touch; loader threads
// only read pages and decode. Budgets:
//  - GPU: the pool (three RangeAllocators: vertices, 16-bit indices, per-triangle objects, sized
//    by poolLayoutFor(gpu_budget_bytes)). A Ready page that does not fit evicts Resident pages
//    not touched for evict_after_frames frames, least recently used first; pinned pages never
//    leave. If it still does not fit it waits (and is counted).
//  - Host: decoded pages waiting in staging; loaders stop taking work above host_budget_bytes
//    (a page's decoded size is reserved when a loader takes it, so staging stays below the
//    budget plus one page; pinned pages are taken regardless, so start-up cannot wedge).
//  - Upload: takeUploads returns at most upload_bytes_per_frame of data (at least one page).
// The request queue is ordered by request priority (higher first); requests are renewed every
// frame (within a frame the highest priority wins, a later frame's request replaces it) and a
// queued page not requested for a few (4) frames is dropped from the queue and is Absent again.
// A decoded page that waits for pool space and is not requested for that long is dropped too.
// A page that fails to read or decode (or is larger than the whole pool) is counted in
// load_errors, reports Absent and failed(page), and is never requested again.
// Threads: loader_threads loaders read and decode; with 0 the render thread loads inside
// beginFrame (up to upload_bytes_per_frame of decoded data a frame), for debugging.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "package_format.h"
#include "package_view.h"
#include "range_allocator.h"

namespace tw {

// Where page bytes come from. The default reads the package; tests wrap it to be slow.
class PageSource {
 public:
  virtual ~PageSource() = default;
  // Raw (decompressed, checksum-checked) bytes of `page`; may be called from any loader thread
  // concurrently. Throws FormatError on a damaged page.
  virtual void read(uint32_t page, std::vector<uint8_t>& raw) = 0;
};

// PackageView::readPage. The view must outlive it.
std::unique_ptr<PageSource> makePackagePageSource(const PackageView& view);

// Capacities of the three pools, in elements.
struct PoolLayout {
  uint64_t vertices = 0;   // pkg::EncodedVertex (8 bytes)
  uint64_t indices = 0;    // uint16_t, cluster-local (drawn with base vertex)
  uint64_t triangles = 0;  // uint32_t object index per triangle
  uint64_t bytes() const { return vertices * 8 + indices * 2 + triangles * 4; }
};
// Splits a byte budget for typical clusters: 0.75 vertices and 3 indices per triangle, 16 bytes
// a triangle (measured: 0.66-0.81 vertices per triangle on the bunny at cluster sizes 256-64,
// 0.77-0.80 on generated plants; the pool that runs out first limits the others).
PoolLayout poolLayoutFor(uint64_t gpu_budget_bytes);

// A resident cluster's place in the pool.
struct GpuCluster {
  uint64_t first_vertex = 0;    // in the vertex pool
  uint64_t first_index = 0;     // in the index pool
  uint64_t first_triangle = 0;  // in the triangle-object pool
  uint32_t vertex_count = 0;
  uint32_t triangle_count = 0;
  uint32_t shift = 0;           // quantization: position = (grid_origin + q) * cell_m
  glm::ivec3 grid_origin{0};
  double cell_m = 0.0;
  // Every triangle belongs to an object marked pkg::kObjectClosedSurface, and solid_min/max
  // (package frame) hold all those objects' boxes: from an eye outside that box, no back face
  // of the cluster can show, so the renderer may cull them (frame_loop.cpp).
  bool closed = false;
  glm::vec3 solid_min{0.0f}, solid_max{0.0f};
  // Some triangle has no corner of its own object (vertex_object_tags.h), so the cluster is drawn
  // with the program whose fragments look their object up per triangle.
  bool object_per_triangle = false;
};

// One page's data for the renderer to copy into the pool at the given offsets (contiguous per
// page: the page's clusters one after the other).
struct PageUpload {
  uint32_t page = 0;
  uint64_t first_vertex = 0, first_index = 0, first_triangle = 0;
  std::vector<pkg::EncodedVertex> vertices;
  std::vector<uint16_t> indices;
  std::vector<uint32_t> triangle_objects;
  uint64_t bytes() const { return vertices.size() * 8 + indices.size() * 2 + triangle_objects.size() * 4; }
};

enum class PageState : uint8_t { Absent, Requested, Loading, Ready, Resident, Evicted };

struct PagerOptions {
  uint32_t loader_threads = 2;
  uint64_t gpu_budget_bytes = 1ull << 30;
  uint64_t host_budget_bytes = 256ull << 20;
  uint64_t upload_bytes_per_frame = 32ull << 20;
  uint32_t evict_after_frames = 30;  // frames unused before a page may be evicted (min 1)
};

struct PagerStats {
  uint32_t pages_resident = 0;
  uint32_t pages_requested = 0;   // in the queue now
  uint32_t pages_loading = 0;
  uint32_t pages_ready = 0;       // decoded, waiting for upload (or for pool space)
  uint32_t pages_uploaded = 0;    // this frame
  uint32_t pages_evicted = 0;     // this frame
  uint64_t bytes_uploaded = 0;    // this frame
  uint64_t gpu_bytes_used = 0;
  uint64_t host_bytes_used = 0;   // staging
  uint64_t load_errors = 0;       // pages that failed to read or decode (never retried)
  uint32_t pages_waiting_for_pool = 0;  // this frame: Ready pages that found no room even after
                                        // evicting every eligible page
};

class Pager {
 public:
  Pager(const PackageView& view, std::unique_ptr<PageSource> source, const PagerOptions& options);
  ~Pager();  // stops and joins the loaders
  Pager(const Pager&) = delete;
  Pager& operator=(const Pager&) = delete;

  const PoolLayout& poolLayout() const { return layout_; }

  // Starts frame `frame` (increasing): ages the queue, resets per-frame stats.
  void beginFrame(uint64_t frame);
  // Asks for a page (no effect when it is Resident, Ready or Loading; raises a queued page's
  // priority). Render thread only.
  void request(uint32_t page, float priority);
  // Pages that must never be evicted (root pages). Requests them at top priority.
  void pin(std::span<const uint32_t> pages);
  // Blocks until every pinned page is Ready or Resident (start-up only; throws FormatError if one
  // failed to load).
  void waitForPinned();
  // Marks a resident page used this frame (LRU).
  void touch(uint32_t page);
  // Ready pages placed in the pool, within the upload cap; they are Resident from now on.
  std::vector<PageUpload> takeUploads();

  PageState state(uint32_t page) const;
  bool resident(uint32_t page) const;  // cheap; render thread
  // True once the page failed to load (it is then never retried). Render thread.
  bool failed(uint32_t page) const;
  // The pages that failed to load since the last call, each once, as messages naming the
  // package, the page and the reason (a checksum mismatch names its byte). Render thread.
  std::vector<std::string> takeLoadErrors();
  // Placement of a cluster of a resident page (stale for clusters of other pages).
  const GpuCluster& gpuCluster(uint32_t cluster) const;
  PagerStats stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  PoolLayout layout_;
};

}  // namespace tw
