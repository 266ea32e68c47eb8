// Image comparison: PSNR, the neighbourhood tolerance for colour and ids (both directions), the
// diff image, PNG reading and writing on good and damaged files, and `terawalk compare` end to
// end through the real executable on small frame directories written here.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "image_compare.h"
#include "test_support.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

// A small RGBA8 image with its ids, built pixel by pixel.
struct Frame {
  int width = 0, height = 0;
  std::vector<uint8_t> rgba;
  std::vector<uint32_t> ids;

  Frame(int w, int h) : width(w), height(h), rgba(size_t(w) * h * 4, 255), ids(size_t(w) * h, 0) {}

  void set(int x, int y, uint8_t r, uint8_t g, uint8_t b, uint32_t id) {
    uint8_t* p = &rgba[(size_t(y) * width + x) * 4];
    p[0] = r;
    p[1] = g;
    p[2] = b;
    p[3] = 255;
    ids[size_t(y) * width + x] = id;
  }
  const uint8_t* at(int x, int y) const { return &rgba[(size_t(y) * width + x) * 4]; }
};

// A gradient background (id 1) with a bright square (id 2): varied enough that no pixel is
// accidentally matched by a distant neighbour.
Frame scene(int w = 40, int h = 30) {
  Frame f(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) f.set(x, y, uint8_t(x * 3), uint8_t(y * 5), 60, 1);
  for (int y = 10; y < std::min(20, h); ++y)
    for (int x = 12; x < std::min(26, w); ++x) f.set(x, y, 250, 250, 40, 2);
  return f;
}

// Black left of `edge_x`, white from it on; ids 1 and 2 likewise.
Frame edge(int edge_x, int w = 40, int h = 30) {
  Frame f(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (x < edge_x) f.set(x, y, 0, 0, 0, 1);
      else f.set(x, y, 255, 255, 255, 2);
  return f;
}

ImageCompareResult compare(const Frame& a, const Frame& b, int tolerance_px = 1,
                           int colour_threshold = 24, std::vector<uint8_t>* diff = nullptr,
                           bool with_ids = true) {
  ImageCompareOptions options;
  options.neighbourhood_px = tolerance_px;
  options.colour_threshold = colour_threshold;
  std::span<const uint32_t> ids_a, ids_b;
  if (with_ids) {
    ids_a = a.ids;
    ids_b = b.ids;
  }
  return compareImages(a.width, a.height, a.rgba, b.rgba, ids_a, ids_b, options, diff);
}

TEST(ImageCompare, IdenticalImagesAre999DbAndFullMatch) {
  Frame a = scene();
  ImageCompareResult r = compare(a, a);
  EXPECT_EQ(r.width, 40);
  EXPECT_EQ(r.height, 30);
  EXPECT_EQ(r.psnr_db, kIdenticalPsnrDb);
  EXPECT_EQ(r.match_share, 1.0);
  EXPECT_EQ(r.colour_mismatch_share, 0.0);
  EXPECT_EQ(r.id_mismatch_share, 0.0);
}

TEST(ImageCompare, OnePixelEdgeShiftMatchesWithToleranceOnly) {
  Frame a = edge(20), b = edge(21);
  ImageCompareResult tolerant = compare(a, b, 1);
  EXPECT_EQ(tolerant.match_share, 1.0);
  EXPECT_EQ(tolerant.colour_mismatch_share, 0.0);
  EXPECT_EQ(tolerant.id_mismatch_share, 0.0);
  EXPECT_LT(tolerant.psnr_db, 30.0);  // PSNR has no tolerance: the column really differs

  // Without tolerance exactly the column x = 20 differs, in colour and in id.
  ImageCompareResult strict = compare(a, b, 0);
  EXPECT_DOUBLE_EQ(strict.colour_mismatch_share, 1.0 / 40);
  EXPECT_DOUBLE_EQ(strict.id_mismatch_share, 1.0 / 40);
  EXPECT_DOUBLE_EQ(strict.match_share, 1.0 - 1.0 / 40);

  // A two-pixel shift is beyond a one-pixel tolerance: the middle column of the three differs.
  // At x = 20 A's white has no white in B within a pixel; at x = 21 B's black has no black in A.
  ImageCompareResult far = compare(a, edge(22), 1);
  EXPECT_DOUBLE_EQ(far.colour_mismatch_share, 2.0 / 40);
  EXPECT_DOUBLE_EQ(far.id_mismatch_share, 2.0 / 40);
}

TEST(ImageCompare, IdBlobMismatchShareIsTheBlobsShare) {
  Frame a = scene(), b = scene();
  // A 6x5 blob of another object, same colour: only ids can see it.
  for (int y = 3; y < 8; ++y)
    for (int x = 30; x < 36; ++x) b.ids[size_t(y) * b.width + x] = 99;
  ImageCompareResult r = compare(a, b, 1);
  EXPECT_DOUBLE_EQ(r.id_mismatch_share, 30.0 / (40 * 30));
  EXPECT_DOUBLE_EQ(r.match_share, 1.0 - 30.0 / (40 * 30));
  EXPECT_EQ(r.colour_mismatch_share, 0.0);
  EXPECT_EQ(r.psnr_db, kIdenticalPsnrDb);

  // Without ids the same images match completely.
  ImageCompareResult colour_only = compare(a, b, 1, 24, nullptr, false);
  EXPECT_EQ(colour_only.match_share, 1.0);
  EXPECT_EQ(colour_only.id_mismatch_share, 0.0);
}

TEST(ImageCompare, ColourThresholdIsInclusivePerChannel) {
  Frame a(16, 12), b(16, 12);
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 16; ++x) {
      a.set(x, y, 100, 100, 100, 1);
      b.set(x, y, 100, 124, 100, 1);  // green off by 24
    }
  EXPECT_EQ(compare(a, b, 1, 24).match_share, 1.0);
  EXPECT_EQ(compare(a, b, 1, 23).colour_mismatch_share, 1.0);
  EXPECT_EQ(compare(a, b, 1, 23).match_share, 0.0);
  // MSE over three channels of which one is off by 24.
  const double expected = 10.0 * std::log10(255.0 * 255.0 / (24.0 * 24.0 / 3.0));
  EXPECT_NEAR(compare(a, b).psnr_db, expected, 1e-9);
  // Alpha is not colour.
  Frame c = a;
  for (size_t i = 3; i < c.rgba.size(); i += 4) c.rgba[i] = 0;
  EXPECT_EQ(compare(a, c, 0, 0).match_share, 1.0);
}

TEST(ImageCompare, ThinFeatureMissingFromEitherImageIsCaught) {
  Frame plain(30, 20);
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 30; ++x) plain.set(x, y, 20, 20, 20, 1);
  Frame line = plain;
  for (int x = 5; x < 25; ++x) line.set(x, 10, 230, 230, 230, 1);
  // The plain image's pixels all have a plain neighbour in `line`; only the other direction sees
  // the line, and the result must not depend on the argument order.
  ImageCompareResult ab = compare(plain, line, 1), ba = compare(line, plain, 1);
  EXPECT_DOUBLE_EQ(ab.colour_mismatch_share, 20.0 / 600);
  EXPECT_DOUBLE_EQ(ba.colour_mismatch_share, 20.0 / 600);
  EXPECT_DOUBLE_EQ(ab.psnr_db, ba.psnr_db);
}

TEST(ImageCompare, DiffImageMarksIdsMagentaColourRedRestGrey) {
  Frame a = scene(), b = scene();
  b.ids[size_t(2) * b.width + 2] = 77;          // id only at (2, 2)
  b.set(35, 25, 0, 255, 0, 1);                  // colour only at (35, 25)
  b.set(5, 25, 0, 0, 255, 55);                  // both at (5, 25)
  std::vector<uint8_t> diff;
  ImageCompareResult r = compare(a, b, 1, 24, &diff);
  ASSERT_EQ(diff.size(), a.rgba.size());
  auto px = [&](int x, int y) { return &diff[(size_t(y) * 40 + x) * 4]; };
  auto is = [&](int x, int y, uint8_t cr, uint8_t cg, uint8_t cb) {
    const uint8_t* p = px(x, y);
    return p[0] == cr && p[1] == cg && p[2] == cb && p[3] == 255;
  };
  EXPECT_TRUE(is(2, 2, 255, 0, 255));   // id: magenta
  EXPECT_TRUE(is(35, 25, 255, 0, 0));   // colour only: red
  EXPECT_TRUE(is(5, 25, 255, 0, 255));  // both: magenta wins
  int marked = 0;
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) {
      const uint8_t* p = px(x, y);
      if (p[0] == p[1] && p[1] == p[2]) {
        EXPECT_EQ(p[3], 255);
        EXPECT_LE(p[0], 128);  // dimmed
      } else {
        ++marked;
      }
    }
  EXPECT_EQ(marked, 3);
  EXPECT_DOUBLE_EQ(r.match_share, 1.0 - 3.0 / 1200);
  // The grey follows the reference's brightness.
  EXPECT_GT(px(15, 15)[0], px(0, 0)[0]);
}

TEST(ImageCompare, ToleranceWindowIsClippedAtTheBorder) {
  Frame a(2, 2), b(2, 2);
  a.set(0, 0, 255, 0, 0, 3);
  b.set(1, 1, 255, 0, 0, 3);
  // Radius 5 covers everything from everywhere, and must not read outside the 2x2 image.
  EXPECT_EQ(compare(a, b, 5).match_share, 1.0);
  EXPECT_LT(compare(a, b, 0).match_share, 1.0);
  // An empty image is identical.
  Frame empty(0, 0);
  ImageCompareResult r = compare(empty, empty);
  EXPECT_EQ(r.psnr_db, kIdenticalPsnrDb);
  EXPECT_EQ(r.match_share, 1.0);
}

TEST(ImageCompare, RejectsMismatchedBuffersAndBadOptions) {
  Frame a = scene(40, 30), b = scene(30, 40), c = scene(20, 10);
  ImageCompareOptions options;
  // Same pixel count, but wrong for the size given.
  EXPECT_THROW(compareImages(40, 30, a.rgba, c.rgba, {}, {}, options), std::invalid_argument);
  EXPECT_THROW(compareImages(40, 31, a.rgba, a.rgba, {}, {}, options), std::invalid_argument);
  EXPECT_THROW(compareImages(-1, 30, a.rgba, a.rgba, {}, {}, options), std::invalid_argument);
  // Ids on one side only.
  EXPECT_THROW(compareImages(40, 30, a.rgba, a.rgba, a.ids, {}, options), std::invalid_argument);
  EXPECT_THROW(compareImages(40, 30, a.rgba, a.rgba, a.ids, c.ids, options),
               std::invalid_argument);
  try {
    compareImages(40, 30, a.rgba, c.rgba, {}, {}, options);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("40x30"), std::string::npos) << e.what();
  }
  ImageCompareOptions bad = options;
  bad.neighbourhood_px = -1;
  EXPECT_THROW(compareImages(40, 30, a.rgba, a.rgba, {}, {}, bad), std::invalid_argument);
  bad = options;
  bad.colour_threshold = 256;
  EXPECT_THROW(compareImages(40, 30, a.rgba, a.rgba, {}, {}, bad), std::invalid_argument);
  // b has the right byte count for 30x40 only.
  EXPECT_NO_THROW(compareImages(30, 40, b.rgba, b.rgba, b.ids, b.ids, options));
}

TEST(ImagePng, RoundTripsColourAndIds) {
  auto dir = test::scratchDir();
  Frame f = scene(33, 17);
  writePngRgba(dir / "c.png", f.width, f.height, f.rgba);
  RgbaImage back = readPngRgba(dir / "c.png");
  EXPECT_EQ(back.width, 33);
  EXPECT_EQ(back.height, 17);
  EXPECT_EQ(back.rgba, f.rgba);

  // Ids use all four bytes, alpha included (which a PNG writer must not premultiply away).
  std::vector<uint32_t> ids = {0u, 1u, 0x01020304u, 0xffffffffu, 0x00ff00ffu, 70000u};
  EXPECT_EQ(idsFromRgba(idsToRgba(ids)), ids);
  std::vector<uint8_t> bytes = idsToRgba(ids);
  EXPECT_EQ(bytes[8], 0x04);  // little-endian: R holds the low byte
  EXPECT_EQ(bytes[11], 0x01);
  writePngRgba(dir / "ids.png", 3, 2, bytes);
  EXPECT_EQ(idsFromRgba(readPngRgba(dir / "ids.png").rgba), ids);

  EXPECT_THROW(idsFromRgba(std::vector<uint8_t>(7)), std::invalid_argument);
  EXPECT_THROW(writePngRgba(dir / "x.png", 3, 3, bytes), std::invalid_argument);
  EXPECT_THROW(writePngRgba(dir / "no" / "such" / "dir.png", 3, 2, bytes), std::runtime_error);
}

std::string errorOf(const fs::path& path) {
  try {
    readPngRgba(path);
  } catch (const FormatError& e) {
    return e.what();
  }
  return "";
}

TEST(ImagePng, BadFilesGiveErrorsNamingTheFile) {
  auto dir = test::scratchDir();
  std::string missing = errorOf(dir / "missing.png");
  EXPECT_NE(missing.find("missing.png"), std::string::npos) << missing;
  EXPECT_NE(missing.find("no such file"), std::string::npos) << missing;

  test::writeFile(dir / "text.png", "this is not a png at all");
  std::string text = errorOf(dir / "text.png");
  EXPECT_NE(text.find("text.png"), std::string::npos) << text;
  EXPECT_NE(text.find("not a PNG"), std::string::npos) << text;

  Frame f = scene();
  writePngRgba(dir / "good.png", f.width, f.height, f.rgba);
  std::string good = test::readFile(dir / "good.png");
  test::writeFile(dir / "cut.png", good.substr(0, good.size() / 2));
  std::string cut = errorOf(dir / "cut.png");
  EXPECT_NE(cut.find("cut.png"), std::string::npos) << cut;
  EXPECT_NE(cut.find("corrupt PNG"), std::string::npos) << cut;

  // A header claiming 10000 x 10000 pixels (stb itself would allocate 400 MB for it) is refused
  // before anything that size is allocated.
  std::string huge = good;
  const uint8_t dims[8] = {0, 0, 0x27, 0x10, 0, 0, 0x27, 0x10};  // IHDR width, height
  for (int i = 0; i < 8; ++i) huge[16 + i] = char(dims[i]);
  test::writeFile(dir / "huge.png", huge);
  std::string big = errorOf(dir / "huge.png");
  EXPECT_NE(big.find("huge.png"), std::string::npos) << big;
  EXPECT_NE(big.find("10000x10000 is outside"), std::string::npos) << big;
}

TEST(ImagePng, DamagedPngsAreRejectedCleanly) {
  auto dir = test::scratchDir();
  Frame f = scene(24, 16);
  writePngRgba(dir / "frame.png", f.width, f.height, f.rgba);
  std::string original = test::readFile(dir / "frame.png");
  ASSERT_LT(original.size(), 4096u);  // every truncation is tried
  int rejected = test::expectRobustToDamage(
      original, "frame_00000.png",
      [](const fs::path& path, SceneSink&) {
        RgbaImage image = readPngRgba(path);
        // Whatever decodes must be self-consistent.
        if (image.rgba.size() != size_t(image.width) * image.height * 4)
          throw std::logic_error("inconsistent image");
      });
  EXPECT_GE(rejected, int(original.size()));  // at least every truncation
}

TEST(IdCensus, CountsCoveredPixelsAndDistinctObjects) {
  const std::vector<uint32_t> ids = {0, 7, 7, 0, 3, 9, 3, 0, 7, 0xffffffffu};
  const IdCensus census = censusOf(ids);
  EXPECT_EQ(census.covered_pixels, 7u);
  EXPECT_EQ(census.visible_objects, 4u);  // 3, 7, 9 and the largest id
  const IdCensus empty = censusOf(std::vector<uint32_t>(16, 0));
  EXPECT_EQ(empty.covered_pixels, 0u);
  EXPECT_EQ(empty.visible_objects, 0u);
}

// --- `terawalk compare` through the real executable ---

using RunResult = test::CommandResult;

RunResult run(const std::string& args) { return test::runTerawalk(args); }

void writeFrame(const fs::path& dir, int number, const Frame& f, bool with_ids = true) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05d.png", number);
  writePngRgba(dir / name, f.width, f.height, f.rgba);
  if (with_ids) {
    std::snprintf(name, sizeof name, "ids_%05d.png", number);
    writePngRgba(dir / name, f.width, f.height, idsToRgba(f.ids));
  }
}

// Reference and test directories of three frames: frame 0 identical, frame 1 with an 8x5 id blob
// (40 of 1200 pixels), frame 2 with an edge shifted by one pixel.
void writeSequences(const fs::path& a, const fs::path& b) {
  fs::create_directories(a);
  fs::create_directories(b);
  writeFrame(a, 0, scene());
  writeFrame(b, 0, scene());
  Frame blob = scene();
  for (int y = 22; y < 27; ++y)
    for (int x = 28; x < 36; ++x) blob.ids[size_t(y) * blob.width + x] = 1234567;
  writeFrame(a, 1, scene());
  writeFrame(b, 1, blob);
  writeFrame(a, 2, edge(20));
  writeFrame(b, 2, edge(21));
  test::writeFile(a / "frames.csv", "frame,ms\n0,1\n");  // stats files are ignored
}

class CompareCli : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(TW_TERAWALK_EXE))
      FAIL() << "build the terawalk executable first: " << TW_TERAWALK_EXE;
    dir_ = test::scratchDir();
    a_ = dir_ / "ref";
    b_ = dir_ / "lod";
    writeSequences(a_, b_);
  }
  fs::path dir_, a_, b_;
};

TEST_F(CompareCli, ReportsPerFrameFiguresAndWritesDiffsAndSummary) {
  fs::path out = dir_ / "diff";
  RunResult r = run("compare --quiet --json " + a_.string() + " " + b_.string() + " --out " +
                    out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["frames"], 3);
  EXPECT_EQ(j["ids_compared_frames"], 3);
  EXPECT_EQ(j["tolerance_px"], 1);
  EXPECT_EQ(j["worst_match_frame"], 1);
  EXPECT_NEAR(j["worst_match_pct"].get<double>(), 100.0 * (1.0 - 40.0 / 1200), 1e-9);
  EXPECT_NEAR(j["mean_match_pct"].get<double>(), 100.0 * (1.0 - 40.0 / 3600), 1e-9);
  EXPECT_EQ(j["identical_frames"], 2);  // frames 0 and 1 differ only in ids
  EXPECT_EQ(j["min_psnr_frame"], 2);
  ASSERT_EQ(j["per_frame"].size(), 3u);
  EXPECT_EQ(j["per_frame"][0]["psnr_db"], kIdenticalPsnrDb);
  EXPECT_NEAR(j["per_frame"][1]["id_mismatch_pct"].get<double>(), 100.0 * 40 / 1200, 1e-9);
  EXPECT_EQ(j["per_frame"][2]["match_pct"], 100.0);
  EXPECT_LT(j["per_frame"][2]["psnr_db"].get<double>(), 30.0);
  // What each frame shows: every pixel is some object's; B's frame 1 adds the blob's object.
  EXPECT_EQ(j["per_frame"][1]["covered_pixels_a"], 1200);
  EXPECT_EQ(j["per_frame"][1]["visible_objects_a"], 2);
  EXPECT_EQ(j["per_frame"][1]["visible_objects_b"], 3);
  EXPECT_EQ(j["median_covered_pixels_b"], 1200.0);
  EXPECT_EQ(j["median_visible_objects_a"], 2.0);
  EXPECT_EQ(j["median_visible_objects_b"], 2.0);

  for (const char* name : {"diff_00000.png", "diff_00001.png", "diff_00002.png"}) {
    RgbaImage diff = readPngRgba(out / name);
    EXPECT_EQ(diff.width, 40);
    EXPECT_EQ(diff.height, 30);
  }
  EXPECT_EQ(nlohmann::json::parse(test::readFile(out / "summary.json")), j);
  std::string csv = test::readFile(out / "compare.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 4) << csv;
  EXPECT_EQ(csv.rfind("frame,psnr_db,colour_mismatch_pct,id_mismatch_pct,match_pct", 0), 0u);
  EXPECT_NE(csv.find(",1,1200,2,1200,3\n"), std::string::npos) << csv;  // frame 1's census

  // Tolerance 0: the shifted edge now costs one column of frame 2.
  RunResult strict = run("compare --quiet --json --tolerance-px 0 " + a_.string() + " " +
                         b_.string());
  ASSERT_EQ(strict.exit_code, 0) << strict.output;
  nlohmann::json s = nlohmann::json::parse(strict.output);
  EXPECT_NEAR(s["per_frame"][2]["match_pct"].get<double>(), 100.0 * 39 / 40, 1e-9);
}

TEST_F(CompareCli, TextReportAndIdenticalDirectories) {
  RunResult r = run("compare --quiet " + a_.string() + " " + a_.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("match    mean 100.000 %"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("3 identical"), std::string::npos) << r.output;
}

TEST_F(CompareCli, FramesWithoutIdsAreComparedByColour) {
  fs::path c = dir_ / "no_ids";
  fs::create_directories(c);
  for (int i = 0; i < 3; ++i) writeFrame(c, i, i == 2 ? edge(21) : scene(), false);
  RunResult r = run("compare --quiet --json " + a_.string() + " " + c.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["ids_compared_frames"], 0);
  EXPECT_TRUE(j["per_frame"][1]["id_mismatch_pct"].is_null());
  EXPECT_TRUE(j["per_frame"][1]["visible_objects_b"].is_null());
  EXPECT_TRUE(j["median_covered_pixels_a"].is_null());
  EXPECT_EQ(j["mean_match_pct"], 100.0);
}

TEST_F(CompareCli, CorruptPngIsAClearError) {
  std::string good = test::readFile(b_ / "frame_00001.png");
  test::writeFile(b_ / "frame_00001.png", good.substr(0, good.size() / 3));
  RunResult r = run("compare --quiet " + a_.string() + " " + b_.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;  // an error exit, not a signal
  EXPECT_NE(r.output.find("error"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("frame_00001.png"), std::string::npos) << r.output;

  test::writeFile(b_ / "frame_00001.png", "garbage");
  r = run("compare --quiet " + a_.string() + " " + b_.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("frame_00001.png: byte 0: not a PNG"), std::string::npos) << r.output;

  // A damaged id image is named too.
  writeFrame(b_, 1, scene());
  test::writeFile(b_ / "ids_00002.png", "\x89PNG\r\n\x1a\nbroken");
  r = run("compare --quiet " + a_.string() + " " + b_.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("ids_00002.png"), std::string::npos) << r.output;
}

TEST_F(CompareCli, MismatchedCountsAndSizesAreErrors) {
  fs::remove(b_ / "frame_00002.png");
  RunResult r = run("compare --quiet " + a_.string() + " " + b_.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("frame_00002.png: missing"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("has 3 frames"), std::string::npos) << r.output;

  writeFrame(b_, 2, scene(41, 30));
  r = run("compare --quiet " + a_.string() + " " + b_.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("frame_00002.png: 41x30 but"), std::string::npos) << r.output;

  // An id image whose size differs from its colour frame.
  writeFrame(b_, 2, edge(21));
  Frame small = scene(10, 10);
  writePngRgba(b_ / "ids_00002.png", 10, 10, idsToRgba(small.ids));
  r = run("compare --quiet " + a_.string() + " " + b_.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("ids_00002.png: 10x10"), std::string::npos) << r.output;

  r = run("compare --quiet " + a_.string() + " " + (dir_ / "nowhere").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("nowhere: not a directory"), std::string::npos) << r.output;

  r = run("compare --quiet " + a_.string() + " " + b_.string() + " --out " + b_.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--out must not be one of the compared"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(b_ / "summary.json"));

  fs::create_directories(dir_ / "empty");
  r = run("compare --quiet " + a_.string() + " " + (dir_ / "empty").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("no frame_*.png"), std::string::npos) << r.output;
}

TEST_F(CompareCli, HelpAndBadOptions) {
  RunResult help = run("compare --help");
  EXPECT_EQ(help.exit_code, 0) << help.output;
  EXPECT_NE(help.output.find("--tolerance-px"), std::string::npos) << help.output;
  RunResult bad = run("compare --tolerance-px -1 " + a_.string() + " " + b_.string());
  EXPECT_NE(bad.exit_code, 0) << bad.output;
}

}  // namespace
}  // namespace tw
