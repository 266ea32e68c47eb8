// The soak test, two minutes of it: `terawalk render --random-walk` (teleports, fast flights,
// turns in place, walks) through duplex-mep with a GPU budget small enough that pages are evicted
// every few frames, logged by `--soak-interval` (no per-frame log, so the process's own memory is
// what grows or not). The hour-long run is bench/soak.sh. Registered first among the test
// programs, so CTest starts it first and the rest of the suite runs beside it.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "package_view.h"
#include "test_support.h"

namespace tw {
namespace {

// soak.csv as rows of named numbers.
std::vector<std::map<std::string, double>> readSoakCsv(const std::filesystem::path& file) {
  std::istringstream text(test::readFile(file));
  std::string line;
  std::vector<std::string> columns;
  std::vector<std::map<std::string, double>> rows;
  while (std::getline(text, line)) {
    std::vector<std::string> cells;
    std::stringstream fields(line);
    for (std::string cell; std::getline(fields, cell, ',');) cells.push_back(cell);
    if (columns.empty()) {
      columns = cells;
      continue;
    }
    EXPECT_EQ(cells.size(), columns.size()) << line;
    std::map<std::string, double> row;
    for (size_t i = 0; i < cells.size() && i < columns.size(); ++i) row[columns[i]] = std::stod(cells[i]);
    rows.push_back(row);
  }
  return rows;
}

double largest(const std::vector<std::map<std::string, double>>& rows, size_t from, size_t to,
               const std::function<double(const std::map<std::string, double>&)>& value) {
  double most = 0.0;
  for (size_t i = from; i < to; ++i) most = std::max(most, value(rows[i]));
  return most;
}

// Two minutes of eviction every few frames: resident memory in the last third of the run no
// higher than in the middle third (within 8 MiB of allocator noise), the pager's queues in the
// last third no longer than before, no page failing, and the frames evicting and loading pages
// all along (so the test could not pass by drawing a model that stays resident).
TEST(Soak, TwoMinutesOfRandomWalkKeepMemoryAndThePagerQueuesFlat) {
  const auto model = test::sharedDataDir() / "duplex-mep.obj";
  if (!std::filesystem::exists(model)) GTEST_SKIP() << "shared data not present: " << model;
  const auto dir = test::scratchDir();
  const auto package = dir / "duplex.twk";
  auto pre = test::runTerawalk("-q preprocess " + model.string() + " --up y -o " + package.string());
  ASSERT_EQ(pre.exit_code, 0) << pre.output;
  const size_t pages = PackageView::open(package).pages().size();

  auto r = test::runTerawalk("-q render " + package.string() +
                             " --random-walk 60000 --seed 7 --max-seconds 120 --gpu-budget 4M "
                             "--evict-after 2 --size 640x360 --soak-interval 5 --out " +
                             (dir / "soak").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto rows = readSoakCsv(dir / "soak" / "soak.csv");
  ASSERT_GE(rows.size(), 12u) << "one row per 5 s of a run of up to 120 s";
  EXPECT_GE(rows.back().at("wall_s"), 60.0) << "it ran for two minutes, or its whole path";

  double frames = 0, evicting = 0, loaded = 0;
  for (const auto& row : rows) {
    frames += row.at("frames");
    evicting += row.at("frames_with_eviction");
    loaded += row.at("pages_loaded");
  }
  EXPECT_GE(evicting, 0.2 * frames) << "pages evicted every few frames";
  EXPECT_GE(loaded, 1000.0);
  EXPECT_EQ(rows.back().at("page_load_errors"), 0.0);

  const size_t third = rows.size() / 3;
  auto rss = [](const std::map<std::string, double>& row) { return row.at("rss_max_bytes"); };
  const double middle = largest(rows, third, 2 * third, rss);
  const double last = largest(rows, 2 * third, rows.size(), rss);
  EXPECT_LE(last, middle + 8.0 * 1024 * 1024)
      << "resident memory grew from " << middle / 1048576 << " to " << last / 1048576 << " MiB";
  auto queue = [](const std::map<std::string, double>& row) {
    return row.at("pages_requested_max") + row.at("pages_loading_max") + row.at("pages_ready_max");
  };
  EXPECT_LE(largest(rows, 2 * third, rows.size(), queue), largest(rows, 0, 2 * third, queue))
      << "the pager's queues grew in the last third";
  for (const char* state : {"pages_requested_max", "pages_ready_max"})
    EXPECT_LE(largest(rows, 0, rows.size(), [&](const auto& row) { return row.at(state); }),
              double(pages))
        << state;
  EXPECT_LE(largest(rows, 0, rows.size(), [](const auto& row) { return row.at("pages_loading_max"); }),
            2.0)
      << "two loader threads";
}

}  // namespace
}  // namespace tw
