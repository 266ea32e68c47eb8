// The report side of `terawalk bench`: report.md with its tables, gnuplot plots, and the ratios of
// one results.json against an earlier one (--compare). Pure over the results JSON, so a report can
// be made again from a saved results.json.
#pragma once

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

namespace tw {

// Writes out_dir/report.md and out_dir/plots/*.png (gnuplot, from *.dat and *.gp written beside
// them). Without gnuplot on PATH the report says so and lists no plots. Throws
// std::runtime_error when a file cannot be written.
void writeBenchReport(const nlohmann::json& results, const std::filesystem::path& out_dir);

// One line per numeric figure present in both results (per-frame series excluded): old, new and
// new / old, so a regression shows up.
std::string compareBenchResults(const nlohmann::json& old_results,
                                const nlohmann::json& new_results);

}  // namespace tw
