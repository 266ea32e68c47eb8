// The SQLite-backed project database: one `records` row per database key.
//
// Writes go through one prepared INSERT OR REPLACE statement inside transactions of
// kRowsPerTransaction rows, because SQLite commits per statement otherwise (thousands of fsyncs).
// A database made by create() is scratch output of the generator or an importer, so durability
// is traded for speed (journal off, no syncs); open() is read-only.
#include "project_database.h"

#include <sqlite3.h>

#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <system_error>

namespace tw {
namespace {

constexpr uint64_t kRowsPerTransaction = 10'000;

constexpr const char* kCreateSql =
    "CREATE TABLE records ("
    "db_key TEXT PRIMARY KEY, type TEXT, line_number TEXT, service TEXT, material TEXT, "
    "nominal_diameter_mm REAL, design_pressure_bar REAL, design_temperature_c REAL, "
    "description TEXT)";
constexpr const char* kInsertSql =
    "INSERT OR REPLACE INTO records (db_key, type, line_number, service, material, "
    "nominal_diameter_mm, design_pressure_bar, design_temperature_c, description) "
    "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)";
constexpr const char* kFindSql =
    "SELECT db_key, type, line_number, service, material, nominal_diameter_mm, "
    "design_pressure_bar, design_temperature_c, description FROM records WHERE db_key = ?1";
constexpr const char* kCountSql = "SELECT COUNT(*) FROM records";
// Generic properties beside the records: what importers know of an object (IFC property sets,
// STEP attributes) without a schema of their own. Several rows per key.
constexpr const char* kCreatePropertiesSql =
    "CREATE TABLE properties (db_key TEXT NOT NULL, property_set TEXT NOT NULL, "
    "name TEXT NOT NULL, value TEXT, unit TEXT);"
    "CREATE INDEX properties_by_key ON properties (db_key)";
constexpr const char* kInsertPropertySql =
    "INSERT INTO properties (db_key, property_set, name, value, unit) VALUES (?1, ?2, ?3, ?4, ?5)";
constexpr const char* kPropertiesSql =
    "SELECT db_key, property_set, name, value, unit FROM properties WHERE db_key = ?1 "
    "ORDER BY rowid";

std::string columnText(sqlite3_stmt* stmt, int column) {
  const unsigned char* text = sqlite3_column_text(stmt, column);
  if (!text) return {};
  return std::string(reinterpret_cast<const char*>(text),
                     static_cast<size_t>(sqlite3_column_bytes(stmt, column)));
}

}  // namespace

struct ProjectDatabase::State {
  std::string path;
  sqlite3* db = nullptr;
  sqlite3_stmt* insert = nullptr;
  sqlite3_stmt* find = nullptr;
  sqlite3_stmt* count = nullptr;
  sqlite3_stmt* insert_property = nullptr;
  sqlite3_stmt* properties = nullptr;  // null for a database made before the table existed
  bool in_transaction = false;
  uint64_t pending_rows = 0;

  ~State() {
    // A destructor cannot report errors: an open batch is committed on a best-effort basis so
    // that a caller who forgot commit() still gets its rows.
    if (in_transaction && db) sqlite3_exec(db, "COMMIT", nullptr, nullptr, nullptr);
    sqlite3_finalize(insert);
    sqlite3_finalize(find);
    sqlite3_finalize(count);
    sqlite3_finalize(insert_property);
    sqlite3_finalize(properties);
    sqlite3_close(db);
  }

  [[noreturn]] void fail(const std::string& what) const {
    std::string message = path + ": " + what;
    if (db) message += ": " + std::string(sqlite3_errmsg(db));
    throw std::runtime_error(message);
  }
  void check(int rc, const char* what) const {
    if (rc != SQLITE_OK && rc != SQLITE_DONE && rc != SQLITE_ROW) fail(what);
  }
  void exec(const char* sql) { check(sqlite3_exec(db, sql, nullptr, nullptr, nullptr), sql); }
  sqlite3_stmt* prepare(const char* sql) {
    sqlite3_stmt* stmt = nullptr;
    check(sqlite3_prepare_v2(db, sql, -1, &stmt, nullptr), "cannot prepare statement");
    return stmt;
  }
  void beginBatch() {
    if (in_transaction) return;
    exec("BEGIN");
    in_transaction = true;
  }
  void bindText(sqlite3_stmt* stmt, int index, const std::string& value) const {
    check(sqlite3_bind_text(stmt, index, value.data(), static_cast<int>(value.size()),
                            SQLITE_TRANSIENT),
          "cannot bind value");
  }
};

ProjectDatabase::ProjectDatabase(std::unique_ptr<State> state) : state_(std::move(state)) {}
ProjectDatabase::~ProjectDatabase() = default;
ProjectDatabase::ProjectDatabase(ProjectDatabase&&) noexcept = default;
ProjectDatabase& ProjectDatabase::operator=(ProjectDatabase&&) noexcept = default;

ProjectDatabase ProjectDatabase::create(const std::filesystem::path& path) {
  auto state = std::make_unique<State>();
  state->path = path.string();
  std::error_code ec;
  std::filesystem::remove(path, ec);
  if (ec) throw std::runtime_error(state->path + ": cannot remove existing file: " + ec.message());
  int rc = sqlite3_open_v2(state->path.c_str(), &state->db,
                           SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr);
  if (rc != SQLITE_OK) state->fail("cannot create database");
  state->exec("PRAGMA journal_mode=OFF");
  state->exec("PRAGMA synchronous=OFF");
  state->exec(kCreateSql);
  state->exec(kCreatePropertiesSql);
  state->insert = state->prepare(kInsertSql);
  state->insert_property = state->prepare(kInsertPropertySql);
  state->properties = state->prepare(kPropertiesSql);
  state->find = state->prepare(kFindSql);
  state->count = state->prepare(kCountSql);
  return ProjectDatabase(std::move(state));
}

ProjectDatabase ProjectDatabase::open(const std::filesystem::path& path) {
  auto state = std::make_unique<State>();
  state->path = path.string();
  int rc = sqlite3_open_v2(state->path.c_str(), &state->db, SQLITE_OPEN_READONLY, nullptr);
  if (rc != SQLITE_OK) state->fail("cannot open database");
  // Opening is lazy in SQLite: preparing against the table is what proves the file is a
  // database holding our schema.
  state->find = state->prepare(kFindSql);
  state->count = state->prepare(kCountSql);
  // Databases made before the property table have none: no properties, not an error.
  if (sqlite3_prepare_v2(state->db, kPropertiesSql, -1, &state->properties, nullptr) != SQLITE_OK)
    state->properties = nullptr;
  return ProjectDatabase(std::move(state));
}

void ProjectDatabase::put(const ProjectRecord& record) {
  State& s = *state_;
  if (!s.insert) s.fail("database is read-only");
  s.beginBatch();
  sqlite3_stmt* stmt = s.insert;
  auto text = [&](int index, const std::string& value) { s.bindText(stmt, index, value); };
  text(1, record.db_key);
  text(2, record.type);
  text(3, record.line_number);
  text(4, record.service);
  text(5, record.material);
  s.check(sqlite3_bind_double(stmt, 6, record.nominal_diameter_mm), "cannot bind value");
  s.check(sqlite3_bind_double(stmt, 7, record.design_pressure_bar), "cannot bind value");
  s.check(sqlite3_bind_double(stmt, 8, record.design_temperature_c), "cannot bind value");
  text(9, record.description);
  int rc = sqlite3_step(stmt);
  sqlite3_reset(stmt);
  if (rc != SQLITE_DONE) s.fail("cannot insert record '" + record.db_key + "'");
  if (++s.pending_rows >= kRowsPerTransaction) commit();
}

void ProjectDatabase::putProperty(const ProjectProperty& property) {
  State& s = *state_;
  if (!s.insert_property) s.fail("database is read-only");
  s.beginBatch();
  sqlite3_stmt* stmt = s.insert_property;
  s.bindText(stmt, 1, property.db_key);
  s.bindText(stmt, 2, property.set);
  s.bindText(stmt, 3, property.name);
  s.bindText(stmt, 4, property.value);
  s.bindText(stmt, 5, property.unit);
  int rc = sqlite3_step(stmt);
  sqlite3_reset(stmt);
  if (rc != SQLITE_DONE) s.fail("cannot insert a property of '" + property.db_key + "'");
  if (++s.pending_rows >= kRowsPerTransaction) commit();
}

std::vector<ProjectProperty> ProjectDatabase::properties(const std::string& db_key) const {
  State& s = *state_;
  std::vector<ProjectProperty> out;
  if (!s.properties) return out;
  sqlite3_stmt* stmt = s.properties;
  s.bindText(stmt, 1, db_key);
  int rc;
  while ((rc = sqlite3_step(stmt)) == SQLITE_ROW)
    out.push_back({columnText(stmt, 0), columnText(stmt, 1), columnText(stmt, 2),
                   columnText(stmt, 3), columnText(stmt, 4)});
  sqlite3_reset(stmt);
  sqlite3_clear_bindings(stmt);
  if (rc != SQLITE_DONE) s.fail("cannot read the properties of '" + db_key + "'");
  return out;
}

std::vector<std::string> ProjectDatabase::findKeys(const std::string& where,
                                                   const std::vector<std::string>& parameters) const {
  State& s = *state_;
  const std::string sql = "SELECT db_key FROM records WHERE (" + where + ") ORDER BY db_key";
  sqlite3_stmt* stmt = nullptr;
  const char* tail = nullptr;
  if (sqlite3_prepare_v2(s.db, sql.c_str(), -1, &stmt, &tail) != SQLITE_OK)
    s.fail("bad query \"" + where + "\"");
  std::unique_ptr<sqlite3_stmt, int (*)(sqlite3_stmt*)> owned(stmt, sqlite3_finalize);
  if (tail && std::string(tail).find_first_not_of(" \t\r\n;") != std::string::npos)
    throw std::runtime_error(s.path + ": bad query \"" + where + "\": one condition, not statements");
  if (int(parameters.size()) != sqlite3_bind_parameter_count(stmt))
    throw std::runtime_error(s.path + ": the query has " +
                             std::to_string(sqlite3_bind_parameter_count(stmt)) +
                             " parameters, " + std::to_string(parameters.size()) + " given");
  for (size_t i = 0; i < parameters.size(); ++i) {
    const std::string& p = parameters[i];
    char* end = nullptr;
    const double number = std::strtod(p.c_str(), &end);
    if (!p.empty() && end == p.c_str() + p.size())
      s.check(sqlite3_bind_double(stmt, int(i) + 1, number), "cannot bind value");
    else
      s.bindText(stmt, int(i) + 1, p);
  }
  std::vector<std::string> keys;
  int rc;
  while ((rc = sqlite3_step(stmt)) == SQLITE_ROW) keys.push_back(columnText(stmt, 0));
  if (rc != SQLITE_DONE) s.fail("query \"" + where + "\" failed");
  return keys;
}

void ProjectDatabase::commit() {
  State& s = *state_;
  if (!s.in_transaction) return;
  s.in_transaction = false;
  s.pending_rows = 0;
  s.exec("COMMIT");
}

std::optional<ProjectRecord> ProjectDatabase::find(const std::string& db_key) const {
  State& s = *state_;
  sqlite3_stmt* stmt = s.find;
  s.bindText(stmt, 1, db_key);
  int rc = sqlite3_step(stmt);
  std::optional<ProjectRecord> result;
  if (rc == SQLITE_ROW) {
    ProjectRecord r;
    r.db_key = columnText(stmt, 0);
    r.type = columnText(stmt, 1);
    r.line_number = columnText(stmt, 2);
    r.service = columnText(stmt, 3);
    r.material = columnText(stmt, 4);
    r.nominal_diameter_mm = sqlite3_column_double(stmt, 5);
    r.design_pressure_bar = sqlite3_column_double(stmt, 6);
    r.design_temperature_c = sqlite3_column_double(stmt, 7);
    r.description = columnText(stmt, 8);
    result = std::move(r);
  }
  sqlite3_reset(stmt);
  sqlite3_clear_bindings(stmt);
  if (rc != SQLITE_ROW && rc != SQLITE_DONE) s.fail("cannot look up '" + db_key + "'");
  return result;
}

uint64_t ProjectDatabase::recordCount() const {
  State& s = *state_;
  int rc = sqlite3_step(s.count);
  int64_t n = rc == SQLITE_ROW ? sqlite3_column_int64(s.count, 0) : 0;
  sqlite3_reset(s.count);
  if (rc != SQLITE_ROW) s.fail("cannot count records");
  return static_cast<uint64_t>(n);
}

}  // namespace tw
