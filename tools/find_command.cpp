// `terawalk find model.twk --db plant.db "QUERY"`: the objects of a package whose project-database
// record matches an SQL condition, e.g. `service = ?1 AND nominal_diameter_mm >= ?2` with
// `--param 'sea water' --param 150` (values bound, never pasted into the SQL), or by a substring
// of their names and keys (`--name`). Prints each object's index, name, layer and key, and the
// query's time; what `render --isolate-keys` and the viewer's search take.
#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <unordered_set>
#include <vector>

#include <nlohmann/json.hpp>

#include "command.h"
#include "object_queries.h"
#include "package_database.h"
#include "package_view.h"
#include "project_database.h"

namespace tw {
namespace {

struct FindArgs {
  std::string file;
  std::string db;
  std::string query;
  std::vector<std::string> params;
  std::string name;  // substring of the object's name or key
  bool json = false;
  bool keys_only = false;
};

void runFind(const FindArgs& args) {
  if (args.query.empty() && args.name.empty())
    throw std::runtime_error("give a QUERY over the database's records, or --name TEXT");
  const PackageView view = PackageView::open(args.file);
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::string> keys;
  std::vector<uint32_t> objects;
  if (!args.query.empty()) {
    const std::filesystem::path db_path = packageDatabasePath(args.file, view, args.db);
    if (db_path.empty())
      throw std::runtime_error(
          "a QUERY needs the project database: --db FILE (the package names none)");
    const ProjectDatabase db = ProjectDatabase::open(db_path);
    keys = db.findKeys(args.query, args.params);
    objects = objectsWithKeys(view, std::unordered_set<std::string>(keys.begin(), keys.end()));
  } else {
    objects = objectsNamed(view, args.name);
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (args.keys_only) {
    std::unordered_set<std::string> printed;
    for (uint32_t o : objects) {
      const std::string key(view.objectDbKey(o));
      if (!key.empty() && printed.insert(key).second) std::printf("%s\n", key.c_str());
    }
    return;
  }
  if (args.json) {
    nlohmann::json list = nlohmann::json::array();
    for (uint32_t o : objects)
      list.push_back({{"object", o},
                      {"name", std::string(view.objectName(o))},
                      {"layer", std::string(view.layerName(view.objects()[o].layer))},
                      {"db_key", std::string(view.objectDbKey(o))}});
    const nlohmann::json j = {{"records", keys.size()}, {"objects", list}, {"query_ms", ms}};
    std::printf("%s\n", j.dump(1).c_str());
    return;
  }
  for (uint32_t o : objects)
    std::printf("%u\t%s\t%s\t%s\n", o, std::string(view.objectName(o)).c_str(),
                std::string(view.layerName(view.objects()[o].layer)).c_str(),
                std::string(view.objectDbKey(o)).c_str());
  std::fprintf(stderr, "find: %zu objects%s in %.1f ms\n", objects.size(),
               args.query.empty() ? "" : (" of " + std::to_string(keys.size()) + " records").c_str(),
               ms);
}

}  // namespace

void registerFindCommand(CLI::App& app, const GlobalOptions&) {
  auto args = std::make_shared<FindArgs>();
  CLI::App* cmd = app.add_subcommand(
      "find", "Objects whose database record matches a query, or whose name or key holds a text");
  cmd->add_option("file", args->file, "Package (.twk)")->required()->check(CLI::ExistingFile);
  cmd->add_option("query", args->query,
                  "SQL condition over the records' columns, e.g. \"service = ?1 AND "
                  "nominal_diameter_mm >= ?2\"");
  cmd->add_option("--db", args->db, "Project database (SQLite); default: the one the package names")
      ->check(CLI::ExistingFile);
  cmd->add_option("--param", args->params, "Value bound to ?1, ?2, ... in order (repeatable)")
      ->allow_extra_args(false);
  cmd->add_option("--name", args->name, "Objects whose name or database key contains this text");
  cmd->add_flag("--json", args->json, "Print JSON");
  cmd->add_flag("--keys", args->keys_only, "Print the matching objects' distinct keys, one a line");
  cmd->callback([args] { runFind(*args); });
}

}  // namespace tw
