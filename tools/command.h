// How the `terawalk` verbs plug into the one executable.
//
// Each verb lives in its own <verb>_command.cpp and registers a CLI11 subcommand. Callbacks
// throw on failure; main() turns any exception into a one-line error and exit code 1.
#pragma once

#include <memory>

#include <CLI/CLI.hpp>

#include "progress.h"

namespace tw {

struct GlobalOptions {
  bool quiet = false;  // no progress output at all
};

// A progress reporter for the command line: a bar with an ETA on a terminal, plain lines when
// stderr is not a terminal, nothing with --quiet. Never nullptr.
std::unique_ptr<Progress> makeCommandProgress(const GlobalOptions& global);

void registerGenCommand(CLI::App& app, const GlobalOptions& global);
void registerInfoCommand(CLI::App& app, const GlobalOptions& global);
void registerPreprocessCommand(CLI::App& app, const GlobalOptions& global);
void registerSnapshotCommand(CLI::App& app, const GlobalOptions& global);
void registerVerifyCommand(CLI::App& app, const GlobalOptions& global);
void registerRenderCommand(CLI::App& app, const GlobalOptions& global);
void registerViewCommand(CLI::App& app, const GlobalOptions& global);
void registerCompareCommand(CLI::App& app, const GlobalOptions& global);
void registerBenchCommand(CLI::App& app, const GlobalOptions& global);
void registerPickCommand(CLI::App& app, const GlobalOptions& global);
void registerFindCommand(CLI::App& app, const GlobalOptions& global);
void registerMeasureCommand(CLI::App& app, const GlobalOptions& global);
void registerBcfCommand(CLI::App& app, const GlobalOptions& global);
void registerChangesCommand(CLI::App& app, const GlobalOptions& global);
void registerPathCommand(CLI::App& app, const GlobalOptions& global);

}  // namespace tw
