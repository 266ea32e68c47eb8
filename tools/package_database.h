// Which project database a command reads: the one given with --db, else the one the package
// names (`preprocess --db`, stored relative to the package's folder; docs/project-database.md).
// Commands that can work without it (pick, view) go on without one, saying why on stderr, when
// the named file is gone.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "package_view.h"
#include "project_database.h"

namespace tw {

// The path to open: `db_option` when given, else the package's own, resolved against the
// package's folder; empty when neither names one.
std::filesystem::path packageDatabasePath(const std::filesystem::path& package,
                                          const PackageView& view, const std::string& db_option);

// The database opened, or nullopt when none is named or the one the package names is missing
// (a line on stderr says so). A given --db that cannot be opened throws, as ProjectDatabase::open.
std::optional<ProjectDatabase> openPackageDatabase(const std::filesystem::path& package,
                                                   const PackageView& view,
                                                   const std::string& db_option);

}  // namespace tw
