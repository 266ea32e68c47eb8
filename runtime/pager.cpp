// The pager's threads and bookkeeping. Ownership is split so that the render thread never waits
// on a loader:
//  - render thread only: the page states the renderer reads (state), LRU frames, pins, the pool
//    allocators and placements, and the decoded pages it has collected (ready);
//  - shared, under mutex: the request queue, each page's loader phase, the list of pages the
//    loaders finished (done) and the host staging byte count.
// Loaders hold the mutex only to pop the queue and to push a result; all reading and decoding
// happens outside it, so the render thread's locks are short whatever the source does. The
// render thread locks once per new request or changed priority, once per beginFrame and
// takeUploads, never while a loader reads.
#include "pager.h"

#include <algorithm>
#include <condition_variable>
#include <exception>
#include <limits>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>

#include "format_error.h"
#include "vertex_object_tags.h"

namespace tw {

namespace {

// A queued page not requested again for this many frames leaves the queue (the cut no longer
// wants it); a decoded page that waits for pool space that long is dropped from staging.
constexpr uint64_t kDropAfterFrames = 4;

constexpr float kPinnedPriority = std::numeric_limits<float>::infinity();

class PackagePageSource final : public PageSource {
 public:
  explicit PackagePageSource(const PackageView& view) : view_(view) {}
  void read(uint32_t page, std::vector<uint8_t>& raw) override { view_.readPage(page, raw); }

 private:
  const PackageView& view_;
};

// Loader-side phase of a page (shared, under mutex_).
enum class Phase : uint8_t { Idle, Queued, Loading, Done };

}  // namespace

std::unique_ptr<PageSource> makePackagePageSource(const PackageView& view) {
  return std::make_unique<PackagePageSource>(view);
}

PoolLayout poolLayoutFor(uint64_t gpu_budget_bytes) {
  // Per triangle: 0.75 vertices * 8 + 3 indices * 2 + 1 object * 4 = 16 bytes.
  PoolLayout layout;
  layout.triangles = gpu_budget_bytes / 16;
  layout.vertices = layout.triangles * 3 / 4;
  layout.indices = layout.triangles * 3;
  return layout;
}

struct Pager::Impl {
  // A page the loaders finished: its data (offsets not yet chosen) or why it failed.
  struct LoadedPage {
    uint32_t page = 0;
    float priority = 0.0f;
    uint64_t staged_bytes = 0;  // counted in host_bytes until uploaded or dropped
    PageUpload upload;
    std::vector<GpuCluster> clusters;  // offsets relative to the page's first element
    std::exception_ptr error;
  };
  struct QueueKey {
    float priority;
    uint32_t page;
    bool operator<(const QueueKey& o) const {
      if (priority != o.priority) return priority > o.priority;  // highest first
      return page < o.page;
    }
  };
  struct Placement {
    uint64_t first_vertex = 0, first_index = 0, first_triangle = 0;
    uint64_t vertices = 0, indices = 0, triangles = 0;
  };

  Impl(const PackageView& v, std::unique_ptr<PageSource> s, const PagerOptions& o,
       const PoolLayout& layout)
      : view(v),
        source(std::move(s)),
        options(o),
        vertex_pool(layout.vertices),
        index_pool(layout.indices),
        triangle_pool(layout.triangles) {
    const auto pages = view.pages();
    const auto clusters = view.clusters();
    const size_t page_count = pages.size();
    // Page -> clusters index (CSR), clusters of a page in table order, which is also the order
    // of their data in the page's upload.
    page_first_cluster.assign(page_count + 1, 0);
    for (const pkg::ClusterRecord& c : clusters)
      if (c.kind == static_cast<uint8_t>(pkg::ClusterKind::Mesh) && c.page < page_count)
        ++page_first_cluster[c.page + 1];
    for (size_t p = 0; p < page_count; ++p) page_first_cluster[p + 1] += page_first_cluster[p];
    page_clusters.resize(page_first_cluster[page_count]);
    std::vector<uint32_t> fill(page_first_cluster.begin(), page_first_cluster.end() - 1);
    page_vertices.assign(page_count, 0);
    page_triangles.assign(page_count, 0);
    for (uint32_t i = 0; i < clusters.size(); ++i) {
      const pkg::ClusterRecord& c = clusters[i];
      if (c.kind != static_cast<uint8_t>(pkg::ClusterKind::Mesh) || c.page >= page_count) continue;
      page_clusters[fill[c.page]++] = i;
      page_vertices[c.page] += c.vertex_count;
      page_triangles[c.page] += c.triangle_count;
    }

    state.assign(page_count, static_cast<uint8_t>(PageState::Absent));
    failed.assign(page_count, 0);
    pinned.assign(page_count, 0);
    last_touch.assign(page_count, 0);
    last_request.assign(page_count, 0);
    placement.resize(page_count);
    gpu_clusters.resize(clusters.size());
    phase.assign(page_count, Phase::Idle);
    queued_priority.assign(page_count, 0.0f);
    want_priority.assign(page_count, 0.0f);
    want_frame.assign(page_count, 0);
    pinned_shared.assign(page_count, 0);

    for (uint32_t t = 0; t < options.loader_threads; ++t)
      loaders.emplace_back([this] { loaderLoop(); });
  }

  ~Impl() {
    {
      std::lock_guard<std::mutex> lock(mutex);
      stop = true;
    }
    work_cv.notify_all();
    done_cv.notify_all();
    for (std::thread& t : loaders) t.join();
  }

  uint64_t stagedBytes(uint32_t page) const {
    return page_vertices[page] * 8 + page_triangles[page] * (3 * 2 + 4);
  }

  // --- loaders ------------------------------------------------------------------------------

  // Host budget: a loader may start a page while staging is under budget (so staging stays
  // below budget + one page however many loaders there are, since the page's decoded size is
  // reserved when it is taken). Pinned pages ignore the budget: start-up must not wedge behind
  // decoded pages nobody can upload yet.
  bool canTake() const {
    if (queue.empty()) return false;
    if (host_bytes == 0 || host_bytes < options.host_budget_bytes) return true;
    return pinned_shared[queue.begin()->page] != 0;
  }

  // Pops the best queued page; caller holds the lock and has checked canTake().
  LoadedPage take() {
    const QueueKey key = *queue.begin();
    queue.erase(queue.begin());
    phase[key.page] = Phase::Loading;
    ++loading;
    LoadedPage out;
    out.page = key.page;
    out.priority = key.priority;
    out.staged_bytes = stagedBytes(key.page);
    host_bytes += out.staged_bytes;
    return out;
  }

  // A FormatError at the page's stored bytes in the file.
  FormatError pageError(uint32_t page, const std::string& reason) const {
    const uint64_t at = view.section(pkg::SectionType::PageData).offset + view.pages()[page].offset;
    return FormatError::atByte(view.fileName(), at, "page " + std::to_string(page) + ": " + reason);
  }

  // Sets g.closed and the box of the cluster's objects from the object table. Triangles come
  // sorted by object (page_codec.h), so each object is looked at once per run.
  void markClosed(std::span<const uint32_t> triangle_objects, GpuCluster& g) const {
    const std::span<const pkg::ObjectRecord> objects = view.objects();
    g.closed = !triangle_objects.empty();
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    uint32_t previous = pkg::kNone;
    for (uint32_t object : triangle_objects) {
      if (object == previous) continue;
      previous = object;
      if (object >= objects.size() || !(objects[object].flags & pkg::kObjectClosedSurface)) {
        g.closed = false;
        return;
      }
      const pkg::ObjectRecord& o = objects[object];
      lo = glm::min(lo, glm::vec3(o.aabb_min[0], o.aabb_min[1], o.aabb_min[2]));
      hi = glm::max(hi, glm::vec3(o.aabb_max[0], o.aabb_max[1], o.aabb_max[2]));
    }
    g.solid_min = lo;
    g.solid_max = hi;
  }

  // Reads and decodes without the lock. Scratch buffers are per caller.
  void load(LoadedPage& out, std::vector<uint8_t>& raw, DecodedCluster& decoded) {
    try {
      source->read(out.page, raw);
      if (stopping()) return;
      const pkg::PageRecord& record = view.pages()[out.page];
      if (raw.size() != record.raw_bytes)
        throw pageError(out.page, "the source gave " + std::to_string(raw.size()) +
                                      " raw bytes, the record says " +
                                      std::to_string(record.raw_bytes));
      PageUpload& up = out.upload;
      up.page = out.page;
      // No reserve from the records' counts: a damaged table could claim any size, while what
      // decodes is bounded by the page's bytes and the per-cluster limits.
      const uint32_t first = page_first_cluster[out.page];
      const uint32_t last = page_first_cluster[out.page + 1];
      out.clusters.reserve(last - first);
      for (uint32_t k = first; k < last; ++k) {
        const uint32_t cluster = page_clusters[k];
        view.decodeCluster(cluster, raw, decoded);
        const uint32_t vertex_count = static_cast<uint32_t>(decoded.vertices.size());
        if (decoded.indices.size() != decoded.triangle_objects.size() * 3)
          throw pageError(out.page, "cluster " + std::to_string(cluster) +
                                        ": index and triangle counts disagree");
        GpuCluster g;
        g.first_vertex = up.vertices.size();
        g.first_index = up.indices.size();
        g.first_triangle = up.triangle_objects.size();
        g.vertex_count = vertex_count;
        g.triangle_count = static_cast<uint32_t>(decoded.triangle_objects.size());
        g.shift = decoded.shift;
        g.grid_origin = decoded.grid_origin;
        g.cell_m = decoded.cell_m;
        markClosed(decoded.triangle_objects, g);
        out.clusters.push_back(g);
        up.vertices.insert(up.vertices.end(), decoded.vertices.begin(), decoded.vertices.end());
        for (uint32_t index : decoded.indices) {
          if (index >= vertex_count)  // the decoder checks this; a uint16 cast must never wrap
            throw pageError(out.page, "cluster " + std::to_string(cluster) +
                                          ": index out of range");
          up.indices.push_back(static_cast<uint16_t>(index));
        }
        up.triangle_objects.insert(up.triangle_objects.end(), decoded.triangle_objects.begin(),
                                   decoded.triangle_objects.end());
        // The GPU form: each vertex tagged with a triangle of its object (vertex_object_tags.h).
        const std::span<const uint32_t> objects(up.triangle_objects);
        out.clusters.back().object_per_triangle =
            tagVertexObjects(std::span(up.vertices).subspan(g.first_vertex),
                             std::span(up.indices).subspan(g.first_index),
                             objects.subspan(g.first_triangle)) > 0;
      }
      if (up.bytes() != out.staged_bytes)
        throw pageError(out.page, "decoded size differs from its cluster records");
    } catch (...) {
      out.error = std::current_exception();
      out.upload = PageUpload{};
      out.clusters.clear();
    }
  }

  // Caller holds the lock.
  void finish(LoadedPage&& page) {
    phase[page.page] = Phase::Done;
    --loading;
    done.push_back(std::move(page));
    done_cv.notify_all();
  }

  bool stopping() {
    std::lock_guard<std::mutex> lock(mutex);
    return stop;
  }

  void loaderLoop() {
    std::vector<uint8_t> raw;
    DecodedCluster decoded;
    std::unique_lock<std::mutex> lock(mutex);
    while (true) {
      work_cv.wait(lock, [this] { return stop || canTake(); });
      if (stop) return;
      LoadedPage page = take();
      lock.unlock();
      load(page, raw, decoded);
      lock.lock();
      if (stop) {
        // Nobody will collect it; keep the books straight anyway.
        host_bytes -= page.staged_bytes;
        --loading;
        return;
      }
      finish(std::move(page));
    }
  }

  // loader_threads == 0: loads on the calling (render) thread, at most `byte_limit` decoded
  // bytes (at least one page), within the host budget.
  void loadInline(uint64_t byte_limit) {
    uint64_t loaded = 0;
    while (loaded < byte_limit) {
      LoadedPage page;
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (!canTake()) return;
        page = take();
      }
      load(page, inline_raw, inline_decoded);
      loaded += std::max<uint64_t>(page.staged_bytes, 1);
      std::lock_guard<std::mutex> lock(mutex);
      finish(std::move(page));
    }
  }

  // --- render thread ------------------------------------------------------------------------

  // Queues a page the render thread just marked Requested, or moves a queued page to a new
  // priority. Loaders only wait on an empty queue or a full host budget, so only a first entry
  // (or a pinned page, which ignores the budget) needs to wake them.
  void enqueue(uint32_t page, float priority) {
    bool wake = false;
    {
      std::lock_guard<std::mutex> lock(mutex);
      wake = queue.empty() || pinned_shared[page];
      if (phase[page] == Phase::Queued) {
        queue.erase(QueueKey{queued_priority[page], page});
      } else if (phase[page] == Phase::Idle) {
        phase[page] = Phase::Queued;
      } else {
        return;  // already loading or loaded: the priority no longer matters
      }
      queued_priority[page] = priority;
      queue.insert(QueueKey{priority, page});
    }
    if (wake) work_cv.notify_all();
  }

  // Drops queued pages the cut stopped asking for.
  void ageQueue() {
    std::lock_guard<std::mutex> lock(mutex);
    for (auto it = queue.begin(); it != queue.end();) {
      const uint32_t page = it->page;
      if (!pinned[page] && last_request[page] + kDropAfterFrames < frame) {
        it = queue.erase(it);
        phase[page] = Phase::Idle;
        state[page] = static_cast<uint8_t>(PageState::Absent);
      } else {
        ++it;
      }
    }
  }

  // Collects what the loaders finished: decoded pages become Ready, failures are recorded.
  void collectDone() {
    std::vector<LoadedPage> finished;
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (done.empty()) return;
      finished.swap(done);
      for (LoadedPage& p : finished) {
        phase[p.page] = Phase::Idle;
        if (p.error) host_bytes -= p.staged_bytes;
      }
    }
    if (finished.size() != 0) work_cv.notify_all();  // staging may have room again
    for (LoadedPage& p : finished) {
      if (p.error) {
        failed[p.page] = 1;
        errors.emplace_back(p.page, p.error);
        state[p.page] = static_cast<uint8_t>(PageState::Absent);
        ++load_errors;
        continue;
      }
      state[p.page] = static_cast<uint8_t>(PageState::Ready);
      ready.push_back(std::move(p));
    }
  }

  void releaseStaging(uint64_t bytes) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      host_bytes -= bytes;
    }
    work_cv.notify_all();
  }

  bool allocate(uint32_t page, Placement& where) {
    where = Placement{};
    where.vertices = page_vertices[page];
    where.indices = page_triangles[page] * 3;
    where.triangles = page_triangles[page];
    std::optional<uint64_t> v, i, t;
    if (where.vertices > 0 && !(v = vertex_pool.allocate(where.vertices))) return false;
    if (where.indices > 0 && !(i = index_pool.allocate(where.indices))) {
      if (v) vertex_pool.release(*v);
      return false;
    }
    if (where.triangles > 0 && !(t = triangle_pool.allocate(where.triangles))) {
      if (v) vertex_pool.release(*v);
      if (i) index_pool.release(*i);
      return false;
    }
    where.first_vertex = v.value_or(0);
    where.first_index = i.value_or(0);
    where.first_triangle = t.value_or(0);
    return true;
  }

  void evict(uint32_t page) {
    const Placement& where = placement[page];
    if (where.vertices > 0) vertex_pool.release(where.first_vertex);
    if (where.indices > 0) index_pool.release(where.first_index);
    if (where.triangles > 0) triangle_pool.release(where.first_triangle);
    placement[page] = Placement{};
    state[page] = static_cast<uint8_t>(PageState::Evicted);
    resident_pages.erase(page);
    ++frame_stats.pages_evicted;
  }

  bool fitsPoolAtAll(uint32_t page) const {
    return page_vertices[page] <= vertex_pool.capacity() &&
           page_triangles[page] * 3 <= index_pool.capacity() &&
           page_triangles[page] <= triangle_pool.capacity();
  }

  std::vector<PageUpload> takeUploads() {
    collectDone();
    std::vector<PageUpload> out;
    if (ready.empty()) return out;
    std::stable_sort(ready.begin(), ready.end(), [](const LoadedPage& a, const LoadedPage& b) {
      return a.priority > b.priority;
    });

    // Eviction candidates, built when first needed: resident, unpinned, untouched for
    // evict_after_frames, least recently used first.
    std::vector<uint32_t> candidates;
    size_t next_candidate = 0;
    bool candidates_built = false;
    // A page touched this frame is never a candidate, even with evict_after_frames == 0: it may
    // be in this frame's draw list, or in this very batch of uploads.
    const uint64_t min_age = std::max<uint64_t>(options.evict_after_frames, 1);
    auto buildCandidates = [&] {
      candidates_built = true;
      for (uint32_t page : resident_pages)
        if (!pinned[page] && frame >= last_touch[page] + min_age)
          candidates.push_back(page);
      std::sort(candidates.begin(), candidates.end(), [&](uint32_t a, uint32_t b) {
        return last_touch[a] != last_touch[b] ? last_touch[a] < last_touch[b] : a < b;
      });
    };

    uint64_t sent = 0;
    uint64_t released = 0;
    std::vector<LoadedPage> waiting;
    size_t k = 0;
    for (; k < ready.size(); ++k) {
      LoadedPage& p = ready[k];
      const uint64_t bytes = p.upload.bytes();
      if (!out.empty() && sent + bytes > options.upload_bytes_per_frame) break;
      if (!fitsPoolAtAll(p.page)) {
        // No eviction can ever make room: a load error rather than a page that waits forever.
        failed[p.page] = 1;
        errors.emplace_back(p.page,
                            std::make_exception_ptr(pageError(p.page, "larger than the GPU pool")));
        state[p.page] = static_cast<uint8_t>(PageState::Absent);
        ++load_errors;
        released += p.staged_bytes;
        continue;
      }
      Placement where;
      bool placed = allocate(p.page, where);
      while (!placed) {
        if (!candidates_built) buildCandidates();
        if (next_candidate >= candidates.size()) break;
        const uint32_t victim = candidates[next_candidate++];
        if (state[victim] != static_cast<uint8_t>(PageState::Resident)) continue;
        evict(victim);
        placed = allocate(p.page, where);
      }
      if (!placed) {
        ++frame_stats.pages_waiting_for_pool;
        if (!pinned[p.page] && last_request[p.page] + kDropAfterFrames < frame) {
          // Nobody asked for it lately: free its staging rather than hold the host budget.
          state[p.page] = static_cast<uint8_t>(PageState::Absent);
          released += p.staged_bytes;
        } else {
          waiting.push_back(std::move(p));
        }
        continue;
      }
      placement[p.page] = where;
      const uint32_t first = page_first_cluster[p.page];
      for (size_t c = 0; c < p.clusters.size(); ++c) {
        GpuCluster g = p.clusters[c];
        g.first_vertex += where.first_vertex;
        g.first_index += where.first_index;
        g.first_triangle += where.first_triangle;
        gpu_clusters[page_clusters[first + c]] = g;
      }
      p.upload.first_vertex = where.first_vertex;
      p.upload.first_index = where.first_index;
      p.upload.first_triangle = where.first_triangle;
      state[p.page] = static_cast<uint8_t>(PageState::Resident);
      last_touch[p.page] = frame;
      resident_pages.insert(p.page);
      sent += bytes;
      released += p.staged_bytes;
      ++frame_stats.pages_uploaded;
      frame_stats.bytes_uploaded += bytes;
      out.push_back(std::move(p.upload));
    }
    for (; k < ready.size(); ++k) waiting.push_back(std::move(ready[k]));
    ready.swap(waiting);
    if (released > 0) releaseStaging(released);
    return out;
  }

  // The error of a failed page as a FormatError naming the file (and byte), prefixed by `what`.
  FormatError loadError(const std::string& what, const std::exception_ptr& error) const {
    try {
      std::rethrow_exception(error);
    } catch (const FormatError& e) {
      if (e.where() == FormatError::Where::Byte)
        return FormatError::atByte(e.file(), e.position(), what + e.reason());
      return FormatError(e.file().empty() ? view.fileName() : e.file(), what + e.reason());
    } catch (const std::exception& e) {
      return FormatError(view.fileName(), what + e.what());
    }
  }
  [[noreturn]] void throwLoadError(uint32_t page, const std::exception_ptr& error) const {
    throw loadError("pinned page " + std::to_string(page) + " failed to load: ", error);
  }

  const PackageView& view;
  std::unique_ptr<PageSource> source;
  PagerOptions options;

  // Static per-page facts.
  std::vector<uint32_t> page_first_cluster;  // CSR offsets into page_clusters
  std::vector<uint32_t> page_clusters;
  std::vector<uint64_t> page_vertices;
  std::vector<uint64_t> page_triangles;

  // Render thread only.
  uint64_t frame = 0;
  std::vector<uint8_t> state;   // PageState as the render thread knows it
  std::vector<uint8_t> failed;  // never retried
  std::vector<uint8_t> pinned;
  std::vector<uint32_t> pinned_list;
  std::vector<uint64_t> last_touch;
  std::vector<uint64_t> last_request;
  std::vector<float> want_priority;  // priority of the page's queue entry, as last sent
  std::vector<uint64_t> want_frame;  // frame of that request
  std::vector<LoadedPage> ready;
  std::vector<std::pair<uint32_t, std::exception_ptr>> errors;
  size_t errors_reported = 0;  // errors takeLoadErrors() has handed out
  std::vector<Placement> placement;
  std::vector<GpuCluster> gpu_clusters;
  std::set<uint32_t> resident_pages;
  RangeAllocator vertex_pool, index_pool, triangle_pool;
  PagerStats frame_stats;
  uint64_t load_errors = 0;
  std::vector<uint8_t> inline_raw;
  DecodedCluster inline_decoded;

  // Shared, under mutex.
  mutable std::mutex mutex;
  std::condition_variable work_cv;  // loaders: work, staging room or stop
  std::condition_variable done_cv;  // waitForPinned: a page finished
  std::set<QueueKey> queue;
  std::vector<Phase> phase;
  std::vector<float> queued_priority;
  std::vector<uint8_t> pinned_shared;
  std::vector<LoadedPage> done;
  uint64_t host_bytes = 0;
  uint32_t loading = 0;
  bool stop = false;

  std::vector<std::thread> loaders;  // last: started after everything above exists
};

Pager::Pager(const PackageView& view, std::unique_ptr<PageSource> source,
             const PagerOptions& options)
    : layout_(poolLayoutFor(options.gpu_budget_bytes)) {
  if (!source) throw std::invalid_argument("Pager: no page source");
  impl_ = std::make_unique<Impl>(view, std::move(source), options, layout_);
}

Pager::~Pager() = default;

void Pager::beginFrame(uint64_t frame) {
  Impl& m = *impl_;
  m.frame = frame;
  m.frame_stats = PagerStats{};
  m.ageQueue();
  if (m.options.loader_threads == 0)
    m.loadInline(std::max<uint64_t>(m.options.upload_bytes_per_frame, 1));
  m.collectDone();
}

void Pager::request(uint32_t page, float priority) {
  Impl& m = *impl_;
  if (page >= m.state.size()) throw std::out_of_range("Pager::request: no such page");
  m.last_request[page] = m.frame;
  if (m.failed[page]) return;
  const auto s = static_cast<PageState>(m.state[page]);
  if (s == PageState::Resident || s == PageState::Ready) return;
  if (m.pinned[page]) priority = kPinnedPriority;
  if (priority != priority) priority = 0.0f;  // NaN would break the queue's ordering
  if (s == PageState::Absent || s == PageState::Evicted) {
    m.state[page] = static_cast<uint8_t>(PageState::Requested);
  } else {
    // Within a frame the highest request wins; a later frame's request replaces it. Nothing to
    // tell the loaders when it is unchanged (a still camera), so most renewals take no lock.
    if (m.want_frame[page] == m.frame) priority = std::max(priority, m.want_priority[page]);
    m.want_frame[page] = m.frame;
    if (priority == m.want_priority[page]) return;
  }
  m.want_priority[page] = priority;
  m.want_frame[page] = m.frame;
  m.enqueue(page, priority);
}

void Pager::pin(std::span<const uint32_t> pages) {
  Impl& m = *impl_;
  for (uint32_t page : pages)
    if (page >= m.state.size()) throw std::out_of_range("Pager::pin: no such page");
  {
    std::lock_guard<std::mutex> lock(m.mutex);
    for (uint32_t page : pages) m.pinned_shared[page] = 1;
  }
  for (uint32_t page : pages) {
    if (!m.pinned[page]) m.pinned_list.push_back(page);
    m.pinned[page] = 1;
    request(page, kPinnedPriority);
  }
}

void Pager::waitForPinned() {
  Impl& m = *impl_;
  auto failedPinned = [&]() -> const std::pair<uint32_t, std::exception_ptr>* {
    for (const auto& e : m.errors)
      if (m.pinned[e.first]) return &e;
    return nullptr;
  };
  while (true) {
    m.collectDone();
    if (const auto* e = failedPinned()) m.throwLoadError(e->first, e->second);
    bool all = true;
    for (uint32_t page : m.pinned_list) {
      const auto s = static_cast<PageState>(m.state[page]);
      if (s != PageState::Ready && s != PageState::Resident) all = false;
    }
    if (all) return;
    if (m.options.loader_threads == 0) {
      m.loadInline(std::numeric_limits<uint64_t>::max());
      continue;
    }
    std::unique_lock<std::mutex> lock(m.mutex);
    m.done_cv.wait(lock, [&] { return m.stop || !m.done.empty(); });
  }
}

void Pager::touch(uint32_t page) {
  Impl& m = *impl_;
  if (page < m.last_touch.size()) m.last_touch[page] = m.frame;
}

std::vector<PageUpload> Pager::takeUploads() { return impl_->takeUploads(); }

PageState Pager::state(uint32_t page) const {
  const Impl& m = *impl_;
  if (page >= m.state.size()) throw std::out_of_range("Pager::state: no such page");
  const auto s = static_cast<PageState>(m.state[page]);
  if (s != PageState::Requested) return s;
  std::lock_guard<std::mutex> lock(m.mutex);
  switch (m.phase[page]) {
    case Phase::Loading: return PageState::Loading;
    case Phase::Done: return PageState::Ready;
    default: return PageState::Requested;
  }
}

bool Pager::resident(uint32_t page) const {
  const Impl& m = *impl_;
  return page < m.state.size() && m.state[page] == static_cast<uint8_t>(PageState::Resident);
}

std::vector<std::string> Pager::takeLoadErrors() {
  Impl& m = *impl_;
  std::vector<std::string> out;
  for (; m.errors_reported < m.errors.size(); ++m.errors_reported) {
    const auto& [page, error] = m.errors[m.errors_reported];
    out.push_back(m.loadError("page " + std::to_string(page) + " failed to load: ", error).what());
  }
  return out;
}

bool Pager::failed(uint32_t page) const {
  const Impl& m = *impl_;
  return page < m.failed.size() && m.failed[page] != 0;
}

const GpuCluster& Pager::gpuCluster(uint32_t cluster) const {
  return impl_->gpu_clusters.at(cluster);
}

PagerStats Pager::stats() const {
  const Impl& m = *impl_;
  PagerStats s = m.frame_stats;
  s.pages_resident = static_cast<uint32_t>(m.resident_pages.size());
  s.load_errors = m.load_errors;
  s.gpu_bytes_used =
      m.vertex_pool.used() * 8 + m.index_pool.used() * 2 + m.triangle_pool.used() * 4;
  std::lock_guard<std::mutex> lock(m.mutex);
  s.pages_requested = static_cast<uint32_t>(m.queue.size());
  s.pages_loading = m.loading;
  s.pages_ready = static_cast<uint32_t>(m.ready.size() + m.done.size());
  s.host_bytes_used = m.host_bytes;
  return s;
}

}  // namespace tw
