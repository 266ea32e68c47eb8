// Tests for `terawalk bench`: the quick suite runs end to end (as the CI smoke run), writes its
// files, and its results.json has the keys the report and --compare rely on; --compare reads an
// earlier results.json; bad options fail with a message. No timing is asserted.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "test_support.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

nlohmann::json readJson(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

TEST(Bench, QuickRunWritesResultsReportPlotsAndSamples) {
  const fs::path dir = test::scratchDir();
  const fs::path out = dir / "report";
  const std::string common = "-q bench --quick --sizes 60K,150K --walk-fps 0.4 --out " + out.string() +
                             " --cache " + (dir / "cache").string() + " --paths " +
                             (fs::path(TW_DATA_DIR) / "paths").string();
  const test::CommandResult run = test::runTerawalk(common);
  ASSERT_EQ(run.exit_code, 0) << run.output;

  ASSERT_TRUE(fs::exists(out / "results.json"));
  ASSERT_TRUE(fs::exists(out / "report.md"));
  const nlohmann::json results = readJson(out / "results.json");
  for (const char* key : {"schema", "commit", "machine", "configuration", "models", "total_s"})
    EXPECT_TRUE(results.contains(key)) << key;
  EXPECT_TRUE(results["machine"].contains("cpu"));
  EXPECT_TRUE(results["machine"].contains("renderer"));
  ASSERT_EQ(results["models"].size(), 2u);
  // Walking at twice the recorded rate: one unrecorded frame between recorded ones, on the walks
  // inside and by the modes with frame-to-frame state only.
  EXPECT_EQ(results["configuration"]["walk_fps"], 0.4);
  EXPECT_EQ(results["configuration"]["walk_modes"],
            nlohmann::json({"lod_frustum", "lod_frustum_occlusion", "default"}));
  const auto& decks = results["models"][0]["paths"]["decks"];
  EXPECT_EQ(decks["default"]["walk_frames"], decks["default"]["frames"].get<int>() - 1);
  EXPECT_EQ(decks["lod_frustum"]["walk_frames"], decks["lod_frustum"]["frames"].get<int>() - 1);
  EXPECT_EQ(decks["reference"]["walk_frames"], 0);
  EXPECT_EQ(decks["lod"]["walk_frames"], 0);
  EXPECT_EQ(results["models"][0]["paths"]["orbit"]["default"]["walk_frames"], 0);
  for (const auto& model : results["models"]) {
    const auto& pre = model["preprocess"];
    for (const char* key : {"wall_s", "cpu_s", "peak_rss_bytes", "input_triangles",
                            "input_triangles_per_s", "bytes_per_input_triangle", "stages_s"})
      EXPECT_TRUE(pre.contains(key)) << key;
    EXPECT_GT(pre["input_triangles"].get<double>(), 0.0);
    EXPECT_FALSE(pre["stages_s"].empty());
    for (const char* path : {"decks", "rack", "orbit"}) {
      ASSERT_TRUE(model["paths"].contains(path)) << path;
      for (const char* mode :
           {"reference", "lod", "lod_frustum", "lod_frustum_occlusion", "default"}) {
        const auto& m = model["paths"][path][mode];
        EXPECT_TRUE(m.contains("median_frame_ms")) << path << " " << mode;
        EXPECT_TRUE(m.contains("median_triangles")) << path << " " << mode;
        EXPECT_TRUE(m.contains("median_all_triangles")) << path << " " << mode;
        EXPECT_TRUE(m.contains("first_frame_ms")) << path << " " << mode;
        EXPECT_FALSE(m["series"]["frame_ms"].empty()) << path << " " << mode;
        if (std::string(mode) != "reference") {
          EXPECT_TRUE(m.contains("fidelity")) << mode;
          // What the reference's frames show: some object on some pixel, on every path.
          EXPECT_GT(m["fidelity"].value("median_covered_pixels_a", 0.0), 0.0) << path << " " << mode;
          EXPECT_GT(m["fidelity"].value("median_visible_objects_a", 0.0), 0.0) << path << " " << mode;
        }
      }
      EXPECT_TRUE(model["paths"][path]["lod_frustum_occlusion"].contains("occlusion_lost_share"));
    }
    // The orbit is generated for the replay's rate: every one of its frames is rendered.
    EXPECT_EQ(model["paths"]["orbit"]["default"]["series"]["frame_ms"].size(), 8u);
  }
  // The report names every mode, and the plots the issue lists exist (gnuplot is a dependency).
  std::ifstream in(out / "report.md");
  const std::string report((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const char* text : {"## Preprocessing", "LOD + frustum + occlusion", "full default",
                           "## Path `decks`", "Shown per frame by the reference", "## Plots",
                           "## Sample frames"})
    EXPECT_NE(report.find(text), std::string::npos) << text;
  for (const char* plot : {"frametime-decks.png", "scaling-decks.png", "preprocess.png",
                           "stages.png"})
    EXPECT_TRUE(fs::exists(out / "plots" / plot)) << plot;
  bool sample = false;
  for (const auto& entry : fs::directory_iterator(out / "samples"))
    sample = sample || entry.path().filename().string().rfind("diff-", 0) == 0;
  EXPECT_TRUE(sample);

  // --compare against itself: every ratio is 1 for figures that do not vary; the table lists them.
  const std::string table =
      test::runTerawalk("-q bench --compare " + (out / "results.json").string() +
                        " --report-only " + (out / "results.json").string() + " --out " +
                        (dir / "again").string())
          .output;
  EXPECT_NE(table.find("preprocess.input_triangles"), std::string::npos) << table;
  EXPECT_NE(table.find("1.000"), std::string::npos) << table;
  EXPECT_TRUE(fs::exists(dir / "again" / "report.md"));
}

TEST(Bench, RejectsBadOptions) {
  const fs::path dir = test::scratchDir();
  test::CommandResult bad = test::runTerawalk("-q bench --sizes 10X --out " + dir.string());
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("--sizes"), std::string::npos) << bad.output;
  test::CommandResult missing =
      test::runTerawalk("-q bench --report-only " + (dir / "absent.json").string());
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("absent.json"), std::string::npos) << missing.output;
}

}  // namespace
}  // namespace tw
