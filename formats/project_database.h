// The project database: one record per database key, in SQLite.
//
// Objects carry a database key (a plant tag such as "P-1203-A" or "12\"-HC-1001-A1"); review
// tools look the key up here to show the object's engineering record. The table is
// `records(db_key TEXT PRIMARY KEY, type, line_number, service, material, nominal_diameter_mm,
// design_pressure_bar, design_temperature_c, description)`; beside it, generic properties
// `properties(db_key, property_set, name, value, unit)`, several per key, for what importers know
// of an object (IFC property sets, STEP attributes); see docs/project-database.md.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace tw {

struct ProjectRecord {
  std::string db_key;
  std::string type;         // "pipe", "elbow", "valve", "vessel", "pump", "beam", ...
  std::string line_number;  // piping line number, empty for non-piping
  std::string service;      // process service ("hydrocarbon", "sea water", ...)
  std::string material;     // "CS A106-B", "SS 316L", ...
  double nominal_diameter_mm = 0.0;
  double design_pressure_bar = 0.0;
  double design_temperature_c = 0.0;
  std::string description;
};

struct ProjectProperty {
  std::string db_key;
  std::string set;    // the property set ("Pset_PipeSegmentCommon", "STEP attributes", ...)
  std::string name;
  std::string value;  // as text
  std::string unit;   // empty when the value has none
};

class ProjectDatabase {
 public:
  // Creates (truncating) or opens the database at `path`. Throws std::runtime_error naming the
  // file and SQLite's message on failure.
  static ProjectDatabase create(const std::filesystem::path& path);
  static ProjectDatabase open(const std::filesystem::path& path);  // read-only
  ~ProjectDatabase();
  ProjectDatabase(ProjectDatabase&&) noexcept;
  ProjectDatabase& operator=(ProjectDatabase&&) noexcept;

  // Inserts or replaces a record. Writes are batched in transactions; commit() ends the batch.
  void put(const ProjectRecord& record);
  void putProperty(const ProjectProperty& property);  // appended; same batching as put
  void commit();

  std::optional<ProjectRecord> find(const std::string& db_key) const;
  // The key's properties in the order they were put; none for a database without the table.
  std::vector<ProjectProperty> properties(const std::string& db_key) const;
  // The keys of the records matching `where`, an SQL condition over the columns of `records`
  // (the properties through subqueries on `properties` and `records.db_key`), with ?1, ?2, ...
  // bound to `parameters` as text, numbers where they read as one. One condition, not
  // statements: a query that fails to prepare, or holds more than one statement, throws
  // std::runtime_error with SQLite's message.
  std::vector<std::string> findKeys(const std::string& where,
                                    const std::vector<std::string>& parameters) const;
  uint64_t recordCount() const;

 private:
  struct State;
  explicit ProjectDatabase(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

}  // namespace tw
