// The project database of a command: --db, else the package's own; see package_database.h.
#include "package_database.h"

#include <cstdio>

namespace tw {

std::filesystem::path packageDatabasePath(const std::filesystem::path& package,
                                          const PackageView& view, const std::string& db_option) {
  if (!db_option.empty()) return db_option;
  const std::filesystem::path named(std::string(view.databasePath()));
  if (named.empty() || named.is_absolute()) return named;
  return package.parent_path() / named;
}

std::optional<ProjectDatabase> openPackageDatabase(const std::filesystem::path& package,
                                                   const PackageView& view,
                                                   const std::string& db_option) {
  const std::filesystem::path path = packageDatabasePath(package, view, db_option);
  if (path.empty()) return std::nullopt;
  if (db_option.empty() && !std::filesystem::exists(path)) {
    std::fprintf(stderr,
                 "%s: names the project database %s, which is not there; give it with --db\n",
                 package.string().c_str(), path.string().c_str());
    return std::nullopt;
  }
  return ProjectDatabase::open(path);
}

}  // namespace tw
