// End to end through the `terawalk` executable: the commands a person types, their exit codes,
// their output, and the counts `info` prints for real and generated models.
#include <gtest/gtest.h>

#include <stb_image.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "obj_reader.h"
#include "package_view.h"
#include "package_writer.h"
#include "project_database.h"
#include "test_support.h"

namespace tw {
namespace {

using RunResult = test::CommandResult;

RunResult run(const std::string& args) { return test::runTerawalk(args); }

nlohmann::json infoJson(const std::filesystem::path& file) {
  RunResult r = run("info --json --quiet " + file.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return nlohmann::json::parse(r.output);
}

TEST(Cli, HelpOnEveryVerb) {
  for (const char* verb :
       {"", "info ", "gen ", "gen plant ", "snapshot ", "preprocess ", "verify ", "render ",
        "view ", "compare ", "pick ", "find "}) {
    RunResult r = run(std::string(verb) + "--help");
    EXPECT_EQ(r.exit_code, 0) << verb << r.output;
    EXPECT_NE(r.output.find("Usage"), std::string::npos) << verb << r.output;
  }
}

TEST(Cli, UnknownVerbFails) {
  EXPECT_NE(run("frobnicate").exit_code, 0);
}

TEST(Cli, InfoCountsTheKicadConnector) {
  auto file = test::sharedDataDir() / "kicad_dsub62.obj";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data not present: " << file;
  nlohmann::json j = infoJson(file);
  EXPECT_EQ(j["objects"], 648);
  EXPECT_EQ(j["objects_by_kind"]["mesh"], 648);
  EXPECT_EQ(j["triangles"]["total"], 94176);
  EXPECT_EQ(j["format"], "obj");
}

TEST(Cli, InfoCountsTheBunny) {
  auto file = test::sharedDataDir() / "stanford-bunny.obj";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data not present: " << file;
  nlohmann::json j = infoJson(file);
  EXPECT_EQ(j["objects"], 1);
  EXPECT_EQ(j["triangles"]["total"], 69451);
}

TEST(Cli, BadInputGivesOneLineErrorNamingTheFile) {
  auto dir = test::scratchDir();
  auto bad = dir / "broken.ply";
  test::writeFile(bad, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n");
  RunResult r = run("info --quiet " + bad.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("broken.ply"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("error"), std::string::npos) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;

  RunResult missing = run("info " + (dir / "absent.obj").string());
  EXPECT_NE(missing.exit_code, 0);
}

TEST(Cli, GeneratesAPlantThatInfoCounts) {
  auto dir = test::scratchDir();
  auto tws = dir / "plant.tws";
  auto db = dir / "plant.db";
  auto ply = dir / "plant.ply";
  RunResult gen = run("gen plant --quiet --triangles 200000 --seed 3 -o " + tws.string() +
                      " --db " + db.string() + " --mesh " + ply.string());
  ASSERT_EQ(gen.exit_code, 0) << gen.output;
  ASSERT_TRUE(std::filesystem::exists(tws));
  ASSERT_TRUE(std::filesystem::exists(ply));

  nlohmann::json scene = infoJson(tws);
  uint64_t total = scene["triangles"]["total"];
  // gen prints the total info counts, and the one its size target counts (NURBS per patch),
  // which lands near the target.
  unsigned long long printed = 0, mesh_part = 0, target_count = 0;
  const size_t line = gen.output.find("  triangles    ");
  ASSERT_NE(line, std::string::npos) << gen.output;
  ASSERT_EQ(std::sscanf(gen.output.c_str() + line, " triangles %llu equivalent (%llu in meshes; %llu",
                        &printed, &mesh_part, &target_count),
            3)
      << gen.output;
  EXPECT_EQ(printed, total);
  EXPECT_GT(target_count, 180000u);
  EXPECT_LT(target_count, 220000u);
  EXPECT_GT(scene["objects_by_kind"]["primitive"].get<uint64_t>(), 100u);
  EXPECT_GT(scene["objects_by_kind"]["mesh"].get<uint64_t>(), 0u);
  EXPECT_GT(scene["objects_by_kind"]["nurbs"].get<uint64_t>(), 0u);
  EXPECT_EQ(scene["objects_with_db_key"], scene["objects"]);
  EXPECT_GE(scene["layers"].size(), 5u);

  // The PLY holds the same scene tessellated at the same default tolerance.
  nlohmann::json mesh = infoJson(ply);
  EXPECT_EQ(mesh["triangles"]["total"].get<uint64_t>(), total);

  ProjectDatabase database = ProjectDatabase::open(db);
  EXPECT_GT(database.recordCount(), 0u);
}

// `info` counts a NURBS hull as the preprocessor tessellates it (conforming across patches), so
// the scene's mesh and NURBS triangles are the package's level 0, and the PLY of `gen --mesh`
// holds the same triangles.
TEST(Cli, InfoCountsTheHullAsThePreprocessorTessellatesIt) {
  auto dir = test::scratchDir();
  auto tws = dir / "plant.tws";
  auto ply = dir / "plant.ply";
  auto twk = dir / "plant.twk";
  RunResult gen = run("gen plant --quiet --triangles 300000 --seed 2 --no-db -o " + tws.string() +
                      " --mesh " + ply.string());
  ASSERT_EQ(gen.exit_code, 0) << gen.output;
  RunResult pre = run("preprocess --quiet --visibility off " + tws.string() + " -o " + twk.string());
  ASSERT_EQ(pre.exit_code, 0) << pre.output;

  nlohmann::json scene = infoJson(tws);
  nlohmann::json package = infoJson(twk);
  const uint64_t hull = scene["triangles"]["nurbs_equivalent"];
  const uint64_t mesh = scene["triangles"]["mesh"];
  EXPECT_GT(hull, 0u);
  EXPECT_EQ(mesh + hull, package["triangles"]["level0"].get<uint64_t>());
  EXPECT_EQ(infoJson(ply)["triangles"]["total"], scene["triangles"]["total"]);
}

// `find`: the objects whose record matches a condition, values bound as parameters; SQLite's
// message for a bad query; no second statement; --name by substring.
TEST(Cli, FindMatchesRecordsWithBoundValues) {
  auto dir = test::scratchDir();
  auto tws = dir / "plant.tws", db_path = dir / "plant.db", twk = dir / "plant.twk";
  ASSERT_EQ(run("gen plant --quiet --triangles 200000 --seed 1 -o " + tws.string() + " --db " +
                db_path.string()).exit_code, 0);
  ASSERT_EQ(run("preprocess --quiet --visibility off " + tws.string() + " -o " + twk.string())
                .exit_code, 0);
  const std::string base = "find --quiet " + twk.string() + " --db " + db_path.string() + " ";
  RunResult r = run(base + "\"type = ?1 AND nominal_diameter_mm >= ?2\" --param valve "
                           "--param 100 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  ASSERT_GT(j["objects"].size(), 0u);
  // Every object found has a matching record, and every object with one is found.
  ProjectDatabase db = ProjectDatabase::open(db_path);
  const PackageView view = PackageView::open(twk);
  size_t expected = 0;
  for (uint32_t o = 0; o < view.objects().size(); ++o) {
    const auto record = db.find(std::string(view.objectDbKey(o)));
    expected += record && record->type == "valve" && record->nominal_diameter_mm >= 100;
  }
  EXPECT_EQ(j["objects"].size(), expected);
  for (const auto& o : j["objects"]) {
    const auto record = db.find(o["db_key"].get<std::string>());
    ASSERT_TRUE(record);
    EXPECT_EQ(record->type, "valve");
    EXPECT_GE(record->nominal_diameter_mm, 100.0);
  }
  RunResult bad = run(base + "\"servce = 1\"");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.output.find("no such column: servce"), std::string::npos) << bad.output;
  RunResult two = run(base + "\"1); DELETE FROM records; --\"");
  EXPECT_EQ(two.exit_code, 1) << two.output;
  EXPECT_EQ(db.recordCount(), ProjectDatabase::open(db_path).recordCount());
  RunResult missing = run(base + "\"type = ?1\"");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.output.find("parameters"), std::string::npos) << missing.output;
  RunResult named = run("find --quiet " + twk.string() + " --name HV-00001 --json");
  ASSERT_EQ(named.exit_code, 0) << named.output;
  for (const auto& o : nlohmann::json::parse(named.output)["objects"])
    EXPECT_NE(o["name"].get<std::string>().find("HV-00001"), std::string::npos);
}

// The 10M-triangle benchmark plant (seed 1) has these exact counts. They change only when the
// generator changes on purpose; update them then, from `terawalk info --json`.
TEST(Cli, TenMillionTrianglePlantHasKnownCounts) {
  auto tws = test::scratchDir() / "plant10M.tws";
  RunResult gen = run("gen plant --quiet --triangles 10M --seed 1 --no-db -o " + tws.string());
  ASSERT_EQ(gen.exit_code, 0) << gen.output;
  nlohmann::json j = infoJson(tws);
  EXPECT_EQ(j["objects"], 120173);
  EXPECT_EQ(j["objects_with_db_key"], 120173);
  EXPECT_EQ(j["objects_by_kind"]["primitive"], 119698);
  EXPECT_EQ(j["objects_by_kind"]["mesh"], 473);
  EXPECT_EQ(j["objects_by_kind"]["nurbs"], 2);
  EXPECT_EQ(j["nurbs_patches"], 356);
  EXPECT_EQ(j["triangles"]["total"], 10417074);  // the hulls as the preprocessor tessellates them
  EXPECT_EQ(j["triangles"]["mesh"], 1766624);
  EXPECT_EQ(j["layers"].size(), 12u);
}

TEST(Cli, SnapshotWritesAPng) {
  auto file = test::sharedDataDir() / "kicad_dsub62.obj";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data not present: " << file;
  auto png = test::scratchDir() / "kicad.png";
  RunResult r = run("snapshot --quiet " + file.string() + " --out " + png.string() +
                    " --width 160 --height 90");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::string bytes = test::readFile(png);
  ASSERT_GT(bytes.size(), 8u);
  EXPECT_EQ(bytes.substr(1, 3), "PNG");
}

// A one-cluster package: `verify` passes it and fails it once a page byte changes (exit 1, the
// check named); `info` summarises it by extension or, renamed, by magic.
TEST(Cli, VerifyAndInfoOnAPackage) {
  PackageStorage s;
  s.addLayer({"deck", 0xff808080u});
  ObjectInfo o;
  o.id = 1;
  o.name = "plate";
  s.addObject(o, glm::vec3(0.0f), glm::vec3(1.0f, 1.0f, 0.0f));
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices, objects;
  for (int y = 0; y <= 4; ++y)
    for (int x = 0; x <= 4; ++x) positions.push_back({0.25f * x, 0.25f * y, 0.0f});
  for (uint32_t y = 0; y < 4; ++y)
    for (uint32_t x = 0; x < 4; ++x) {
      uint32_t a = y * 5 + x;
      indices.insert(indices.end(), {a, a + 1, a + 6, a, a + 6, a + 5});
      objects.insert(objects.end(), {0, 0});
    }
  s.addMeshCluster({positions, {}, indices, objects}, ClusterLod{});
  auto dir = test::scratchDir();
  auto path = dir / "plate.twk";
  writePackage(s, path, PackageWriteOptions{false, 9});

  RunResult ok = run("verify --quiet " + path.string());
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_NE(ok.output.find(": OK:"), std::string::npos) << ok.output;

  nlohmann::json j = infoJson(path);
  EXPECT_EQ(j["format"], "twk");
  EXPECT_EQ(j["level_count"], 1);
  EXPECT_EQ(j["triangles"]["level0"], 32);
  ASSERT_EQ(j["levels"].size(), 1u);
  EXPECT_EQ(j["levels"][0]["clusters"], 1);
  EXPECT_EQ(j["layers"][0]["name"], "deck");
  std::string bytes = test::readFile(path);
  test::writeFile(dir / "plate.bin", bytes);
  EXPECT_EQ(infoJson(dir / "plate.bin")["format"], "twk");  // recognised by magic
  RunResult text = run("info --quiet " + path.string());
  EXPECT_EQ(text.exit_code, 0) << text.output;
  EXPECT_NE(text.output.find("1 levels"), std::string::npos) << text.output;

  bytes[bytes.size() - 20] ^= 0x5a;  // page data is the last section
  test::writeFile(path, bytes);
  RunResult bad = run("verify --quiet " + path.string());
  EXPECT_EQ(bad.exit_code, 1) << bad.output;
  EXPECT_NE(bad.output.find("FAILED (checksums)"), std::string::npos) << bad.output;
  RunResult bad_json = run("verify --json --quiet " + path.string());
  EXPECT_EQ(bad_json.exit_code, 1);
  nlohmann::json f = nlohmann::json::parse(bad_json.output);
  EXPECT_EQ(f["ok"], false);
  EXPECT_EQ(f["failure"]["check"], "checksums");
  EXPECT_EQ(f["failure"]["page"], 0);

  // Not a package at all: the view's own checks fail first.
  test::writeFile(dir / "scene.twk", "v 0 0 0\n");
  RunResult junk = run("verify --quiet " + (dir / "scene.twk").string());
  EXPECT_EQ(junk.exit_code, 1) << junk.output;
  EXPECT_NE(junk.output.find("FAILED (structure)"), std::string::npos) << junk.output;
}

}  // namespace
}  // namespace tw

namespace tw {
namespace {

// The preprocessor from the command line on a real CAD part: a package that verifies, whose
// levels shrink, and whose level 0 holds every input triangle and object.
TEST(Cli, PreprocessVerifyAndInfoOnTheKicadConnector) {
  auto file = test::sharedDataDir() / "kicad_dsub62.obj";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data not present: " << file;
  auto twk = test::scratchDir() / "kicad.twk";
  RunResult pre = run("preprocess --quiet " + file.string() + " -o " + twk.string());
  ASSERT_EQ(pre.exit_code, 0) << pre.output;
  EXPECT_NE(pre.output.find("bytes per input triangle"), std::string::npos) << pre.output;
  RunResult verify = run("verify --quiet " + twk.string());
  EXPECT_EQ(verify.exit_code, 0) << verify.output;
  EXPECT_NE(verify.output.find("OK"), std::string::npos) << verify.output;
  nlohmann::json j = infoJson(twk);
  ASSERT_GE(j["levels"].size(), 3u);
  EXPECT_EQ(j["levels"][0]["triangles"], 94176);
  EXPECT_EQ(j["objects"], 648);
  for (size_t level = 1; level < j["levels"].size(); ++level)
    EXPECT_LE(j["levels"][level]["triangles"].get<double>(),
              0.6 * j["levels"][level - 1]["triangles"].get<double>())
        << "level " << level;
  EXPECT_LE(j["bytes_per_input_triangle"].get<double>(), 24.0);
}

// A budget the preprocessor cannot keep to stops the run at once with the smallest budget this
// input needs, and that budget then works: 1K before any input is read, 2M after the survey
// (the smallest brick of the bunny alone needs more).
TEST(Cli, PreprocessStopsAtOnceWhenTheMemoryBudgetIsTooSmall) {
  auto file = test::sharedDataDir() / "stanford-bunny.obj";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data not present: " << file;
  auto twk = test::scratchDir() / "bunny.twk";
  RunResult tiny = run("preprocess --quiet --memory-budget 1K " + file.string() + " -o " + twk.string());
  EXPECT_NE(tiny.exit_code, 0);
  EXPECT_NE(tiny.output.find("--memory-budget 1.0 KiB is below what this input needs"),
            std::string::npos) << tiny.output;
  RunResult small = run("preprocess --quiet --memory-budget 2M " + file.string() + " -o " + twk.string());
  EXPECT_NE(small.exit_code, 0);
  const size_t at = small.output.find("at least ");
  ASSERT_NE(at, std::string::npos) << small.output;
  EXPECT_NE(small.output.find("brick build"), std::string::npos) << small.output;
  EXPECT_FALSE(std::filesystem::exists(twk));
  EXPECT_FALSE(std::filesystem::exists(twk.string() + ".work")) << "work directory left behind";
  const double needed_mib = std::stod(small.output.substr(at + 9));
  EXPECT_GT(needed_mib, 2.0);
  const std::string enough = std::to_string(int(std::ceil(needed_mib))) + "M";
  RunResult ok = run("preprocess --quiet --memory-budget " + enough + " " + file.string() + " -o " +
                     twk.string());
  EXPECT_EQ(ok.exit_code, 0) << enough << ": " << ok.output;
}

// A disk that fills during preprocess (a 3 MiB tmpfs): a clear error naming the file and the
// reason, no package, and nothing left in the folder, so the disk is not kept full; once space is
// freed the same command with --resume finishes with the bytes of a build that never failed.
TEST(Cli, PreprocessOnAFullDiskLeavesNothingBehindAndResumesAfterSpaceIsFreed) {
  auto file = test::sharedDataDir() / "duplex-mep.obj";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data not present: " << file;
  auto dir = test::scratchDir();
  auto disk = dir / "small-disk";
  std::filesystem::create_directories(disk);
  if (test::runShell("mount -t tmpfs -o size=3M tmpfs " + disk.string()).exit_code != 0)
    GTEST_SKIP() << "mounting a tmpfs needs root (CI runs as root)";
  struct Unmount {
    std::string path;
    ~Unmount() { test::runShell("umount " + path); }
  } unmount{disk.string()};
  const auto out = disk / "duplex.twk";
  RunResult full = run("preprocess --quiet " + file.string() + " -o " + out.string());
  EXPECT_EQ(full.exit_code, 1) << full.output;
  EXPECT_NE(full.output.find("No space left on device"), std::string::npos) << full.output;
  EXPECT_NE(full.output.find(disk.string()), std::string::npos) << full.output;
  EXPECT_TRUE(std::filesystem::is_empty(disk)) << "the package, its temporary file and the work folder are gone";

  ASSERT_EQ(test::runShell("mount -o remount,size=64M " + disk.string()).exit_code, 0);
  RunResult resumed = run("preprocess --quiet --resume " + file.string() + " -o " + out.string());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  const auto reference = dir / "reference.twk";
  ASSERT_EQ(run("preprocess --quiet " + file.string() + " -o " + reference.string()).exit_code, 0);
  EXPECT_EQ(test::readFile(out), test::readFile(reference));
}

// SIGKILL as each stage of a bricked preprocess begins, with an older package at the output
// path: the older package is never touched (nothing half-written is ever under the final name,
// nor anywhere but the work folder), and `--resume` finishes with the bytes of a build that was
// never killed, leaving nothing behind. Stages are found by the progress lines on stderr.
TEST(Cli, PreprocessKilledAtEveryStageResumesToTheSameBytes) {
  auto dir = test::scratchDir();
  const auto mesh = dir / "plant.ply";
  ASSERT_EQ(run("gen plant --quiet --triangles 300000 --seed 4 --no-db -o " +
                (dir / "plant.tws").string() + " --mesh " + mesh.string())
                .exit_code,
            0);
  const std::string options = " --brick-triangles 40000";
  const auto reference = dir / "reference.twk";
  ASSERT_EQ(run("preprocess -q " + mesh.string() + " -o " + reference.string() + options).exit_code,
            0);
  const auto older = dir / "older.twk";
  ASSERT_EQ(run("preprocess -q " + (dir / "plant.tws").string() + " -o " + older.string() +
                " --brick-triangles 300000")
                .exit_code,
            0);
  const auto out_dir = dir / "out";
  const auto out = out_dir / "plant.twk";
  const auto log = dir / "stderr.txt";
  for (const char* stage : {"survey", "bricking", "find seams", "build bricks", "merge bricks",
                            "pack", "write package", "visibility cells", "visibility rays"}) {
    SCOPED_TRACE(stage);
    std::filesystem::remove_all(out_dir);
    std::filesystem::create_directories(out_dir);
    std::filesystem::copy_file(older, out);
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      if (!std::freopen(log.c_str(), "w", stderr) || !std::freopen("/dev/null", "w", stdout))
        ::_exit(127);
      ::execl(TW_TERAWALK_EXE, "terawalk", "preprocess", mesh.c_str(), "-o", out.c_str(),
              "--brick-triangles", "40000", static_cast<char*>(nullptr));
      ::_exit(127);
    }
    // Progress lines end in "\r" or "\n"; a stage begins with "<stage>...".
    const std::string begins = std::string(stage) + "...";
    bool seen = false;
    int status = 0;
    for (int polls = 0; polls < 60000 && !seen; ++polls) {
      if (::waitpid(pid, &status, WNOHANG) == pid) break;
      seen = test::readFile(log).find(begins) != std::string::npos;
      if (!seen) ::usleep(2000);
    }
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &status, 0);
    EXPECT_TRUE(seen) << "the run ended before the stage began: " << test::readFile(log);
    EXPECT_TRUE(WIFSIGNALED(status)) << "killed";
    EXPECT_EQ(test::readFile(out), test::readFile(older)) << "the older package is untouched";
    for (const auto& entry : std::filesystem::directory_iterator(out_dir)) {
      const std::string name = entry.path().filename().string();
      EXPECT_TRUE(name == "plant.twk" || name == "plant.twk.work") << "left behind: " << name;
    }
    RunResult resumed =
        run("preprocess -q --resume " + mesh.string() + " -o " + out.string() + options);
    ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
    EXPECT_EQ(test::readFile(out), test::readFile(reference)) << "resumed to other bytes";
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(out_dir),
                            std::filesystem::directory_iterator()),
              1)
        << "the work folder is removed after the resumed run";
  }
}

// A read-only output folder (a read-only tmpfs, as root ignores permission bits): preprocess
// stops before reading its input, naming the folder and the reason, and writes nothing.
TEST(Cli, PreprocessIntoAReadOnlyFolderStopsAtOnce) {
  auto file = test::sharedDataDir() / "stanford-bunny.obj";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data not present: " << file;
  auto disk = test::scratchDir() / "read-only";
  std::filesystem::create_directories(disk);
  if (test::runShell("mount -t tmpfs -o size=1M,ro tmpfs " + disk.string()).exit_code != 0)
    GTEST_SKIP() << "mounting a tmpfs needs root (CI runs as root)";
  struct Unmount {
    std::string path;
    ~Unmount() { test::runShell("umount " + path); }
  } unmount{disk.string()};
  RunResult r = run("preprocess " + file.string() + " -o " + (disk / "bunny.twk").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("is not writable: Read-only file system"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("survey"), std::string::npos) << "stopped before reading: " << r.output;
  EXPECT_TRUE(std::filesystem::is_empty(disk));
}

// A real MEP model (926 pipes, ducts and fittings; a third of its triangles exact copies): its
// DAG halves level after level down to one root cluster, and verify says so, in text and JSON.
TEST(Cli, VerifyReportsThatARealMepModelHalvesToOneRoot) {
  auto file = test::sharedDataDir() / "duplex-mep.obj";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data not present: " << file;
  auto twk = test::scratchDir() / "duplex.twk";
  RunResult pre = run("preprocess " + file.string() + " -o " + twk.string());
  ASSERT_EQ(pre.exit_code, 0) << pre.output;
  EXPECT_NE(pre.output.find("input       335822 triangles"), std::string::npos) << pre.output;
  EXPECT_NE(pre.output.find("repeats     113484 mesh triangles"), std::string::npos) << pre.output;
  RunResult text = run("verify --quiet " + twk.string());
  ASSERT_EQ(text.exit_code, 0) << text.output;
  EXPECT_NE(text.output.find("every level above 1000 triangles halves"), std::string::npos)
      << text.output;
  EXPECT_NE(text.output.find("; root 1 cluster\n"), std::string::npos) << text.output;
  RunResult json = run("verify --quiet --json " + twk.string());
  ASSERT_EQ(json.exit_code, 0) << json.output;
  const nlohmann::json j = nlohmann::json::parse(json.output);
  const nlohmann::json& dag = j["dag"];
  EXPECT_TRUE(dag["halves"].get<bool>());
  EXPECT_TRUE(dag["errors_monotone"].get<bool>());
  EXPECT_EQ(dag["root_clusters"], 1);
  const nlohmann::json& levels = dag["levels"];
  ASSERT_GE(levels.size(), 8u);
  for (size_t l = 1; l < levels.size(); ++l) {
    const double below = levels[l - 1]["triangles"].get<double>();
    const double ratio = levels[l]["triangles"].get<double>() / below;
    EXPECT_NEAR(levels[l]["ratio"].get<double>(), ratio, 1e-9);
    if (below <= 1000) continue;
    EXPECT_GE(ratio, 0.3) << "level " << l;
    EXPECT_LE(ratio, 0.65) << "level " << l;
  }
}

}  // namespace
}  // namespace tw

namespace tw {
namespace {

// A small package from the bunny, built through the command line once for the runtime verbs.
std::filesystem::path bunnyPackageForCli() {
  static const std::filesystem::path path = [] {
    auto out = test::processScratchDir("cli_bunny") / "bunny-cli.twk";
    RunResult r = run("preprocess --quiet " + (test::sharedDataDir() / "stanford-bunny.obj").string() +
                      " -o " + out.string());
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return out;
  }();
  return path;
}

// A package cut short while `render` walks it (a copy still being written, a disk that filled):
// the renderer keeps going on what it has, says which pages it lost, and exits with 1; it is
// never killed by the file changing under it. Budgets of 2 MiB and eviction after one frame make
// it read duplex-mep's pages again all along the orbit, so reads come after the cut (on a slow
// machine the cut may come first, and the open says the file is short; either way, no crash).
TEST(Cli, RenderSurvivesItsPackageBeingCutShort) {
  const auto model = test::sharedDataDir() / "duplex-mep.obj";
  if (!std::filesystem::exists(model)) GTEST_SKIP() << "shared data not present: " << model;
  auto dir = test::scratchDir();
  const auto package = dir / "duplex.twk";
  RunResult pre = run("preprocess -q " + model.string() + " -o " + package.string());
  ASSERT_EQ(pre.exit_code, 0) << pre.output;
  const auto cut = std::filesystem::file_size(package) / 3;
  const RunResult r = test::runShell(
      "( " + std::string(TW_TERAWALK_EXE) + " -q render " + package.string() +
      " --orbit 300 --size 640x480 --gpu-budget 2M --host-budget 2M --evict-after 1 --out " +
      (dir / "out").string() + " > /dev/null & pid=$!; sleep 0.7; truncate -s " +
      std::to_string(cut) + " " + package.string() + "; wait $pid; echo \"exit=$?\" )");
  const size_t at = r.output.rfind("exit=");
  ASSERT_NE(at, std::string::npos) << r.output;
  const int status = std::stoi(r.output.substr(at + 5));
  EXPECT_TRUE(status == 0 || status == 1) << "killed or failed: " << r.output;
  if (status == 1) {
    const bool lost_pages = r.output.find("was truncated after it was opened") != std::string::npos;
    const bool too_late = r.output.find("truncated or extended") != std::string::npos;
    EXPECT_TRUE(lost_pages || too_late) << r.output;
    if (lost_pages) {
      EXPECT_NE(r.output.find("duplex.twk"), std::string::npos) << r.output;
      EXPECT_TRUE(std::filesystem::exists(dir / "out" / "summary.json"));
    }
  }
}

// `render` headless: a generated orbit, its path saved and replayed, stats as CSV and JSON, PNG
// colour and id frames, and the same path replayed from the file gives the same frame count.
// A streamed page that fails its checksum is not drawn silently: render says which page, at which
// byte, as it happens; the frames and statistics are still written (the cut draws the page's
// coarser ancestors), the summary counts it, and the exit status says the frames are not the
// package's.
TEST(Cli, RenderSaysWhenAStreamedPageFailsItsChecksum) {
  auto package = bunnyPackageForCli();
  auto dir = test::scratchDir();
  std::string bytes = test::readFile(package);
  std::vector<uint32_t> fine_pages;
  {
    // Pages of full-resolution clusters alone (never a pinned root page), each corrupted in its
    // middle.
    auto view = PackageView::open(package);
    std::vector<uint8_t> coarse(view.pages().size(), 0);
    for (const pkg::ClusterRecord& c : view.clusters())
      if (c.page < coarse.size() && (c.level > 0 || c.parent_group == pkg::kNone)) coarse[c.page] = 1;
    for (uint32_t p = 0; p < coarse.size(); ++p) {
      if (coarse[p]) continue;
      fine_pages.push_back(p);
      const pkg::PageRecord& record = view.pages()[p];
      bytes[view.section(pkg::SectionType::PageData).offset + record.offset + record.stored_bytes / 2] ^= 0x5a;
    }
  }
  ASSERT_FALSE(fine_pages.empty()) << "no page of level 0 alone";
  const auto broken = dir / "broken.twk";
  test::writeFile(broken, bytes);
  RunResult r = run("render --quiet " + broken.string() + " --orbit 4 --size 640x480 --tau 0.1 --out " +
                    (dir / "out").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("warning: " + broken.string()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" failed to load: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("pages failed to load and were drawn from coarser levels"), std::string::npos)
      << r.output;
  auto summary = nlohmann::json::parse(test::readFile(dir / "out" / "summary.json"));
  EXPECT_EQ(summary["frames"], 4);
  EXPECT_GE(summary["page_load_errors"].get<int>(), 1);
  // The intact package renders the same path with no error.
  RunResult ok = run("render --quiet " + package.string() + " --orbit 4 --size 640x480 --tau 0.1");
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_EQ(ok.output.find("failed to load"), std::string::npos) << ok.output;
}

// A STEP assembly as a user brings it: info counts its part instances, the package verifies,
// and a pick names the part under the pixel by its assembly path.
TEST(Cli, StepAssemblyImportsPreprocessesAndPicksAPartByItsPath) {
  auto file = test::sharedDataDir() / "as1-oc-214.stp";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data not present: " << file;
  RunResult info = run("info " + file.string());
  ASSERT_EQ(info.exit_code, 0) << info.output;
  EXPECT_NE(info.output.find("(step, 441968 bytes, read Z up)"), std::string::npos) << info.output;
  EXPECT_NE(info.output.find("objects     18 (18 parts, 18 with a database key)"),
            std::string::npos)
      << info.output;
  auto twk = test::scratchDir() / "as1.twk";
  RunResult pre = run("preprocess -q " + file.string() + " -o " + twk.string());
  ASSERT_EQ(pre.exit_code, 0) << pre.output;
  RunResult verify = run("verify -q " + twk.string());
  ASSERT_EQ(verify.exit_code, 0) << verify.output;
  EXPECT_NE(verify.output.find(": OK:"), std::string::npos) << verify.output;
  // From in front and above, the image centre falls on the base plate (200 x 150 mm, metres).
  RunResult pick = run("pick " + twk.string() +
                       " --eye 0.09,-0.25,0.2 --target 0.09,0.075,0.03 --pixel 640,360");
  ASSERT_EQ(pick.exit_code, 0) << pick.output;
  EXPECT_NE(pick.output.find("as1/plate_1"), std::string::npos) << pick.output;
  EXPECT_NE(pick.output.find("layer       256"), std::string::npos) << pick.output;
}

// Every IFC sample preprocesses and verifies; a pick on a wall names it by its GlobalId and
// layer and shows its class and property sets.
TEST(Cli, IfcSamplesPreprocessVerifyAndPickAWallByItsGlobalId) {
  const auto dir = test::scratchDir();
  for (const char* name : {"TestModel_IFC4Add2", "acad2010_objects", "basic_shape_Brep",
                           "basic_shape_CSG", "basic_shape_SweptSolid", "cylinders",
                           "bcf-architectural", "bcf-mep"}) {
    const auto file = test::sharedDataDir() / (std::string(name) + ".ifc");
    if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data not present: " << file;
    const auto twk = dir / (std::string(name) + ".twk");
    RunResult pre = run("preprocess -q " + file.string() + " -o " + twk.string());
    ASSERT_EQ(pre.exit_code, 0) << name << ": " << pre.output;
    RunResult verify = run("verify -q " + twk.string());
    EXPECT_EQ(verify.exit_code, 0) << name << ": " << verify.output;
    EXPECT_NE(verify.output.find(": OK:"), std::string::npos) << name << ": " << verify.output;
  }
  RunResult pick = run("pick " + (dir / "TestModel_IFC4Add2.twk").string() +
                       " --eye 0,-30,3 --target 0,0,3 --pixel 640,360");
  ASSERT_EQ(pick.exit_code, 0) << pick.output;
  EXPECT_NE(pick.output.find("db key      37cU2nGL100xirW00wMfmm"), std::string::npos) << pick.output;
  EXPECT_NE(pick.output.find("layer       A-WALL-____-OTLN"), std::string::npos) << pick.output;
  EXPECT_NE(pick.output.find("Basic Wall"), std::string::npos) << pick.output;
  // The preprocessor wrote the products' records and property sets next to the package, and
  // the pick reads them there: class, storey, quantities and the authoring tool's attributes.
  ASSERT_TRUE(std::filesystem::exists(dir / "bcf-architectural.db"));
  RunResult wall = run("pick " + (dir / "bcf-architectural.twk").string() +
                       " --eye 9,-40,8 --target 9,-12,7 --pixel 600,400");
  ASSERT_EQ(wall.exit_code, 0) << wall.output;
  EXPECT_NE(wall.output.find("db key      2k7AL9Q4vAfOld2Ju8s3DV"), std::string::npos) << wall.output;
  EXPECT_NE(wall.output.find("IFC / Class = IFCWALLSTANDARDCASE"), std::string::npos) << wall.output;
  EXPECT_NE(wall.output.find("IFC / Storey = 3.Nadzemn"), std::string::npos) << wall.output;
  EXPECT_NE(wall.output.find("WallQuantities / NominalLength = 4 METRE"), std::string::npos)
      << wall.output;
  EXPECT_NE(wall.output.find("Allplan Attributes / Object_name = Mehrsch-Wand"), std::string::npos)
      << wall.output;
}

// Pixels of one object in an ids_NNNNN.png: their count, mean row and bounding box.
struct IdPixels {
  uint64_t count = 0;
  double mean_row = 0.0;
  int min_x = 1 << 30, max_x = -1, min_y = 1 << 30, max_y = -1;
};
IdPixels pixelsOf(const std::filesystem::path& ids_png, uint32_t id) {
  int w = 0, h = 0, channels = 0;
  unsigned char* data = stbi_load(ids_png.string().c_str(), &w, &h, &channels, 4);
  IdPixels p;
  if (!data) return p;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const unsigned char* px = data + 4 * (size_t(y) * w + x);
      const uint32_t value = px[0] | (px[1] << 8) | (px[2] << 16) | (uint32_t(px[3]) << 24);
      if (value != id) continue;
      ++p.count;
      p.mean_row += y;
      p.min_x = std::min(p.min_x, x);
      p.max_x = std::max(p.max_x, x);
      p.min_y = std::min(p.min_y, y);
      p.max_y = std::max(p.max_y, y);
    }
  stbi_image_free(data);
  if (p.count) p.mean_row /= double(p.count);
  return p;
}

// A Y-up OBJ (a floor slab and a column standing on it) read with --up y orbits upright: the
// column stands above the floor in the image, taller than wide. Read Z up (the default) the
// column lies on its side, and info says the model looks Y up.
TEST(Cli, UpYTurnsAYUpObjUpright) {
  const auto dir = test::scratchDir();
  const auto obj = dir / "yup.obj";
  {
    std::string text;
    auto box = [&](const char* name, glm::vec3 lo, glm::vec3 hi, int base) {
      text += std::string("o ") + name + "\n";
      for (int i = 0; i < 8; ++i)
        text += "v " + std::to_string((i & 1) ? hi.x : lo.x) + " " +
                std::to_string((i & 2) ? hi.y : lo.y) + " " + std::to_string((i & 4) ? hi.z : lo.z) +
                "\n";
      const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                               {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
      for (const auto& f : faces)
        text += "f " + std::to_string(base + f[0]) + " " + std::to_string(base + f[1]) + " " +
                std::to_string(base + f[2]) + " " + std::to_string(base + f[3]) + "\n";
    };
    box("floor", {-5.0f, 0.0f, -5.0f}, {5.0f, 0.2f, 5.0f}, 1);
    box("column", {-0.3f, 0.2f, -0.3f}, {0.3f, 6.0f, 0.3f}, 9);
    test::writeFile(obj, text);
  }
  RunResult info = run("info " + obj.string());
  ASSERT_EQ(info.exit_code, 0) << info.output;
  EXPECT_NE(info.output.find("if the file is Y up, read it with --up y"), std::string::npos)
      << info.output;
  RunResult info_y = run("info --up y " + obj.string());
  EXPECT_EQ(info_y.output.find("warning"), std::string::npos) << info_y.output;
  EXPECT_NE(info_y.output.find("read Y up"), std::string::npos) << info_y.output;

  auto orbit = [&](const std::string& name, const std::string& up) {
    const auto twk = dir / (name + ".twk");
    RunResult pre = run("preprocess -q " + obj.string() + " -o " + twk.string() + up);
    EXPECT_EQ(pre.exit_code, 0) << pre.output;
    RunResult render = run("-q render " + twk.string() + " --orbit 1 --size 320x240 --png --out " +
                           (dir / name).string());
    EXPECT_EQ(render.exit_code, 0) << render.output;
    return dir / name / "ids_00000.png";
  };
  // Object indices + 1: the floor is 1, the column 2.
  const auto upright = orbit("upright", " --up y");
  const IdPixels floor = pixelsOf(upright, 1), column = pixelsOf(upright, 2);
  ASSERT_GT(floor.count, 100u);
  ASSERT_GT(column.count, 100u);
  EXPECT_LT(column.mean_row, floor.mean_row) << "the column stands above the floor";
  EXPECT_GT(column.max_y - column.min_y, 2 * (column.max_x - column.min_x)) << "and upright";
  EXPECT_GT(floor.max_x - floor.min_x, floor.max_y - floor.min_y) << "the floor lies flat";

  const auto lying = orbit("lying", "");
  const IdPixels lying_column = pixelsOf(lying, 2);
  ASSERT_GT(lying_column.count, 100u);
  EXPECT_LT(lying_column.max_y - lying_column.min_y, lying_column.max_x - lying_column.min_x)
      << "read Z up, the column lies on its side";
}

// The Revit MEP model is Y up. Read with --up y, its orbit is upright in every frame: the
// parts at the file's lowest Y (the ground-floor runs) are drawn below those at its highest Y
// (the runs under the roof). Read Z up, the model lies on its side and the orbit turns it round
// the wrong axis, so that order holds in some frames and not in others.
TEST(Cli, UpYOrbitsTheYUpMepModelUpright) {
  const auto file = test::sharedDataDir() / "duplex-mep.obj";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data not present: " << file;
  test::CollectingSink scene;
  readObj(file, scene);
  float lowest = INFINITY, highest = -INFINITY;
  std::vector<std::pair<float, float>> span;  // per object: its file-Y range
  for (const SceneObject& o : scene.objects) {
    const auto& mesh = std::get<TriangleMesh>(o.geometry);
    float lo = INFINITY, hi = -INFINITY;
    for (const glm::vec3& p : mesh.positions) {
      const float y = float(o.info.transform.origin.y) + p.y;  // OBJ objects are not rotated
      lo = std::min(lo, y);
      hi = std::max(hi, y);
    }
    if (span.size() <= o.info.id) span.resize(o.info.id + 1, {INFINITY, -INFINITY});
    span[o.info.id] = {std::min(span[o.info.id].first, lo), std::max(span[o.info.id].second, hi)};
    lowest = std::min(lowest, lo);
    highest = std::max(highest, hi);
  }
  const float band = 0.2f * (highest - lowest);
  std::vector<uint32_t> bottom, top;  // ids + 1, as the id images hold them
  for (uint32_t id = 0; id < span.size(); ++id) {
    if (span[id].second < lowest + band) bottom.push_back(id + 1);
    if (span[id].first > highest - band) top.push_back(id + 1);
  }
  ASSERT_GT(bottom.size(), 20u);
  ASSERT_GT(top.size(), 5u);

  const auto dir = test::scratchDir();
  constexpr int kFrames = 8;
  // Per frame where both kinds of part are drawn: whether the bottom parts lie lower in the image
  // (larger rows) than the top parts, on average. A frame drawn from the root alone, while its
  // pages stream in (the first), may show too little of either to count. Returns the frames
  // that count and those upright among them.
  std::string rows_seen;  // per frame: the bottom and top parts' mean rows, for a failure message
  auto uprightFrames = [&](const std::string& name, const std::string& up) {
    rows_seen = name + ":";
    const auto twk = dir / (name + ".twk");
    RunResult pre = run("preprocess -q " + file.string() + " -o " + twk.string() + up);
    EXPECT_EQ(pre.exit_code, 0) << pre.output;
    RunResult render = run("-q render " + twk.string() + " --orbit " + std::to_string(kFrames) +
                           " --size 480x360 --png --out " + (dir / name).string());
    EXPECT_EQ(render.exit_code, 0) << render.output;
    int seen = 0, upright = 0;
    for (int f = 0; f < kFrames; ++f) {
      char ids[32];
      std::snprintf(ids, sizeof ids, "ids_%05d.png", f);
      auto meanRow = [&](const std::vector<uint32_t>& parts) {
        double rows = 0.0;
        uint64_t count = 0;
        for (uint32_t id : parts) {
          const IdPixels p = pixelsOf(dir / name / ids, id);
          rows += p.mean_row * double(p.count);
          count += p.count;
        }
        return count >= 20 ? std::optional<double>(rows / double(count)) : std::nullopt;
      };
      const auto bottom_row = meanRow(bottom), top_row = meanRow(top);
      rows_seen += " " + (bottom_row ? std::to_string(int(*bottom_row)) : std::string("-")) + "/" +
                   (top_row ? std::to_string(int(*top_row)) : std::string("-"));
      // Both seen, and the bottom parts 15 of 360 rows lower at least.
      if (!bottom_row || !top_row) continue;
      ++seen;
      if (*bottom_row > *top_row + 15.0) ++upright;
    }
    return std::pair(seen, upright);
  };
  const auto [seen, upright] = uprightFrames("upright", " --up y");
  EXPECT_GE(seen, kFrames - 1) << rows_seen;
  EXPECT_EQ(upright, seen) << "every frame upright; " << rows_seen;
  const auto [seen_lying, upright_lying] = uprightFrames("lying", "");
  EXPECT_GE(seen_lying, kFrames / 2) << rows_seen;
  EXPECT_LT(upright_lying, seen_lying) << "read Z up, the model lies on its side; " << rows_seen;
}

TEST(Cli, RenderWritesFramesStatsAndReplaysItsPath) {
  auto package = bunnyPackageForCli();
  auto dir = test::scratchDir();
  RunResult r = run("render --quiet " + package.string() + " --orbit 4 --size 96x64 --png --out " +
                    (dir / "orbit").string() + " --save-path " + (dir / "orbit.path").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* name : {"frame_00000.png", "ids_00003.png", "frames.csv", "frames.json",
                           "summary.json"})
    EXPECT_TRUE(std::filesystem::exists(dir / "orbit" / name)) << name;
  auto summary = nlohmann::json::parse(test::readFile(dir / "orbit" / "summary.json"));
  EXPECT_EQ(summary["frames"], 4);
  EXPECT_GT(summary["median_triangles"].get<double>(), 0.0);
  auto frames = nlohmann::json::parse(test::readFile(dir / "orbit" / "frames.json"));
  ASSERT_EQ(frames["frames"].size(), 4u);
  EXPECT_GT(frames["frames"][0]["triangles_drawn"].get<uint64_t>(), 0u);
  std::string csv = test::readFile(dir / "orbit" / "frames.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 5);  // header + 4 frames

  RunResult replay = run("render --quiet " + package.string() + " --path " +
                         (dir / "orbit.path").string() + " --size 96x64 --out " +
                         (dir / "replay").string());
  ASSERT_EQ(replay.exit_code, 0) << replay.output;
  auto replayed = nlohmann::json::parse(test::readFile(dir / "replay" / "summary.json"));
  EXPECT_EQ(replayed["frames"], 4);

  RunResult reference = run("render --quiet " + package.string() + " --orbit 2 --size 96x64 " +
                            "--reference --out " + (dir / "reference").string());
  ASSERT_EQ(reference.exit_code, 0) << reference.output;
  auto ref = nlohmann::json::parse(test::readFile(dir / "reference" / "summary.json"));
  EXPECT_EQ(ref["mode"], "reference");
  EXPECT_EQ(ref["median_triangles"].get<double>(), 69451.0);  // every bunny triangle
}

// `--walk-fps`: the camera is also rendered between the recorded frames, which keep their times,
// their numbering and their PNG names; a negative rate is refused.
TEST(Cli, RenderWalksBetweenRecordedFrames) {
  auto package = bunnyPackageForCli();
  auto dir = test::scratchDir();
  RunResult orbit = run("render --quiet " + package.string() + " --orbit 4 --size 64x48 --out " +
                        (dir / "plain").string() + " --save-path " + (dir / "orbit.path").string());
  ASSERT_EQ(orbit.exit_code, 0) << orbit.output;
  RunResult r = run("render --quiet " + package.string() + " --path " +
                    (dir / "orbit.path").string() + " --fps 30 --walk-fps 120 --size 64x48 --png " +
                    "--out " + (dir / "walked").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto summary = nlohmann::json::parse(test::readFile(dir / "walked" / "summary.json"));
  EXPECT_EQ(summary["frames"], 4);
  EXPECT_EQ(summary["walk_fps"], 120.0);
  EXPECT_EQ(summary["walk_frames"], 9);  // three steps between each of the four frames
  auto walked = nlohmann::json::parse(test::readFile(dir / "walked" / "frames.json"))["frames"];
  auto plain = nlohmann::json::parse(test::readFile(dir / "plain" / "frames.json"))["frames"];
  ASSERT_EQ(walked.size(), 4u);
  for (size_t i = 0; i < walked.size(); ++i) {
    EXPECT_EQ(walked[i]["frame"], i);
    EXPECT_DOUBLE_EQ(walked[i]["time_s"].get<double>(), plain[i]["time_s"].get<double>());
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "walked" / "frame_00003.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "walked" / "frame_00004.png"));

  RunResult negative = run("render --quiet " + package.string() + " --orbit 2 --size 32x32 " +
                           "--walk-fps -1");
  EXPECT_EQ(negative.exit_code, 1) << negative.output;
  EXPECT_NE(negative.output.find("--walk-fps"), std::string::npos) << negative.output;
}

// Values that would hang the run (a walk of a billion steps a frame), wrap (a width past 32
// bits read as 1) or take gigabytes (16384x16384) are refused at once, naming the option.
TEST(Cli, RenderRefusesOptionValuesThatWouldHangWrapOrFillMemory) {
  auto package = bunnyPackageForCli();
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"--walk-fps 1e9", "--walk-fps 1e+09: must be 0 to 1000 times --fps (30)"},
      {"--fps inf", "--fps inf: must be above 0"},
      {"--size 4294967297x1", "got '4294967297x1': each side must be 1 to 16384 pixels"},
      {"--size 16384x16384", "got '16384x16384': at most 33554432 pixels"},
      {"--size 64x48junk", "got '64x48junk'"},
      {"--tau nan", "--tau nan: must be above 0"},
      {"--tau -1", "--tau -1: must be above 0"},
      {"--max-frames 0", "--max-frames"},
  };
  for (const auto& [option, message] : refused) {
    const std::string size = option.rfind("--size", 0) == 0 ? "" : "--size 32x32 ";
    RunResult r = run("render --quiet " + package.string() + " --orbit 2 " + size + option);
    EXPECT_NE(r.exit_code, 0) << option;
    EXPECT_NE(r.output.find(message), std::string::npos) << option << ": " << r.output;
    EXPECT_LT(r.output.size(), 400u) << option << ": one short line";
  }
}

// The package's path is checked before any input is read: an input given as the output is left
// as it was, and a folder, an empty path or a missing folder fail at once with the path named.
TEST(Cli, PreprocessRefusesAnOutputItCannotWriteBeforeReadingAnything) {
  auto dir = test::scratchDir();
  const auto scene = dir / "s.tws";
  ASSERT_EQ(run("gen plant --quiet --triangles 20K --no-db -o " + scene.string()).exit_code, 0);
  const std::string before = test::readFile(scene);
  const std::vector<std::pair<std::string, std::string>> refused = {
      {scene.string(), scene.string() + ": is also an input; writing the package there would destroy it"},
      {dir.string(), dir.string() + ": is a directory"},
      {"''", "the output path (-o) is empty"},
      {(dir / "missing" / "p.twk").string(), "the folder " + (dir / "missing").string() + " does not exist"},
  };
  for (const auto& [output, message] : refused) {
    RunResult r = run("preprocess --quiet " + scene.string() + " -o " + output);
    EXPECT_NE(r.exit_code, 0) << output;
    EXPECT_NE(r.output.find(message), std::string::npos) << output << ": " << r.output;
  }
  EXPECT_EQ(test::readFile(scene), before) << "the input is untouched";
  EXPECT_FALSE(std::filesystem::exists(dir / "s.tws.work"));
}

TEST(Cli, RenderRejectsABadPathFileNamingTheLine) {
  auto package = bunnyPackageForCli();
  auto dir = test::scratchDir();
  test::writeFile(dir / "bad.path", "# terawalk camera path 1\n0 1 2 3 0 0 60\n1 1 2 zz 0 0 60\n");
  RunResult r = run("render --quiet " + package.string() + " --path " +
                    (dir / "bad.path").string() + " --size 32x32");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("bad.path"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("bad.path:3: z is not a number"), std::string::npos) << r.output;
  RunResult no_path = run("render --quiet " + package.string() + " --size 32x32");
  EXPECT_EQ(no_path.exit_code, 1) << no_path.output;
}

}  // namespace
}  // namespace tw
