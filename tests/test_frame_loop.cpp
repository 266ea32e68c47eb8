// The walkthrough frame loop on llvmpipe: first frames show the model, the reference draws every
// full-resolution triangle, a model at plant coordinates renders like one at the origin, a slow
// page reader never stalls a frame (ancestors stand in, then the cut converges), and the adaptive
// tau moves the right way.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "bunny_package_support.h"
#include "camera_test_support.h"
#include "camera_path.h"
#include "egl_context.h"
#include "frame_loop.h"
#include "package_rewrite_support.h"
#include "preprocess_driver.h"
#include "test_support.h"
#include "tws_writer.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

using test::bunnyPackage;

// The bunny with every mesh cluster in a page of its own (it packs into 5 pages otherwise), for
// paging tests that need residency to follow the cut closely.
fs::path pagedBunnyPackage() {
  static const fs::path path = [] {
    fs::path out = test::processScratchDir("frame_loop_bunny") / "bunny-paged.twk";
    test::rewritePackage(PackageView::open(bunnyPackage()), out, false, true);
    return out;
  }();
  return path;
}

// A row of closed boxes, each its own object, placed at `origin` (world metres).
fs::path boxesPackage(const fs::path& dir, const std::string& name, const glm::dvec3& origin) {
  const fs::path scene = dir / (name + ".tws");
  {
    TwsWriter writer(scene);
    writer.onLayer(0, {"boxes", 0xff3366ccu});
    for (uint32_t i = 0; i < 8; ++i) {
      SceneObject object;
      object.info.id = i;
      object.info.name = "box " + std::to_string(i);
      object.info.transform.origin = origin + glm::dvec3(i * 3.0, 0.0, 0.0);
      TriangleMesh mesh;
      for (int corner = 0; corner < 8; ++corner)
        mesh.positions.push_back(glm::vec3(corner & 1 ? 1.0f : -1.0f, corner & 2 ? 1.0f : -1.0f,
                                           corner & 4 ? 1.0f : -1.0f));
      mesh.indices = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                      2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
      object.geometry = std::move(mesh);
      writer.onObject(object);
    }
    writer.finish();
  }
  const fs::path out = dir / (name + ".twk");
  PreprocessOptions options;
  options.inputs = {scene};
  options.output = out;
  runPreprocess(options);
  return out;
}

using test::lookingAt;

double coveredShare(GlRenderer& renderer, uint32_t object_limit) {
  std::vector<uint32_t> ids;
  renderer.readObjectIds(ids);
  size_t covered = 0;
  for (uint32_t id : ids) {
    EXPECT_LE(id, object_limit);
    covered += id != 0;
  }
  return double(covered) / double(ids.size());
}

class FrameLoop : public ::testing::Test {
 protected:
  EglContext context_;
};

TEST_F(FrameLoop, FirstFrameShowsTheWholeBunny) {
  WalkthroughOptions options;
  options.width = 160;
  options.height = 120;
  Walkthrough walk(bunnyPackage(), options);
  const glm::dvec3 center = 0.5 * (walk.worldMin() + walk.worldMax());
  const double size = glm::length(walk.worldMax() - walk.worldMin());
  const FrameStats stats =
      walk.renderFrame(lookingAt(center + glm::dvec3(0, -1.5 * size, 0.3 * size), center), 0.0);
  EXPECT_GT(stats.triangles_drawn, 0u);
  EXPECT_LT(stats.triangles_drawn, walk.package().header().total_triangles);
  EXPECT_GT(coveredShare(walk.renderer(), uint32_t(walk.package().objects().size())), 0.05);
}

TEST_F(FrameLoop, ReferenceDrawsEveryFullResolutionTriangle) {
  WalkthroughOptions options;
  options.width = 160;
  options.height = 120;
  options.reference = true;
  Walkthrough walk(bunnyPackage(), options);
  const glm::dvec3 center = 0.5 * (walk.worldMin() + walk.worldMax());
  const double size = glm::length(walk.worldMax() - walk.worldMin());
  const FrameStats stats =
      walk.renderFrame(lookingAt(center + glm::dvec3(0, -1.5 * size, 0.0), center), 0.0);
  EXPECT_EQ(stats.triangles_drawn, walk.package().header().total_triangles);
}

TEST_F(FrameLoop, PlantCoordinatesRenderLikeTheOrigin) {
  const glm::dvec3 far_origin(500000.0, 7000000.0, 0.0);
  const fs::path dir = test::scratchDir();
  const fs::path near_package = boxesPackage(dir, "near", glm::dvec3(0.0));
  const fs::path far_package = boxesPackage(dir, "far", far_origin);
  WalkthroughOptions options;
  options.width = 160;
  options.height = 120;
  std::vector<uint32_t> near_ids, far_ids;
  // A camera close to the boxes (a metre or so), moving by a millimetre per frame: at these
  // coordinates a float eye would move in 0.5 m steps and the image would jump.
  for (int step = 0; step < 3; ++step) {
    const glm::dvec3 eye(4.0 + 0.001 * step, -3.0, 0.5);
    const glm::dvec3 target(6.0, 0.0, 0.0);
    {
      Walkthrough walk(near_package, options);
      walk.renderFrame(lookingAt(eye, target), 0.0);
      walk.renderer().readObjectIds(near_ids);
    }
    {
      Walkthrough walk(far_package, options);
      walk.renderFrame(lookingAt(far_origin + eye, far_origin + target), 0.0);
      walk.renderer().readObjectIds(far_ids);
    }
    ASSERT_EQ(near_ids.size(), far_ids.size());
    size_t differ = 0, covered = 0;
    for (size_t i = 0; i < near_ids.size(); ++i) {
      differ += near_ids[i] != far_ids[i];
      covered += near_ids[i] != 0;
    }
    EXPECT_GT(covered, near_ids.size() / 10) << "step " << step;
    EXPECT_LE(differ, near_ids.size() / 1000) << "step " << step;
  }
}

// Reads pages through the package, slowly, counting reads.
class SlowSource : public PageSource {
 public:
  SlowSource(const PackageView& view, std::chrono::milliseconds delay)
      : inner_(makePackagePageSource(view)), delay_(delay) {}
  void read(uint32_t page, std::vector<uint8_t>& raw) override {
    std::this_thread::sleep_for(delay_);
    inner_->read(page, raw);
  }

 private:
  std::unique_ptr<PageSource> inner_;
  std::chrono::milliseconds delay_;
};

TEST_F(FrameLoop, SlowPagesNeverStallAFrameAndTheCutConverges) {
  WalkthroughOptions options;
  options.width = 160;
  options.height = 120;
  options.tau_px = 0.5;
  options.pager.loader_threads = 1;
  options.page_source = [](const PackageView& view) {
    return std::make_unique<SlowSource>(view, std::chrono::milliseconds(400));
  };
  Walkthrough walk(bunnyPackage(), options);
  const glm::dvec3 center = 0.5 * (walk.worldMin() + walk.worldMax());
  const double size = glm::length(walk.worldMax() - walk.worldMin());
  // Teleport close: the cut wants pages that take 400 ms each to read (long, so that a loaded CI
  // machine's slow frames are never mistaken for a wait).
  const Camera close = lookingAt(center + glm::dvec3(0, -0.6 * size, 0.1 * size), center);
  FrameStats first = walk.renderFrame(close, 0.0);
  EXPECT_GT(first.ancestor_fallbacks, 0u);
  EXPECT_GT(first.triangles_drawn, 0u);  // the resident ancestors, never a hole
  EXPECT_LT(first.frame_ms, 400.0) << "the frame waited for a page read";
  FrameStats last = first;
  int frames = 1;
  const auto start = std::chrono::steady_clock::now();
  while (last.ancestor_fallbacks > 0 &&
         std::chrono::steady_clock::now() - start < std::chrono::seconds(60)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    last = walk.renderFrame(close, 0.0);
    EXPECT_LT(last.frame_ms, 400.0) << "frame " << frames << " waited for a page read";
    ++frames;
  }
  EXPECT_EQ(last.ancestor_fallbacks, 0u) << "the cut did not converge in " << frames << " frames";
  EXPECT_GT(last.triangles_drawn, first.triangles_drawn);
}

// A replay at a low frame rate (camera time 2 s a frame, four times the 0.5 s prefetch horizon):
// the prefetch looks one frame's step ahead, so with the camera moving steadily toward the model
// every frame after the first two finds the pages its cut wants already loaded. The render thread
// loads (loader_threads 0), so which pages are resident at each frame does not depend on timing.
TEST_F(FrameLoop, PrefetchCoversTheNextFrameAtLowFrameRates) {
  uint32_t fallbacks_with = 0, fallbacks_without = 0;
  for (bool prefetch : {true, false}) {
    WalkthroughOptions options;
    options.width = 160;
    options.height = 120;
    options.tau_px = 0.5;
    options.pager.loader_threads = 0;
    options.prefetch = prefetch;
    Walkthrough walk(pagedBunnyPackage(), options);
    const glm::dvec3 center = 0.5 * (walk.worldMin() + walk.worldMax());
    const double size = glm::length(walk.worldMax() - walk.worldMin());
    uint32_t& fallbacks = prefetch ? fallbacks_with : fallbacks_without;
    for (int k = 0; k < 7; ++k) {
      const Camera camera = lookingAt(center + glm::dvec3(0, -(12.0 - 1.8 * k) * size, 0), center);
      const FrameStats stats = walk.renderFrame(camera, 2.0 * k);
      // Frame 0 has no velocity yet, so frame 1 may wait for its own pages.
      if (k >= 2) fallbacks += stats.ancestor_fallbacks;
    }
  }
  EXPECT_EQ(fallbacks_with, 0u);
  EXPECT_GT(fallbacks_without, 0u);  // the test has teeth: without prefetch the cut lags
}

TEST_F(FrameLoop, TargetFpsMovesTau) {
  WalkthroughOptions options;
  options.width = 160;
  options.height = 120;
  options.target_fps = 1e6;  // unreachable: tau must rise
  Walkthrough fast(bunnyPackage(), options);
  const glm::dvec3 center = 0.5 * (fast.worldMin() + fast.worldMax());
  const double size = glm::length(fast.worldMax() - fast.worldMin());
  const Camera camera = lookingAt(center + glm::dvec3(0, -1.5 * size, 0.0), center);
  for (int i = 0; i < 5; ++i) fast.renderFrame(camera, i / 30.0);
  EXPECT_GT(fast.tau(), options.tau_px);
  options.target_fps = 0.001;  // trivially met: tau must fall to its floor
  Walkthrough slow(bunnyPackage(), options);
  for (int i = 0; i < 40; ++i) slow.renderFrame(camera, i / 30.0);
  EXPECT_DOUBLE_EQ(slow.tau(), options.min_tau_px);
}

}  // namespace
}  // namespace tw
