// `terawalk verify FILE.twk`: proves a package is intact and consistent before anyone ships or
// renders it (checksums, references, monotone errors, bounds, crack-freedom; docs/verify.md).
// Exit 0 when every check passes; 1 with the first failure otherwise.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>

#include "command.h"
#include "dag_levels.h"
#include "package_check.h"
#include "package_view.h"

namespace tw {
namespace {

struct VerifyOptions {
  std::string file;
  bool json = false;
  bool no_cracks = false;
};

// Exits the process with status 1 after printing: the verb's result is its exit status, and a
// failed check is not an error of the program (main() would print "error:").
[[noreturn]] void exitFailed() {
  std::fflush(stdout);
  std::exit(1);
}

nlohmann::json countsToJson(const CheckCounts& c) {
  return {{"checksums", c.checksums},       {"pages", c.pages},
          {"clusters", c.clusters},         {"groups", c.groups},
          {"vertices", c.vertices},         {"instances", c.instances},
          {"border_edges", c.border_edges}, {"boundary_edges", c.boundary_edges}};
}

nlohmann::json levelsToJson(const DagLevels& d) {
  nlohmann::json levels = nlohmann::json::array();
  for (const DagLevel& l : d.levels)
    levels.push_back({{"triangles", l.triangles},
                      {"clusters", l.clusters},
                      {"ratio", l.ratio},
                      {"max_error", l.max_error}});
  return {{"levels", levels},
          {"root_clusters", d.root_clusters},
          {"halves", d.halves},
          {"errors_monotone", d.errors_monotone}};
}

// The DAG's shape, three lines: triangles per level, each level's ratio to the one below, and
// the largest error per level.
void printLevels(const DagLevels& d) {
  std::printf("  levels  %zu, mesh triangles per level's front:", d.levels.size());
  for (const DagLevel& l : d.levels) std::printf(" %llu", static_cast<unsigned long long>(l.triangles));
  std::printf("; root %u cluster%s\n", d.root_clusters, d.root_clusters == 1 ? "" : "s");
  std::printf("  ratios ");
  for (size_t l = 1; l < d.levels.size(); ++l) std::printf(" %.3f", d.levels[l].ratio);
  std::printf(": %s\n", d.halves ? "every level above 1000 triangles halves (0.30 to 0.65)"
                                  : "NOT every level above 1000 triangles within 0.30 to 0.65");
  std::printf("  errors ");
  for (const DagLevel& l : d.levels) std::printf(" %.3g", double(l.max_error));
  std::printf(" (largest per level, metres): %s\n",
              d.errors_monotone ? "monotone" : "NOT monotone");
}

}  // namespace

void registerVerifyCommand(CLI::App& app, const GlobalOptions& global) {
  auto options = std::make_shared<VerifyOptions>();
  CLI::App* cmd = app.add_subcommand(
      "verify", "Check a package: checksums, references, errors, bounds, crack-freedom");
  cmd->add_option("file", options->file, "Package (.twk)")->required()->check(CLI::ExistingFile);
  cmd->add_flag("--json", options->json, "Machine-readable output");
  cmd->add_flag("--no-cracks", options->no_cracks,
                "Skip the crack check (the one that holds two levels in memory)");
  cmd->callback([options, &global] {
    auto progress = makeCommandProgress(global);
    const auto start = std::chrono::steady_clock::now();
    CheckReport report;
    std::optional<PackageView> view;
    try {
      view.emplace(PackageView::open(options->file, PackageView::Verify::Headers));
    } catch (const FormatError& e) {
      // The view's own checks (identity, table, records, references): the package is unusable.
      report.failure = CheckFailure{"structure", e.reason(), e.position()};
    }
    if (view) {
      CheckOptions check;
      check.cracks = !options->no_cracks;
      report = checkPackage(*view, check, progress.get());
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (report.cancelled) throw std::runtime_error("verify: cancelled");
    if (options->json) {
      nlohmann::json j;
      j["file"] = options->file;
      j["ok"] = report.ok();
      j["checked"] = countsToJson(report.counts);
      j["seconds"] = seconds;
      if (view) j["dag"] = levelsToJson(dagLevels(*view));
      if (report.failure) {
        const CheckFailure& f = *report.failure;
        nlohmann::json failure = {{"check", f.check}, {"what", f.what}, {"byte", f.file_offset}};
        if (f.cluster != pkg::kNone) failure["cluster"] = f.cluster;
        if (f.group != pkg::kNone) failure["group"] = f.group;
        if (f.page != pkg::kNone) failure["page"] = f.page;
        j["failure"] = failure;
      } else {
        j["failure"] = nullptr;
      }
      std::cout << j.dump(2) << "\n";
    } else if (report.failure) {
      const CheckFailure& f = *report.failure;
      std::printf("%s: FAILED (%s) at byte %llu: %s\n", options->file.c_str(), f.check.c_str(),
                  static_cast<unsigned long long>(f.file_offset), f.what.c_str());
    } else {
      const CheckCounts& c = report.counts;
      std::printf(
          "%s: OK: %llu checksums, %llu pages, %llu clusters (%llu vertices, %llu instances), "
          "%llu groups, %llu shared border edges, %llu boundary edges checked in %.2f s\n",
          options->file.c_str(), static_cast<unsigned long long>(c.checksums),
          static_cast<unsigned long long>(c.pages), static_cast<unsigned long long>(c.clusters),
          static_cast<unsigned long long>(c.vertices), static_cast<unsigned long long>(c.instances),
          static_cast<unsigned long long>(c.groups),
          static_cast<unsigned long long>(c.border_edges),
          static_cast<unsigned long long>(c.boundary_edges), seconds);
      printLevels(dagLevels(*view));
    }
    if (!report.ok()) {
      view.reset();
      progress.reset();
      exitFailed();
    }
  });
}

}  // namespace tw
