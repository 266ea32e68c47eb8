// The pager over real packages (and its pool layout): every requested
// page arrives with exactly its decoded data at non-overlapping places, a slow reader never
// stalls the render thread, the GPU, host and upload budgets hold, eviction takes only stale
// unpinned pages, and damaged pages are counted, never retried and never wedge the pager.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <random>
#include <set>
#include <thread>
#include <vector>

#include <tbb/global_control.h>
#include <unistd.h>

#include "package_view.h"
#include "package_writer.h"
#include "pager.h"
#include "preprocess_driver.h"
#include "test_support.h"
#include "vertex_object_tags.h"

namespace tw {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// The fixtures are built by the preprocessor on one TBB thread: these tests are about the pager's
// own threads, and ThreadSanitizer (tools/sanitize.sh) cannot see the synchronization inside
// Debian's uninstrumented TBB scheduler, so work it shares out would read as data races.
const tbb::global_control kOneTbbThread(tbb::global_control::max_allowed_parallelism, 1);
using namespace std::chrono_literals;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

TEST(PoolLayout, SplitsTheBudgetWithoutExceedingIt) {
  for (uint64_t budget : {0ull, 1000ull, 1ull << 20, 1ull << 30, 3ull << 32}) {
    PoolLayout layout = poolLayoutFor(budget);
    EXPECT_LE(layout.bytes(), budget);
    EXPECT_GE(layout.bytes() + 64, budget * 99 / 100) << "most of the budget is used";
    EXPECT_EQ(layout.indices, layout.triangles * 3);
  }
}

// ---------------------------------------------------------------------------------------------
// Packages

// Packages shared by the tests of one process (ctest may run several test_pager processes at
// once).
const fs::path& fixtureDir() {
  static const fs::path dir = test::processScratchDir("pager-fixtures");
  return dir;
}

// The bunny through the real preprocessor: a handful of pages over several LOD levels.
const fs::path& bunnyPackage() {
  static const fs::path path = [] {
    PreprocessOptions options;
    options.inputs = {test::sharedDataDir() / "stanford-bunny.obj"};
    options.output = fixtureDir() / "bunny.twk";
    options.cluster_size = 64;
    runPreprocess(options);
    return options.output;
  }();
  return path;
}

// Many small pages of root clusters (bumpy grid patches of 32..200 triangles, two objects each),
// written straight through PackageStorage with a 4 KiB page target so budgets and eviction have
// something to work on; takes milliseconds.
const fs::path& gridPackage() {
  static const fs::path path = [] {
    constexpr int kClusters = 300;
    constexpr uint32_t kObjects = 8;
    PackageStorage storage;
    storage.target_page_bytes = 4096;
    storage.addLayer({"grid", 0xff808080u});
    for (uint32_t o = 0; o < kObjects; ++o) {
      ObjectInfo info;
      info.id = o;
      info.name = "patch " + std::to_string(o);
      storage.addObject(info, glm::vec3(0.0f, 0.0f, -1.0f), glm::vec3(kClusters * 2.0f, 2.0f, 1.0f));
    }
    std::mt19937 rng(7);
    for (int c = 0; c < kClusters; ++c) {
      const int n = 4 + static_cast<int>(rng() % 7);
      std::vector<glm::vec3> positions, normals;
      std::vector<uint32_t> indices, objects;
      for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
          positions.emplace_back(c * 2.0f + 1.5f * i / n, 1.5f * j / n,
                                 0.1f * std::sin(0.7f * i + 1.3f * j + c));
          normals.push_back(glm::normalize(glm::vec3(0.1f * i / n, 0.05f, 1.0f)));
        }
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          uint32_t a = i * (n + 1) + j, b = a + 1, d = a + (n + 1), e = d + 1;
          indices.insert(indices.end(), {a, d, e, a, e, b});
        }
      const uint32_t triangles = static_cast<uint32_t>(indices.size() / 3);
      const uint32_t lo = static_cast<uint32_t>(c) % kObjects, hi = std::min(lo + 1, kObjects - 1);
      for (uint32_t t = 0; t < triangles; ++t) objects.push_back(t < triangles / 2 ? lo : hi);
      ClusterGeometryInput input;
      input.positions = positions;
      input.normals = normals;
      input.indices = indices;
      input.triangle_objects = objects;
      storage.addMeshCluster(input, ClusterLod{});
    }
    fs::path out = fixtureDir() / "grid.twk";
    writePackage(storage, out);
    return out;
  }();
  return path;
}

// What a page's upload must hold: its mesh clusters in table order, decoded by the view.
struct ExpectedPage {
  std::vector<uint32_t> clusters;
  std::vector<DecodedCluster> decoded;
  std::vector<bool> object_per_triangle;  // per cluster, as the pager must flag it
  uint64_t bytes = 0;
};

std::vector<ExpectedPage> expectedPages(const PackageView& view) {
  std::vector<ExpectedPage> pages(view.pages().size());
  std::vector<uint8_t> raw;
  for (uint32_t c = 0; c < view.clusters().size(); ++c) {
    const pkg::ClusterRecord& r = view.clusters()[c];
    if (r.kind != static_cast<uint8_t>(pkg::ClusterKind::Mesh)) continue;
    pages[r.page].clusters.push_back(c);
  }
  for (uint32_t p = 0; p < pages.size(); ++p) {
    view.readPage(p, raw);
    for (uint32_t c : pages[p].clusters) {
      DecodedCluster d;
      view.decodeCluster(c, raw, d);
      pages[p].bytes += d.vertices.size() * 8 + d.indices.size() * 2 + d.triangle_objects.size() * 4;
      // What the GPU receives: the decode with its vertices tagged by object.
      std::vector<uint16_t> indices(d.indices.begin(), d.indices.end());
      pages[p].object_per_triangle.push_back(
          tagVertexObjects(d.vertices, indices, d.triangle_objects) > 0);
      d.indices.assign(indices.begin(), indices.end());
      pages[p].decoded.push_back(std::move(d));
    }
  }
  return pages;
}

// A PageSource over the package with knobs: a delay per read, pages that fail, a hook that may
// damage the raw bytes. Counts reads per page and keeps their order.
class TestSource : public PageSource {
 public:
  explicit TestSource(const PackageView& view) : view_(view), reads_(view.pages().size()) {}

  std::chrono::milliseconds delay{0};
  std::set<uint32_t> throw_pages;     // FormatError before any byte arrives
  std::set<uint32_t> truncate_pages;  // half the bytes
  std::function<void(uint32_t, std::vector<uint8_t>&)> damage;

  void read(uint32_t page, std::vector<uint8_t>& raw) override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++reads_[page];
      order_.push_back(page);
    }
    if (delay.count() > 0) std::this_thread::sleep_for(delay);
    if (throw_pages.count(page))
      throw FormatError::atByte(view_.fileName(), 4242, "test: unreadable page");
    view_.readPage(page, raw);
    if (truncate_pages.count(page)) raw.resize(raw.size() / 2);
    if (damage) damage(page, raw);
  }
  int reads(uint32_t page) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return reads_[page];
  }
  std::vector<uint32_t> order() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return order_;
  }

 private:
  const PackageView& view_;
  mutable std::mutex mutex_;
  std::vector<int> reads_;
  std::vector<uint32_t> order_;
};

// Waits (up to 5 s) until the source has started `reads` reads: the loaders are then busy, with
// no guess at how long that takes on a loaded machine.
void waitForReads(const TestSource& source, size_t reads) {
  const auto start = std::chrono::steady_clock::now();
  while (source.order().size() < reads &&
         std::chrono::steady_clock::now() - start < std::chrono::seconds(5))
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

// Checks an upload against the view's decode and the pager's cluster placements.
void expectUploadMatches(const Pager& pager, const PageUpload& up, const ExpectedPage& expected) {
  ASSERT_EQ(up.bytes(), expected.bytes) << "page " << up.page;
  uint64_t v = 0, i = 0, t = 0;
  for (size_t k = 0; k < expected.clusters.size(); ++k) {
    const DecodedCluster& d = expected.decoded[k];
    const GpuCluster& g = pager.gpuCluster(expected.clusters[k]);
    EXPECT_EQ(g.first_vertex, up.first_vertex + v);
    EXPECT_EQ(g.first_index, up.first_index + i);
    EXPECT_EQ(g.first_triangle, up.first_triangle + t);
    ASSERT_EQ(g.vertex_count, d.vertices.size());
    ASSERT_EQ(g.triangle_count, d.triangle_objects.size());
    EXPECT_EQ(g.shift, d.shift);
    EXPECT_EQ(g.grid_origin, d.grid_origin);
    EXPECT_EQ(g.cell_m, d.cell_m);
    EXPECT_EQ(g.object_per_triangle, expected.object_per_triangle[k]);
    EXPECT_EQ(std::memcmp(up.vertices.data() + v, d.vertices.data(), d.vertices.size() * 8), 0)
        << "vertices of cluster " << expected.clusters[k];
    for (size_t n = 0; n < d.indices.size(); ++n)
      ASSERT_EQ(up.indices[i + n], d.indices[n]) << "cluster " << expected.clusters[k];
    for (size_t n = 0; n < d.triangle_objects.size(); ++n)
      ASSERT_EQ(up.triangle_objects[t + n], d.triangle_objects[n]);
    v += d.vertices.size();
    i += d.indices.size();
    t += d.triangle_objects.size();
  }
}

// Ranges [first, first + count) of resident pages must not overlap and must lie in the pool.
void expectDisjoint(std::vector<std::pair<uint64_t, uint64_t>> ranges, uint64_t capacity,
                    const char* pool) {
  std::sort(ranges.begin(), ranges.end());
  for (size_t k = 0; k < ranges.size(); ++k) {
    EXPECT_LE(ranges[k].first + ranges[k].second, capacity) << pool;
    if (k > 0) {
      EXPECT_LE(ranges[k - 1].first + ranges[k - 1].second, ranges[k].first) << pool;
    }
  }
}

struct RunResult {
  uint64_t frames = 0;
  bool settled = false;  // every page resident or failed
};

// Frames until every page in `pages` is resident (or failed): request the missing ones, touch
// the resident ones, take uploads and hand them to `onUploads`.
template <class OnUploads>
RunResult runUntilSettled(
    Pager& pager, const std::vector<uint32_t>& pages, uint64_t& frame, double max_seconds,
    OnUploads&& onUploads, const std::function<float(uint32_t)>& priority = [](uint32_t) {
      return 1.0f;
    }) {
  RunResult result;
  const auto t0 = Clock::now();
  while (msSince(t0) < max_seconds * 1000.0) {
    pager.beginFrame(frame);
    bool all = true;
    for (uint32_t p : pages) {
      if (pager.resident(p)) {
        pager.touch(p);
      } else if (!pager.failed(p)) {
        all = false;
        pager.request(p, priority(p));
      }
    }
    std::vector<PageUpload> uploads = pager.takeUploads();
    onUploads(uploads);
    ++frame;
    ++result.frames;
    if (all) {
      result.settled = true;
      break;
    }
    std::this_thread::sleep_for(1ms);
  }
  return result;
}

std::vector<uint32_t> allPages(const PackageView& view) {
  std::vector<uint32_t> pages(view.pages().size());
  for (uint32_t p = 0; p < pages.size(); ++p) pages[p] = p;
  return pages;
}

// Loads every page of `path` with `threads` loaders and checks data and placements.
void expectEveryPageArrivesIntact(const fs::path& path, uint32_t threads) {
  PackageView view = PackageView::open(path);
  const std::vector<ExpectedPage> expected = expectedPages(view);
  PagerOptions options;
  options.loader_threads = threads;
  options.gpu_budget_bytes = 64ull << 20;
  Pager pager(view, makePackagePageSource(view), options);
  std::map<uint32_t, int> uploads_of;
  std::vector<std::pair<uint64_t, uint64_t>> vertices, indices, triangles;
  uint64_t uploaded = 0;
  uint64_t frame = 1;
  RunResult run = runUntilSettled(pager, allPages(view), frame, 20.0, [&](auto& uploads) {
    for (const PageUpload& up : uploads) {
      ++uploads_of[up.page];
      EXPECT_EQ(pager.state(up.page), PageState::Resident);
      expectUploadMatches(pager, up, expected[up.page]);
      vertices.emplace_back(up.first_vertex, up.vertices.size());
      indices.emplace_back(up.first_index, up.indices.size());
      triangles.emplace_back(up.first_triangle, up.triangle_objects.size());
      uploaded += up.bytes();
    }
  });
  ASSERT_TRUE(run.settled) << "after " << run.frames << " frames";
  EXPECT_EQ(uploads_of.size(), view.pages().size());
  for (const auto& [page, count] : uploads_of) EXPECT_EQ(count, 1) << "page " << page;
  expectDisjoint(vertices, pager.poolLayout().vertices, "vertices");
  expectDisjoint(indices, pager.poolLayout().indices, "indices");
  expectDisjoint(triangles, pager.poolLayout().triangles, "triangles");
  PagerStats stats = pager.stats();
  EXPECT_EQ(stats.pages_resident, view.pages().size());
  EXPECT_EQ(stats.gpu_bytes_used, uploaded);
  EXPECT_EQ(stats.host_bytes_used, 0u);
  EXPECT_EQ(stats.load_errors, 0u);
  EXPECT_EQ(stats.pages_requested + stats.pages_loading + stats.pages_ready, 0u);
}

// ---------------------------------------------------------------------------------------------
// Pager

TEST(Pager, EveryBunnyPageArrivesWithItsDecodedData) {
  expectEveryPageArrivesIntact(bunnyPackage(), 2);
}

TEST(Pager, EveryGridPageArrivesIntactWithThreeLoaders) {
  PackageView view = PackageView::open(gridPackage());
  ASSERT_GE(view.pages().size(), 40u) << "the fixture should have many pages";
  expectEveryPageArrivesIntact(gridPackage(), 3);
}

TEST(Pager, LoadsOnTheRenderThreadWithoutLoaders) {
  expectEveryPageArrivesIntact(gridPackage(), 0);
}

TEST(Pager, LoadsTheHighestPriorityFirst) {
  PackageView view = PackageView::open(gridPackage());
  auto source = std::make_unique<TestSource>(view);
  source->delay = 20ms;
  TestSource* src = source.get();
  PagerOptions options;
  options.loader_threads = 1;
  Pager pager(view, std::move(source), options);
  // Page 20 first, so the loader is busy while the others queue up.
  std::vector<uint32_t> pages = {20};
  pager.beginFrame(1);
  pager.request(20, 1.0f);
  waitForReads(*src, 1);
  for (uint32_t p = 0; p < 12; ++p) pages.push_back(p);
  auto priority = [](uint32_t p) { return static_cast<float>((p * 7) % 12); };  // shuffled
  uint64_t frame = 1;
  RunResult run = runUntilSettled(pager, pages, frame, 10.0, [](auto&) {}, priority);
  ASSERT_TRUE(run.settled);
  std::vector<uint32_t> order = src->order();
  ASSERT_EQ(order.size(), pages.size());
  EXPECT_EQ(order[0], 20u);
  for (size_t k = 2; k < order.size(); ++k)
    EXPECT_GT(priority(order[k - 1]), priority(order[k])) << "read " << k;
}

// While the only loader is busy, frame 2 reverses frame 1's priorities and a second request in
// one frame raises a page to the top: the reads follow the latest order.
TEST(Pager, RenewedRequestsReorderTheQueue) {
  PackageView view = PackageView::open(gridPackage());
  auto source = std::make_unique<TestSource>(view);
  source->delay = 60ms;
  TestSource* src = source.get();
  PagerOptions options;
  options.loader_threads = 1;
  Pager pager(view, std::move(source), options);
  pager.beginFrame(1);
  pager.request(0, 100.0f);
  waitForReads(*src, 1);  // the loader is now busy with page 0
  for (uint32_t p = 1; p <= 5; ++p) pager.request(p, 10.0f * p);
  pager.beginFrame(2);
  for (uint32_t p = 1; p <= 5; ++p) pager.request(p, static_cast<float>(10 - p));
  pager.request(4, 50.0f);
  pager.request(4, 2.0f);  // lower than this frame's 50: ignored
  const auto t0 = Clock::now();
  uint64_t frame = 3;
  while (src->order().size() < 6 && msSince(t0) < 5000) {
    pager.beginFrame(frame++);
    for (uint32_t p = 1; p <= 5; ++p) pager.request(p, static_cast<float>(10 - p) + (p == 4 ? 50 : 0));
    std::this_thread::sleep_for(5ms);
  }
  EXPECT_EQ(src->order(), (std::vector<uint32_t>{0, 4, 1, 2, 3, 5}));
}

TEST(Pager, DropsQueuedPagesNoLongerRequested) {
  PackageView view = PackageView::open(gridPackage());
  auto source = std::make_unique<TestSource>(view);
  source->delay = 150ms;
  TestSource* src = source.get();
  PagerOptions options;
  options.loader_threads = 1;
  Pager pager(view, std::move(source), options);
  pager.beginFrame(1);
  for (uint32_t p = 0; p < 6; ++p) pager.request(p, p == 0 ? 10.0f : 1.0f);
  EXPECT_EQ(pager.state(3), PageState::Requested);
  waitForReads(*src, 1);  // no other call: loaders see requests at once
  EXPECT_EQ(pager.state(0), PageState::Loading) << "the only loader is reading page 0";
  EXPECT_EQ(pager.stats().pages_requested, 5u);
  for (uint64_t frame = 2; frame <= 7; ++frame) {
    pager.beginFrame(frame);
    pager.takeUploads();
  }
  for (uint32_t p = 1; p < 6; ++p) EXPECT_EQ(pager.state(p), PageState::Absent) << "page " << p;
  EXPECT_EQ(pager.stats().pages_requested, 0u);
  std::this_thread::sleep_for(200ms);
  EXPECT_EQ(src->order().size(), 1u) << "dropped pages must not be read";
}

TEST(Pager, SlowSourceNeverBlocksTheRenderThread) {
  PackageView view = PackageView::open(gridPackage());
  auto source = std::make_unique<TestSource>(view);
  source->delay = 50ms;
  PagerOptions options;
  options.loader_threads = 2;
  Pager pager(view, std::move(source), options);
  const std::vector<uint32_t> pages = allPages(view);
  double worst_begin = 0, worst_request = 0, worst_take = 0;
  int frames_with_loads = 0, frames = 0;
  uint64_t frame = 1;
  const auto t0 = Clock::now();
  while (msSince(t0) < 600) {  // about 24 of the pages can load in this time
    auto t = Clock::now();
    pager.beginFrame(frame++);
    worst_begin = std::max(worst_begin, msSince(t));
    t = Clock::now();
    for (uint32_t p : pages) {
      if (pager.resident(p)) pager.touch(p);
      else pager.request(p, static_cast<float>(p));
    }
    worst_request = std::max(worst_request, msSince(t));
    t = Clock::now();
    pager.takeUploads();
    worst_take = std::max(worst_take, msSince(t));
    ++frames;
    if (pager.stats().pages_loading > 0) ++frames_with_loads;
    std::this_thread::sleep_for(2ms);  // "rendering"
  }
  RecordProperty("worst_begin_frame_us", static_cast<int>(worst_begin * 1000));
  RecordProperty("worst_requests_us", static_cast<int>(worst_request * 1000));
  RecordProperty("worst_take_uploads_us", static_cast<int>(worst_take * 1000));
  EXPECT_LT(worst_begin, 20.0);
  EXPECT_LT(worst_request, 20.0);
  EXPECT_LT(worst_take, 20.0);
  EXPECT_GT(frames, 60) << "frames keep going while pages load";
  EXPECT_GT(frames_with_loads, 40);
  const PagerStats stats = pager.stats();
  EXPECT_GT(stats.pages_resident, 0u);
  EXPECT_LT(stats.pages_resident, pages.size()) << "loads should still be in flight";
}

TEST(Pager, GpuBudgetEvictsOnlyStalePagesAndKeepsPinnedOnes) {
  PackageView view = PackageView::open(gridPackage());
  const std::vector<ExpectedPage> expected = expectedPages(view);
  const uint32_t page_count = static_cast<uint32_t>(view.pages().size());
  uint64_t total = 0;
  for (const auto& e : expected) total += e.bytes;
  PagerOptions options;
  options.loader_threads = 2;
  options.gpu_budget_bytes = total * 2 / 5;
  options.evict_after_frames = 5;
  Pager pager(view, makePackagePageSource(view), options);
  const PoolLayout& layout = pager.poolLayout();
  const std::vector<uint32_t> pinned = {page_count - 1, page_count - 2};
  pager.pin(pinned);
  pager.waitForPinned();

  std::vector<uint64_t> last_touch(page_count, 0);
  std::vector<bool> was_resident(page_count, false);
  uint64_t evicted = 0, waited = 0, frame = 1;
  // Each window of pages nearly fills the pool and the next one is disjoint, so its pages must
  // wait until the previous window has gone unused for evict_after_frames.
  const uint32_t window = page_count / 4;
  for (uint32_t start = 0; start + window < page_count - 2; start += window) {
    std::vector<uint32_t> wanted;
    for (uint32_t p = start; p < start + window; ++p) wanted.push_back(p);
    // First stay on one frame while the window loads: the previous window was touched a frame
    // ago, so nothing may be evicted for it yet, and pages that do not fit must wait. Staying
    // put (rather than running frames on the clock) makes that wait happen however slowly the
    // loaders run, as they do under a sanitizer.
    if (start > 0) {
      pager.beginFrame(frame);
      const auto stall = Clock::now();
      uint64_t waited_here = 0;
      while (waited_here == 0 && msSince(stall) < 5000) {
        bool all = true;
        for (uint32_t p : wanted) {
          if (pager.resident(p)) {
            pager.touch(p);
            last_touch[p] = frame;
          } else {
            all = false;
            pager.request(p, 1.0f);
          }
        }
        if (all) break;
        pager.takeUploads();
        waited_here = pager.stats().pages_waiting_for_pool;
        std::this_thread::sleep_for(1ms);
      }
      waited += waited_here;
      evicted += pager.stats().pages_evicted;
      ++frame;
    }
    // Hold the view until the window is resident and a few frames more.
    uint64_t settled = 0;
    const auto t0 = Clock::now();
    while (settled < 3 && msSince(t0) < 5000) {
      pager.beginFrame(frame);
      bool all = true;
      for (uint32_t p : wanted) {
        if (pager.resident(p)) {
          pager.touch(p);
          last_touch[p] = frame;
        } else {
          all = false;
          pager.request(p, 1.0f);
        }
      }
      pager.takeUploads();
      const PagerStats stats = pager.stats();
      ASSERT_LE(stats.gpu_bytes_used, layout.bytes());
      evicted += stats.pages_evicted;
      waited += stats.pages_waiting_for_pool;
      for (uint32_t p = 0; p < page_count; ++p) {
        const bool now = pager.resident(p);
        if (was_resident[p] && !now) {
          EXPECT_EQ(pager.state(p), PageState::Evicted);
          EXPECT_GE(frame, last_touch[p] + options.evict_after_frames)
              << "page " << p << " evicted " << frame - last_touch[p] << " frames after use";
        }
        was_resident[p] = now;
      }
      for (uint32_t p : pinned) ASSERT_TRUE(pager.resident(p)) << "pinned page " << p << " left";
      settled = all ? settled + 1 : 0;
      ++frame;
      std::this_thread::sleep_for(1ms);
    }
    ASSERT_EQ(settled, 3u) << "window at page " << start << " never became resident";
  }
  EXPECT_GT(evicted, 0u);
  EXPECT_GT(waited, 0u) << "the pool was never full: the test does not test eviction";
  EXPECT_LT(pager.stats().pages_resident, page_count);
}

TEST(Pager, HostStagingStaysWithinBudget) {
  PackageView view = PackageView::open(gridPackage());
  const std::vector<ExpectedPage> expected = expectedPages(view);
  uint64_t total = 0, largest = 0;
  for (const auto& e : expected) {
    total += e.bytes;
    largest = std::max(largest, e.bytes);
  }
  PagerOptions options;
  options.loader_threads = 4;
  options.host_budget_bytes = 3 * total / expected.size();  // about three pages
  Pager pager(view, makePackagePageSource(view), options);
  const std::vector<uint32_t> pages = allPages(view);
  uint64_t frame = 1, highest = 0;
  // No uploads for a while: the loaders must stop at the budget.
  for (int k = 0; k < 40; ++k) {
    pager.beginFrame(frame++);
    for (uint32_t p : pages) pager.request(p, 1.0f);
    const PagerStats stats = pager.stats();
    ASSERT_LE(stats.host_bytes_used, options.host_budget_bytes + largest);
    highest = std::max(highest, stats.host_bytes_used);
    std::this_thread::sleep_for(2ms);
  }
  EXPECT_GE(highest, options.host_budget_bytes) << "staging should have filled up";
  EXPECT_LT(pager.stats().pages_ready, pages.size() / 2);
  // Then uploads drain staging and loading resumes until everything is resident.
  RunResult run = runUntilSettled(pager, pages, frame, 20.0, [&](auto&) {
    ASSERT_LE(pager.stats().host_bytes_used, options.host_budget_bytes + largest);
  });
  EXPECT_TRUE(run.settled);
  EXPECT_EQ(pager.stats().host_bytes_used, 0u);
}

TEST(Pager, UploadsRespectThePerFrameCap) {
  PackageView view = PackageView::open(gridPackage());
  const std::vector<ExpectedPage> expected = expectedPages(view);
  uint64_t total = 0;
  for (const auto& e : expected) total += e.bytes;
  for (uint64_t cap : {total / expected.size() * 3, uint64_t{1}}) {
    PagerOptions options;
    options.upload_bytes_per_frame = cap;
    Pager pager(view, makePackagePageSource(view), options);
    uint64_t frame = 1;
    int multi_page_frames = 0;
    RunResult run = runUntilSettled(pager, allPages(view), frame, 20.0, [&](auto& uploads) {
      uint64_t bytes = 0;
      for (const PageUpload& up : uploads) bytes += up.bytes();
      if (uploads.size() > 1) {
        ++multi_page_frames;
        EXPECT_LE(bytes, cap) << "cap " << cap;
      }
      EXPECT_EQ(pager.stats().bytes_uploaded, bytes);
      EXPECT_EQ(pager.stats().pages_uploaded, uploads.size());
    });
    EXPECT_TRUE(run.settled) << "cap " << cap;
    if (cap == 1) {
      EXPECT_EQ(multi_page_frames, 0);
    } else {
      EXPECT_GT(multi_page_frames, 0);
    }
  }
}

TEST(Pager, DestructorReturnsPromptlyWithLoadsInFlight) {
  PackageView view = PackageView::open(gridPackage());
  auto source = std::make_unique<TestSource>(view);
  source->delay = 200ms;
  TestSource* src = source.get();
  auto pager = std::make_unique<Pager>(view, std::move(source), PagerOptions{});
  pager->beginFrame(1);
  for (uint32_t p = 0; p < view.pages().size(); ++p) pager->request(p, 1.0f);
  pager->takeUploads();
  std::this_thread::sleep_for(50ms);
  EXPECT_EQ(pager->stats().pages_loading, 2u);
  const size_t reads = src->order().size();
  const auto t0 = Clock::now();
  pager.reset();
  EXPECT_LT(msSince(t0), 1000.0) << "one read in flight per loader at most";
  EXPECT_EQ(reads, 2u);
}

TEST(Pager, FailedPagesAreCountedAndNeverRetried) {
  PackageView view = PackageView::open(gridPackage());
  auto source = std::make_unique<TestSource>(view);
  source->throw_pages = {1, 5};
  source->truncate_pages = {7};
  TestSource* src = source.get();
  Pager pager(view, std::move(source), PagerOptions{});
  const std::vector<uint32_t> pages = allPages(view);
  uint64_t frame = 1;
  RunResult run = runUntilSettled(pager, pages, frame, 20.0, [](auto&) {});
  ASSERT_TRUE(run.settled);
  // Keep asking for the failed pages: nothing more is read.
  for (int k = 0; k < 10; ++k) {
    pager.beginFrame(frame++);
    for (uint32_t p : {1u, 5u, 7u}) pager.request(p, 5.0f);
    EXPECT_TRUE(pager.takeUploads().empty());
  }
  std::this_thread::sleep_for(20ms);
  for (uint32_t p : {1u, 5u, 7u}) {
    EXPECT_TRUE(pager.failed(p));
    EXPECT_EQ(pager.state(p), PageState::Absent);
    EXPECT_FALSE(pager.resident(p));
    EXPECT_EQ(src->reads(p), 1) << "page " << p;
  }
  const PagerStats stats = pager.stats();
  EXPECT_EQ(stats.load_errors, 3u);
  EXPECT_EQ(stats.pages_resident, pages.size() - 3);
  EXPECT_EQ(stats.host_bytes_used, 0u);
  EXPECT_FALSE(pager.failed(0));
}

// The package file cut short, then overwritten in place, while the pager reads it through the
// real page source (a viewer's package replaced under it): the pages past the new end and the
// changed pages fail (counted, never retried), every other page arrives, and the tables read at
// open stay as they were. With a mapping, reading past the new end was a SIGBUS.
TEST(Pager, APackageCutShortOrOverwrittenWhileOpenFailsOnlyItsPages) {
  const fs::path copy = test::scratchDir() / "grid.twk";
  fs::copy_file(gridPackage(), copy);
  PackageView view = PackageView::open(copy);
  const std::vector<uint32_t> pages = allPages(view);
  ASSERT_GT(pages.size(), 20u);
  const std::string name0(view.objectName(0));
  const uint64_t page_data = view.section(pkg::SectionType::PageData).offset;
  // Keep the first half of the pages' bytes; then zero a page inside what is left.
  const uint32_t half = uint32_t(pages.size() / 2);
  const uint64_t cut = page_data + view.pages()[half].offset;
  fs::resize_file(copy, cut);
  {
    std::fstream file(copy, std::ios::in | std::ios::out | std::ios::binary);
    file.seekp(std::streamoff(page_data + view.pages()[1].offset));
    const std::vector<char> zeros(view.pages()[1].stored_bytes, 0);
    file.write(zeros.data(), std::streamsize(zeros.size()));
  }
  PagerOptions options;
  options.gpu_budget_bytes = 64ull << 20;
  Pager pager(view, makePackagePageSource(view), options);
  uint64_t frame = 1;
  RunResult run = runUntilSettled(pager, pages, frame, 20.0, [](auto&) {});
  ASSERT_TRUE(run.settled);
  for (uint32_t p : pages) {
    const bool lost = p >= half || p == 1;
    EXPECT_EQ(pager.failed(p), lost) << "page " << p;
    EXPECT_EQ(pager.resident(p), !lost) << "page " << p;
  }
  EXPECT_EQ(pager.stats().load_errors, pages.size() - half + 1);
  EXPECT_EQ(view.objectName(0), name0);
  std::vector<uint8_t> raw;
  try {
    view.readPage(half + 1, raw);
    ADD_FAILURE() << "a page past the end was read";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("truncated after it was opened"), std::string::npos)
        << e.what();
  }
}

// Random byte damage in every page, many times over: each page ends resident (the damage hit
// padding or decoded to something the record still accepts) or failed; nothing crashes or hangs.
TEST(Pager, SurvivesCorruptedPageBytes) {
  PackageView view = PackageView::open(gridPackage());
  const std::vector<uint32_t> pages = allPages(view);
  uint64_t errors = 0, resident = 0;
  for (uint32_t seed = 0; seed < 12; ++seed) {
    auto source = std::make_unique<TestSource>(view);
    source->damage = [seed](uint32_t page, std::vector<uint8_t>& raw) {
      std::mt19937 rng(seed * 1000 + page);
      if (raw.empty()) return;
      const int hits = 1 + static_cast<int>(rng() % 4);
      for (int h = 0; h < hits; ++h) raw[rng() % raw.size()] = static_cast<uint8_t>(rng());
      if (seed % 2 && rng() % 2) raw.resize(rng() % raw.size());  // and truncation
    };
    PagerOptions options;
    options.loader_threads = seed % 3;
    Pager pager(view, std::move(source), options);
    uint64_t frame = 1;
    RunResult run = runUntilSettled(pager, pages, frame, 20.0, [](auto&) {});
    ASSERT_TRUE(run.settled) << "seed " << seed << ": pages neither resident nor failed";
    const PagerStats stats = pager.stats();
    EXPECT_EQ(stats.pages_resident + stats.load_errors, pages.size());
    errors += stats.load_errors;
    resident += stats.pages_resident;
  }
  EXPECT_GT(errors, 50u) << "most damage should be caught";
  EXPECT_GT(resident, 0u);
}

// The team's damage harness over the whole package file: the view rejects what it can at open,
// and the pager turns every page it cannot load into a counted error, never a crash or a hang.
TEST(Pager, LoadsDamagedPackagesSafely) {
  const std::string original = test::readFile(gridPackage());
  int opened = 0;
  const int rejected = test::expectRobustToDamage(
      original, "damaged.twk",
      [&](const fs::path& path, SceneSink&) {
        PackageView view = PackageView::open(path);
        ++opened;
        PagerOptions options;
        options.loader_threads = 1;
        Pager pager(view, makePackagePageSource(view), options);
        const std::vector<uint32_t> pages = allPages(view);
        uint64_t frame = 1;
        RunResult run = runUntilSettled(pager, pages, frame, 10.0, [](auto&) {});
        ASSERT_TRUE(run.settled) << "pages neither resident nor failed";
        const PagerStats stats = pager.stats();
        ASSERT_EQ(stats.pages_resident + stats.load_errors, pages.size());
        if (stats.load_errors > 0)
          throw FormatError(view.fileName(), std::to_string(stats.load_errors) + " bad pages");
      },
      150);
  EXPECT_GT(rejected, 100);
  EXPECT_GT(opened, 50) << "corruptions inside page data must reach the pager";
}

TEST(Pager, WaitForPinnedLoadsTheRootPages) {
  PackageView view = PackageView::open(bunnyPackage());
  std::set<uint32_t> roots;
  for (const pkg::ClusterRecord& c : view.clusters())
    if (c.parent_group == pkg::kNone && c.kind == static_cast<uint8_t>(pkg::ClusterKind::Mesh))
      roots.insert(c.page);
  ASSERT_FALSE(roots.empty());
  const std::vector<uint32_t> pinned(roots.begin(), roots.end());
  for (uint32_t threads : {0u, 2u}) {
    auto source = std::make_unique<TestSource>(view);
    source->delay = 30ms;
    PagerOptions options;
    options.loader_threads = threads;
    Pager pager(view, std::move(source), options);
    pager.beginFrame(1);
    pager.pin(pinned);
    pager.waitForPinned();
    for (uint32_t p : pinned) {
      const PageState s = pager.state(p);
      EXPECT_TRUE(s == PageState::Ready || s == PageState::Resident) << "page " << p;
    }
    // Pinned pages come up even when they are not asked for again.
    for (uint64_t frame = 2; frame < 12; ++frame) {
      pager.beginFrame(frame);
      pager.takeUploads();
    }
    for (uint32_t p : pinned) EXPECT_TRUE(pager.resident(p)) << "page " << p;
  }
}

// Hand-made bad pages, each pinned: the error names the file, the pinned page, where and why.
TEST(Pager, WaitForPinnedReportsAPinnedPageThatFails) {
  PackageView view = PackageView::open(gridPackage());
  const uint64_t page_data = view.section(pkg::SectionType::PageData).offset;
  const uint32_t first_cluster_page2 = expectedPages(view)[2].clusters.front();
  struct Case {
    const char* name;
    uint32_t page;
    std::function<void(TestSource&)> damage;
    std::string reason;
    uint64_t position;
  };
  const std::vector<Case> cases = {
      {"source throws", 3, [](TestSource& s) { s.throw_pages = {3}; }, "unreadable page", 4242},
      {"short page", 7, [](TestSource& s) { s.truncate_pages = {7}; },
       "page 7: the source gave", page_data + view.pages()[7].offset},
      {"bad cluster magic", 2,
       [&](TestSource& s) {
         s.damage = [&](uint32_t page, std::vector<uint8_t>& raw) {
           if (page == 2) raw[view.clusters()[first_cluster_page2].page_offset] ^= 0xff;
         };
       },
       "cluster " + std::to_string(first_cluster_page2), page_data + view.pages()[2].offset},
  };
  for (const Case& c : cases)
    for (uint32_t threads : {0u, 2u}) {
      SCOPED_TRACE(std::string(c.name) + ", loaders: " + std::to_string(threads));
      auto source = std::make_unique<TestSource>(view);
      c.damage(*source);
      Pager pager(view, std::move(source), PagerOptions{.loader_threads = threads});
      const std::vector<uint32_t> pinned = {c.page - 1, c.page, c.page + 1};
      pager.pin(pinned);
      try {
        pager.waitForPinned();
        ADD_FAILURE() << "waitForPinned must throw";
      } catch (const FormatError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("grid.twk"), std::string::npos) << what;
        EXPECT_NE(what.find("pinned page " + std::to_string(c.page)), std::string::npos) << what;
        EXPECT_NE(what.find(c.reason), std::string::npos) << what;
        EXPECT_EQ(e.where(), FormatError::Where::Byte);
        EXPECT_EQ(e.position(), c.position) << what;
      }
      EXPECT_EQ(pager.stats().load_errors, 1u);
      EXPECT_TRUE(pager.failed(c.page));
    }
}

TEST(Pager, APageLargerThanThePoolFailsInsteadOfWaiting) {
  PackageView view = PackageView::open(gridPackage());
  const std::vector<ExpectedPage> expected = expectedPages(view);
  PagerOptions options;
  options.gpu_budget_bytes = 3000;  // room for about 200 triangles
  options.evict_after_frames = 1;
  Pager pager(view, makePackagePageSource(view), options);
  std::vector<uint32_t> pages = allPages(view);
  uint64_t frame = 1;
  uint32_t too_big = 0;
  for (uint32_t p : pages)
    if (expected[p].bytes > pager.poolLayout().bytes()) ++too_big;
  ASSERT_GT(too_big, 0u);
  // Ask for one page at a time, so the small pool only has to hold one.
  for (uint32_t p : pages) {
    RunResult run = runUntilSettled(pager, {p}, frame, 5.0, [](auto&) {});
    ASSERT_TRUE(run.settled) << "page " << p << " neither resident nor failed";
    if (expected[p].bytes > pager.poolLayout().bytes()) {
      EXPECT_TRUE(pager.failed(p)) << p;
    }
    ASSERT_LE(pager.stats().gpu_bytes_used, pager.poolLayout().bytes());
  }
  EXPECT_GE(pager.stats().load_errors, too_big);
}

}  // namespace
}  // namespace tw
