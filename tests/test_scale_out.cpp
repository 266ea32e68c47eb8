// Scale-out preprocessing (preprocess_steps.h, tools/preprocess_mpi.h, tools/slurm): the plan,
// brick and merge steps run by hand, by two MPI ranks, by a killed and re-run mpirun and by the
// Slurm script all write the package a one-process `terawalk preprocess` writes, byte for byte.
#include <gtest/gtest.h>

#include <signal.h>

#include <chrono>
#include <fstream>
#include <regex>
#include <set>
#include <thread>

#include "brick_seams.h"
#include "preprocess_plan.h"
#include "test_support.h"
#include "x_screen_support.h"

namespace tw {
namespace {

// A 1M plant in bricks of at most 60,000 triangles (a dozen), and its one-process package:
// built once for the whole program.
struct Fixture {
  std::filesystem::path scene, package;
  size_t bricks = 0;
};
const std::string kOptions = " --brick-triangles 60000";

const Fixture& fixture() {
  static const Fixture f = [] {
    const auto dir = test::processScratchDir("scale_out");
    Fixture out{dir / "plant.tws", dir / "one.twk"};
    const test::CommandResult gen = test::runTerawalk(
        "--quiet gen plant --triangles 1M --seed 3 --no-db -o " + out.scene.string());
    EXPECT_EQ(gen.exit_code, 0) << gen.output;
    const test::CommandResult one = test::runTerawalk(
        "--quiet preprocess " + out.scene.string() + " -o " + out.package.string() + kOptions);
    EXPECT_EQ(one.exit_code, 0) << one.output;
    const test::CommandResult plan = test::runTerawalk(
        "--quiet preprocess plan " + out.scene.string() + " --work " + (dir / "work").string() +
        kOptions);
    EXPECT_EQ(plan.exit_code, 0) << plan.output;
    out.bricks = readPreprocessPlan(dir / "work").jobs.size();
    EXPECT_GE(out.bricks, 8u);
    return out;
  }();
  return f;
}

bool sameBytes(const std::filesystem::path& a, const std::filesystem::path& b) {
  const std::string x = test::readFile(a), y = test::readFile(b);
  return !x.empty() && x == y;
}

bool haveMpirun() { return std::system("command -v mpirun > /dev/null 2>&1") == 0; }

std::string mpirun(int ranks) {
  return "mpirun -np " + std::to_string(ranks) + " --oversubscribe --allow-run-as-root --bind-to none ";
}

// The bricks a log names with `what` ("already built", or a number of triangles when built).
std::set<uint32_t> bricksIn(const std::string& log, const std::string& pattern) {
  std::set<uint32_t> bricks;
  const std::regex line("brick ([0-9]+) of [0-9]+: " + pattern);
  for (auto it = std::sregex_iterator(log.begin(), log.end(), line); it != std::sregex_iterator(); ++it)
    bricks.insert(uint32_t(std::stoul((*it)[1])));
  return bricks;
}

TEST(ScaleOut, StepsRunByHandWriteTheOneProcessPackage) {
  const auto dir = test::scratchDir();
  const auto work = dir / "work";
  const auto plan = test::runTerawalk("--quiet preprocess plan " + fixture().scene.string() +
                                      " --work " + work.string() + kOptions);
  ASSERT_EQ(plan.exit_code, 0) << plan.output;
  const size_t n = fixture().bricks;
  const std::string count = std::to_string(n);
  EXPECT_NE(plan.output.find("plan: " + count + " brick jobs"), std::string::npos) << plan.output;
  const PreprocessPlan manifest = readPreprocessPlan(work);
  ASSERT_EQ(manifest.jobs.size(), n);
  for (size_t j = 1; j < manifest.jobs.size(); ++j)
    EXPECT_GE(manifest.jobs[j - 1].triangles, manifest.jobs[j].triangles) << "largest first";
  EXPECT_TRUE(manifest.options.inputs.front().is_absolute());

  // Every job but the last; the merge then refuses, naming the missing brick.
  for (size_t j = 0; j + 1 < manifest.jobs.size(); ++j) {
    const auto brick = test::runTerawalk("--quiet preprocess brick --work " + work.string() +
                                         " --job " + std::to_string(j));
    ASSERT_EQ(brick.exit_code, 0) << brick.output;
    EXPECT_EQ(bricksIn(brick.output, "[0-9]+ triangles"), std::set{manifest.jobs[j].index});
  }
  const uint32_t last = manifest.jobs.back().index;
  const auto early = test::runTerawalk("--quiet preprocess merge --work " + work.string() +
                                       " -o " + (dir / "early.twk").string());
  EXPECT_NE(early.exit_code, 0);
  EXPECT_NE(early.output.find("1 of " + count + " bricks are not built (" + std::to_string(last) + ")"),
            std::string::npos)
      << early.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "early.twk"));

  const std::string last_brick =
      "--quiet preprocess brick --work " + work.string() + " --index " + std::to_string(last);
  ASSERT_EQ(test::runTerawalk(last_brick).exit_code, 0);
  const auto again = test::runTerawalk(last_brick);
  EXPECT_EQ(again.exit_code, 0);
  EXPECT_EQ(bricksIn(again.output, "already built"), std::set{last}) << again.output;
  const auto outside = test::runTerawalk("--quiet preprocess brick --work " + work.string() +
                                         " --index " + count);
  EXPECT_NE(outside.exit_code, 0);
  EXPECT_NE(outside.output.find("index " + count + " is not in the plan (" + count + " bricks, 0.." +
                                std::to_string(n - 1) + ")"),
            std::string::npos)
      << outside.output;

  const auto merge = test::runTerawalk("--quiet preprocess merge --work " + work.string() +
                                       " -o " + (dir / "split.twk").string());
  ASSERT_EQ(merge.exit_code, 0) << merge.output;
  EXPECT_TRUE(sameBytes(dir / "split.twk", fixture().package));
  EXPECT_FALSE(std::filesystem::exists(work)) << "the merge removes the work directory";
}

TEST(ScaleOut, AStepRefusesAWorkDirectoryWithoutAPlanOrWithChangedInputs) {
  const auto dir = test::scratchDir();
  const auto none = test::runTerawalk("--quiet preprocess brick --work " + (dir / "none").string() +
                                      " --index 0");
  EXPECT_NE(none.exit_code, 0);
  EXPECT_NE(none.output.find("manifest.json: no plan here; run `terawalk preprocess plan"),
            std::string::npos)
      << none.output;

  const auto scene = dir / "plant.tws";
  std::filesystem::copy_file(fixture().scene, scene);
  const auto work = dir / "work";
  ASSERT_EQ(test::runTerawalk("--quiet preprocess plan " + scene.string() + " --work " +
                              work.string() + kOptions)
                .exit_code,
            0);
  std::filesystem::last_write_time(scene, std::filesystem::last_write_time(scene) +
                                              std::chrono::seconds(10));
  const auto changed =
      test::runTerawalk("--quiet preprocess brick --work " + work.string() + " --job 0");
  EXPECT_NE(changed.exit_code, 0);
  EXPECT_NE(changed.output.find("changed since the plan was made"), std::string::npos)
      << changed.output;
}

// A damaged manifest is an error naming the file, never a crash or a brick built from garbage.
TEST(ScaleOut, ATruncatedOrCorruptedManifestIsAClearError) {
  const auto dir = test::scratchDir();
  const auto work = dir / "work";
  ASSERT_EQ(test::runTerawalk("--quiet preprocess plan " + fixture().scene.string() + " --work " +
                              work.string() + kOptions)
                .exit_code,
            0);
  const std::string manifest = test::readFile(planPath(work));
  for (size_t cut : {size_t(0), size_t(1), manifest.size() / 3, manifest.size() - 3}) {
    test::writeFile(planPath(work), manifest.substr(0, cut));
    try {
      readPreprocessPlan(work);
      ADD_FAILURE() << "a manifest cut at " << cut << " was read";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(planPath(work).string() + ": "), std::string::npos)
          << e.what();
    }
  }
  std::string wrong = manifest;
  wrong.replace(wrong.find("\"cluster_size\""), 14, "\"cluster_sizE\"");
  test::writeFile(planPath(work), wrong);
  EXPECT_THROW(readPreprocessPlan(work), std::runtime_error);
}

TEST(ScaleOut, SeamsReadBackEqualAndADamagedBlobIsRefused) {
  std::vector<std::vector<SeamEdgeKey>> per_brick(2);
  const SeamEdgeKey shared = seamEdgeKey({0, 0, 0}, {1, 0, 0});
  per_brick[0] = {shared, seamEdgeKey({0, 0, 0}, {0, 1, 0})};
  per_brick[1] = {shared};
  for (auto& keys : per_brick) std::sort(keys.begin(), keys.end());
  const BrickSeams seams = BrickSeams::fromOpenEdges(per_brick);
  const std::vector<uint8_t> bytes = seams.serialize();
  const BrickSeams back = BrickSeams::deserialize(bytes, "seams");
  EXPECT_EQ(back.size(), 1u);
  EXPECT_TRUE(back.contains({1, 0, 0}, {0, 0, 0}));
  EXPECT_FALSE(back.contains({0, 0, 0}, {0, 1, 0}));
  EXPECT_EQ(back.serialize(), bytes);
  for (size_t cut = 0; cut < bytes.size(); ++cut)
    EXPECT_THROW(BrickSeams::deserialize(std::span(bytes.data(), cut), "seams"), FormatError);
}

TEST(ScaleOut, TwoMpiRanksWriteTheOneProcessPackage) {
  if (!haveMpirun()) GTEST_SKIP() << "no mpirun (openmpi-bin)";
  const auto dir = test::scratchDir();
  const auto out = dir / "mpi.twk";
  const auto run = test::runShell(mpirun(2) + TW_TERAWALK_EXE + " --quiet preprocess --mpi " +
                                  fixture().scene.string() + " -o " + out.string() + kOptions);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const size_t n = fixture().bricks;
  EXPECT_NE(run.output.find("plan of " + std::to_string(n) + " bricks; 2 ranks build them"),
            std::string::npos);
  // Both ranks built bricks, and every brick was built once.
  const std::set<uint32_t> all = bricksIn(run.output, "[0-9]+ triangles");
  EXPECT_EQ(all.size(), n) << run.output;
  EXPECT_NE(run.output.find("rank 0: brick"), std::string::npos);
  EXPECT_NE(run.output.find("rank 1: brick"), std::string::npos);
  EXPECT_TRUE(sameBytes(out, fixture().package));
}

// A rank killed while it builds a brick takes the run down (mpirun's rule); what was finished
// stays, and the same command again builds only the rest.
TEST(ScaleOut, AKilledRankLosesOnlyItsBrickAndTheSameCommandFinishes) {
  if (!haveMpirun()) GTEST_SKIP() << "no mpirun (openmpi-bin)";
  const auto dir = test::scratchDir();
  const auto out = dir / "mpi.twk";
  const std::vector<std::string> command = {
      "mpirun", "-np", "2", "--oversubscribe", "--allow-run-as-root", "--bind-to", "none", TW_TERAWALK_EXE, "--quiet",
      "preprocess", "--mpi", fixture().scene.string(), "-o", out.string(), "--threads", "1",
      "--brick-triangles", "60000"};
  const auto first_log = dir / "first.log";
  int killed_brick = -1;
  {
    test::BackgroundProcess run(command, {}, first_log);
    // Rank 1's second brick: by then both ranks have finished one.
    const std::regex started("rank 1 \\(pid ([0-9]+)\\): brick ([0-9]+) of [0-9]+ started");
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (run.running() && killed_brick < 0 && std::chrono::steady_clock::now() < deadline) {
      const std::string log = test::readFile(first_log);
      auto it = std::sregex_iterator(log.begin(), log.end(), started);
      if (it != std::sregex_iterator() && ++it != std::sregex_iterator()) {
        ::kill(pid_t(std::stol((*it)[1])), SIGKILL);
        killed_brick = std::stoi((*it)[2]);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    ASSERT_GE(killed_brick, 0) << test::readFile(first_log);
    EXPECT_NE(run.wait(), 0) << "mpirun reports the killed rank";
  }
  const std::string first = test::readFile(first_log);
  EXPECT_FALSE(std::filesystem::exists(out));
  const std::set<uint32_t> finished = bricksIn(first, "[0-9]+ triangles");
  EXPECT_FALSE(finished.count(uint32_t(killed_brick))) << first;

  const auto again = test::runShell(mpirun(2) + TW_TERAWALK_EXE + " --quiet preprocess --mpi " +
                                    fixture().scene.string() + " -o " + out.string() + kOptions);
  ASSERT_EQ(again.exit_code, 0) << again.output;
  const std::set<uint32_t> kept = bricksIn(again.output, "already built");
  const std::set<uint32_t> rebuilt = bricksIn(again.output, "[0-9]+ triangles");
  for (uint32_t b : finished) EXPECT_TRUE(kept.count(b)) << "brick " << b << " was rebuilt";
  EXPECT_TRUE(rebuilt.count(uint32_t(killed_brick))) << again.output;
  EXPECT_EQ(kept.size() + rebuilt.size(), fixture().bricks);
  EXPECT_GE(kept.size(), 2u);
  EXPECT_TRUE(sameBytes(out, fixture().package));
}

// tools/slurm/preprocess.sbatch without Slurm: each step run by hand, the array's tasks in a
// loop; and its plan step's submissions, seen through an `sbatch` that only records them.
TEST(ScaleOut, TheSlurmScriptRunByHandWritesTheOneProcessPackage) {
  const auto dir = test::scratchDir();
  const std::string script = std::string(TW_SOURCE_DIR) + "/tools/slurm/preprocess.sbatch";
  const std::string env = "TERAWALK=" + std::string(TW_TERAWALK_EXE) +
                          " TW_INPUTS=" + fixture().scene.string() +
                          " TW_OUTPUT=" + (dir / "slurm.twk").string() + " TW_OPTIONS='" +
                          kOptions + "' ";
  const size_t n = fixture().bricks;
  const std::string last = std::to_string(n - 1);
  const auto plan = test::runShell(env + "TW_SUBMIT=no " + script + " plan");
  ASSERT_EQ(plan.exit_code, 0) << plan.output;
  EXPECT_NE(plan.output.find(std::to_string(n) + " brick jobs (tasks 0-" + last + "); not submitted"),
            std::string::npos)
      << plan.output;
  const auto bricks = test::runShell("for i in $(seq 0 " + last + "); do SLURM_ARRAY_TASK_ID=$i " +
                                     env + script + " brick || exit 1; done");
  ASSERT_EQ(bricks.exit_code, 0) << bricks.output;
  EXPECT_EQ(bricksIn(bricks.output, "[0-9]+ triangles").size(), n) << bricks.output;
  const auto merge = test::runShell(env + script + " merge");
  ASSERT_EQ(merge.exit_code, 0) << merge.output;
  EXPECT_TRUE(sameBytes(dir / "slurm.twk", fixture().package));

  // The plan job's submissions: the array over the plan's jobs, the merge after it.
  const auto bin = dir / "bin";
  std::filesystem::create_directories(bin);
  test::writeFile(bin / "sbatch",
                  "#!/bin/sh\necho \"$@\" >> " + (dir / "sbatch.txt").string() +
                      "\necho $((4200 + $(wc -l < " + (dir / "sbatch.txt").string() + ")))\n");
  std::filesystem::permissions(bin / "sbatch", std::filesystem::perms::owner_all);
  const auto submit = test::runShell("PATH=" + bin.string() + ":$PATH TW_PARALLEL=4 " + env +
                                     script + " plan");
  ASSERT_EQ(submit.exit_code, 0) << submit.output;
  const std::string calls = test::readFile(dir / "sbatch.txt");
  EXPECT_NE(calls.find("--parsable --job-name=terawalk-brick --array=0-" + last + "%4 " + script +
                       " brick"),
            std::string::npos)
      << calls;
  EXPECT_NE(calls.find("--dependency=afterok:4201 " + script + " merge"), std::string::npos)
      << calls;
}

}  // namespace
}  // namespace tw
