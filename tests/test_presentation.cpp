// Presentation through the command a user runs: the ocean and the sky drawn around the generated
// plant as "no object", stereo pairs whose eyes see a plate shifted as their separation says, and
// `render --video` read back by ffprobe.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "camera.h"
#include "camera_path.h"
#include "generated_plant_support.h"
#include "image_compare.h"
#include "package_view.h"
#include "stereo.h"
#include "test_support.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 320, kHeight = 200;
const std::string kSetting = " --ocean --sky --waterline -10";

struct Frame {
  std::vector<uint8_t> rgba;
  std::vector<uint32_t> ids;
};

Frame renderStill(const fs::path& path, const fs::path& out, const std::string& options) {
  const test::CommandResult r = test::runTerawalk(
      "render --quiet " + test::generatedPlant().package.string() + " --path " + path.string() +
      " --size " + std::to_string(kWidth) + "x" + std::to_string(kHeight) + " --png --out " + out.string() +
      options);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  Frame f;
  f.rgba = readPngRgba(out / "frame_00000.png").rgba;
  f.ids = idsFromRgba(readPngRgba(out / "ids_00000.png").rgba);
  return f;
}

// The plant's side seen from 60 m off its hull, 5 m above the deck and looking down a little:
// the hull below the waterline (-10 m) lies behind the water, the modules above stand in the sky.
Camera sideCamera() {
  const PackageView view = PackageView::open(test::generatedPlant().package);
  const glm::dvec3 lo = view.origin() + glm::dvec3(view.header().bounds_min[0], view.header().bounds_min[1],
                                                   view.header().bounds_min[2]);
  const glm::dvec3 hi = view.origin() + glm::dvec3(view.header().bounds_max[0], view.header().bounds_max[1],
                                                   view.header().bounds_max[2]);
  Camera camera;
  camera.position = {0.5 * (lo.x + hi.x), lo.y - 60.0, 5.0};
  camera.lookAt({0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), -8.0});
  return camera;
}

TEST(Environment, TheOceanAndTheSkyAreNoObjectAndLeaveEverythingAboveTheHorizonAlone) {
  const fs::path dir = test::scratchDir();
  const Camera camera = sideCamera();
  CameraPath still;
  still.keys.push_back({0.0, camera});
  writeCameraPath(still, dir / "side.path");
  const Frame bare = renderStill(dir / "side.path", dir / "bare", "");
  const Frame set = renderStill(dir / "side.path", dir / "set", kSetting);
  ASSERT_EQ(bare.ids.size(), set.ids.size());

  // The horizon: where a level ray from the eye lands in the image. Water and waves lie below the
  // eye, so nothing above that row may change; the sky only fills the background.
  const auto horizon = imagePoint(camera, kWidth, kHeight, camera.position + 1e5 * glm::dvec3(camera.forward().x, camera.forward().y, 0.0));
  ASSERT_TRUE(horizon.has_value());
  const int horizon_row = int(horizon->y);
  ASSERT_GT(horizon_row, 20);
  ASSERT_LT(horizon_row, kHeight - 20);
  size_t covered = 0, background_left = 0, water = 0, changed_above = 0;
  const uint8_t* bg = bare.rgba.data();  // the top-left pixel: background without the setting
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const size_t p = size_t(y) * kWidth + x;
      // Ocean and sky draw "no object": an id is either the model's own or 0.
      ASSERT_TRUE(set.ids[p] == bare.ids[p] || set.ids[p] == 0u) << "pixel " << x << "," << y;
      if (y < horizon_row - 2) changed_above += set.ids[p] != bare.ids[p];
      if (bare.ids[p] != 0 && set.ids[p] == 0) ++covered;  // a part under the water
      if (set.ids[p] == 0) {
        const uint8_t* c = &set.rgba[4 * p];
        background_left += c[0] == bg[0] && c[1] == bg[1] && c[2] == bg[2];
        water += y > horizon_row + 2;
      }
    }
  EXPECT_EQ(changed_above, 0u) << "the setting hid part of the model above the horizon";
  EXPECT_GT(covered, 200u) << "the hull below the waterline is behind the water";
  EXPECT_GT(water, size_t(kWidth) * 10) << "the ocean reaches the bottom of the frame";
  EXPECT_EQ(background_left, 0u) << "the sky and the ocean fill all the background";
}

// A 4 m plate 20 m ahead, eyes 1 m apart converging at 10 m: in a side-by-side frame the plate's
// centre lies P00 * s * (1/D - 1/d) apart in normalized device units between the halves (the
// right eye sees it further right: behind the zero-parallax plane the disparity is uncrossed),
// and at d = D the halves are the same picture.
TEST(Stereo, ASideBySideFrameShiftsAPlateByTheEyeSeparation) {
  const fs::path dir = test::scratchDir();
  test::writeFile(dir / "plate.obj", "v -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nf 1 2 3\nf 1 3 4\n");
  ASSERT_EQ(test::runTerawalk("preprocess --quiet " + (dir / "plate.obj").string() + " -o " + (dir / "plate.twk").string()).exit_code, 0);
  constexpr int kEyeWidth = 200, kEyeHeight = 150;
  const double separation = 1.0, zero_parallax = 10.0;
  for (const double distance : {20.0, 10.0}) {
    SCOPED_TRACE(distance);
    Camera camera;
    camera.position = {0.0, -distance, 0.0};
    camera.lookAt({0.0, 0.0, 0.0});
    CameraPath still;
    still.keys.push_back({0.0, camera});
    writeCameraPath(still, dir / "plate.path");
    const fs::path out = dir / ("sbs" + std::to_string(int(distance)));
    const test::CommandResult r = test::runTerawalk(
        "render --quiet " + (dir / "plate.twk").string() + " --path " + (dir / "plate.path").string() +
        " --size " + std::to_string(2 * kEyeWidth) + "x" + std::to_string(kEyeHeight) +
        " --stereo side-by-side --eye-separation 1 --zero-parallax 10 --png --out " + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const RgbaImage frame = readPngRgba(out / "frame_00000.png");
    ASSERT_EQ(frame.width, 2 * kEyeWidth);
    // The plate's pixels (not the background's colour, taken at a corner) in each half.
    auto centre = [&](int x0) {
      const uint8_t* bg = &frame.rgba[0];
      double sum = 0.0;
      int n = 0;
      for (int y = 0; y < kEyeHeight; ++y)
        for (int x = x0; x < x0 + kEyeWidth; ++x) {
          const uint8_t* p = &frame.rgba[4 * (size_t(y) * frame.width + x)];
          if (std::abs(p[0] - bg[0]) + std::abs(p[1] - bg[1]) + std::abs(p[2] - bg[2]) > 30) {
            sum += x - x0 + 0.5;
            ++n;
          }
        }
      EXPECT_GT(n, 400);
      return n > 0 ? sum / n : 0.0;
    };
    const double left = centre(0), right = centre(kEyeWidth);
    const double p00 = camera.projection(double(kEyeWidth) / kEyeHeight)[0][0];
    const double expected_px = p00 * separation * (1.0 / zero_parallax - 1.0 / distance) * 0.5 * kEyeWidth;
    EXPECT_NEAR(right - left, expected_px, 0.5) << "left " << left << ", right " << right;
    if (distance == zero_parallax) {
      EXPECT_NEAR(left, right, 0.25);
    }
  }
}

struct Probe {
  int frames = 0, width = 0, height = 0;
  std::string rate;
};

Probe probe(const fs::path& video) {
  const test::CommandResult r = test::runShell(
      "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
      "stream=nb_read_frames,width,height,r_frame_rate -of default=noprint_wrappers=1 " +
      video.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  Probe p;
  char rate[32] = {};
  for (size_t start = 0; start < r.output.size();) {
    const size_t end = std::min(r.output.find('\n', start), r.output.size());
    const std::string line = r.output.substr(start, end - start);
    std::sscanf(line.c_str(), "nb_read_frames=%d", &p.frames);
    std::sscanf(line.c_str(), "width=%d", &p.width);
    std::sscanf(line.c_str(), "height=%d", &p.height);
    if (std::sscanf(line.c_str(), "r_frame_rate=%31s", rate) == 1) p.rate = rate;
    start = end + 1;
  }
  return p;
}

TEST(Environment, RenderWritesVideosThatFfprobeDecodesFrameForFrame) {
  if (test::runShell("command -v ffmpeg && command -v ffprobe").exit_code != 0)
    GTEST_SKIP() << "ffmpeg is not installed (tools/install_deps.sh installs it)";
  const fs::path dir = test::scratchDir();
  for (const std::string name : {"walk.mp4", "walk.avi"}) {
    SCOPED_TRACE(name);
    const test::CommandResult r = test::runTerawalk(
        "render --quiet " + test::generatedPlant().package.string() +
        " --orbit 12 --fps 6 --size 160x120 --video " + (dir / name).string() + kSetting);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const Probe p = probe(dir / name);
    EXPECT_EQ(p.frames, 12);
    EXPECT_EQ(p.width, 160);
    EXPECT_EQ(p.height, 120);
    EXPECT_EQ(p.rate, "6/1");
  }
}

TEST(Environment, AVideoWithoutFfmpegOrOnAFullDiskIsAClearErrorAndThePngsAreKept) {
  const fs::path dir = test::scratchDir();
  // No ffmpeg on PATH: refused before anything is rendered.
  const test::CommandResult missing = test::runShell(
      "PATH=/nonexistent " + std::string(TW_TERAWALK_EXE) + " render --quiet " +
      test::generatedPlant().package.string() + " --orbit 3 --size 160x120 --video " +
      (dir / "a.mp4").string());
  EXPECT_EQ(missing.exit_code, 1) << missing.output;
  EXPECT_NE(missing.output.find("a.mp4: ffmpeg was not found on PATH"), std::string::npos) << missing.output;

  // A disk that fills while ffmpeg writes: the error names the file and ffmpeg's reason, and
  // every frame is still written as a picture.
  const fs::path disk = dir / "small-disk";
  fs::create_directories(disk);
  if (test::runShell("mount -t tmpfs -o size=64k tmpfs " + disk.string()).exit_code != 0)
    GTEST_SKIP() << "mounting a tmpfs needs root (CI runs as root)";
  struct Unmount {
    std::string path;
    ~Unmount() { test::runShell("umount " + path); }
  } unmount{disk.string()};
  const test::CommandResult full = test::runTerawalk(
      "render --quiet " + test::generatedPlant().package.string() +
      " --orbit 40 --fps 10 --size 320x200 --video " + (disk / "walk.avi").string() + " --png --out " +
      (dir / "frames").string());
  EXPECT_EQ(full.exit_code, 1) << full.output;
  EXPECT_NE(full.output.find((disk / "walk.avi").string()), std::string::npos) << full.output;
  EXPECT_NE(full.output.find("No space left on device"), std::string::npos) << full.output;
  for (int i = 0; i < 40; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.png", i);
    EXPECT_TRUE(fs::exists(dir / "frames" / name)) << name;
  }
}

}  // namespace
}  // namespace tw
