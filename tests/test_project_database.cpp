// Tests for the SQLite project database: round trips, batching, read-only reopen and errors.
#include <gtest/gtest.h>

#include <sqlite3.h>

#include <string>

#include "project_database.h"
#include "test_support.h"

namespace tw {
namespace {

ProjectRecord pumpRecord() {
  ProjectRecord r;
  r.db_key = "P-1203-A";
  r.type = "pump";
  r.service = "hydrocarbon";
  r.material = "SS 316L";
  r.nominal_diameter_mm = 150.0;
  r.design_pressure_bar = 40.5;
  r.design_temperature_c = 120.25;
  r.description = "crude transfer pump A";
  return r;
}

TEST(ProjectDatabase, PutFindAndCount) {
  auto path = test::scratchDir() / "plant.db";
  auto db = ProjectDatabase::create(path);
  EXPECT_EQ(db.recordCount(), 0u);
  db.put(pumpRecord());
  ProjectRecord line;
  line.db_key = "12\"-HC-1001-A1";  // keys contain quotes: binding must not break on them
  line.type = "pipe";
  line.line_number = "1001";
  line.service = "hydrocarbon";
  line.nominal_diameter_mm = 300.0;
  line.description = "it's a \"line\"; DROP TABLE records;";
  db.put(line);
  db.commit();
  EXPECT_EQ(db.recordCount(), 2u);

  auto found = db.find("P-1203-A");
  ASSERT_TRUE(found.has_value());
  EXPECT_EQ(found->type, "pump");
  EXPECT_EQ(found->material, "SS 316L");
  EXPECT_EQ(found->line_number, "");
  EXPECT_DOUBLE_EQ(found->nominal_diameter_mm, 150.0);
  EXPECT_DOUBLE_EQ(found->design_pressure_bar, 40.5);
  EXPECT_DOUBLE_EQ(found->design_temperature_c, 120.25);
  EXPECT_EQ(found->description, "crude transfer pump A");

  auto found_line = db.find("12\"-HC-1001-A1");
  ASSERT_TRUE(found_line.has_value());
  EXPECT_EQ(found_line->line_number, "1001");
  EXPECT_EQ(found_line->description, line.description);
  EXPECT_FALSE(db.find("P-9999-Z").has_value());
  EXPECT_FALSE(db.find("").has_value());
}

TEST(ProjectDatabase, PutReplacesSameKey) {
  auto db = ProjectDatabase::create(test::scratchDir() / "plant.db");
  ProjectRecord r = pumpRecord();
  db.put(r);
  r.description = "replaced";
  db.put(r);
  EXPECT_EQ(db.recordCount(), 1u);
  EXPECT_EQ(db.find("P-1203-A")->description, "replaced");
}

TEST(ProjectDatabase, ManyRowsSpanSeveralTransactionsAndReopenReadOnly) {
  auto path = test::scratchDir() / "many.db";
  constexpr int kRows = 25'000;  // more than two batches of 10,000
  {
    auto db = ProjectDatabase::create(path);
    ProjectRecord r;
    r.type = "beam";
    for (int i = 0; i < kRows; ++i) {
      r.db_key = "ST-" + std::to_string(i);
      r.design_pressure_bar = i;
      db.put(r);
    }
    db.commit();
    EXPECT_EQ(db.recordCount(), static_cast<uint64_t>(kRows));
  }
  auto db = ProjectDatabase::open(path);
  EXPECT_EQ(db.recordCount(), static_cast<uint64_t>(kRows));
  auto r = db.find("ST-24999");
  ASSERT_TRUE(r.has_value());
  EXPECT_DOUBLE_EQ(r->design_pressure_bar, 24999.0);
  // Read-only: writing must fail with an error naming the file.
  try {
    db.put(pumpRecord());
    db.commit();
    FAIL() << "put on a read-only database succeeded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("many.db"), std::string::npos) << e.what();
  }
}

TEST(ProjectDatabase, DestructorKeepsUncommittedRows) {
  auto path = test::scratchDir() / "forgot.db";
  {
    auto db = ProjectDatabase::create(path);
    db.put(pumpRecord());
  }
  EXPECT_EQ(ProjectDatabase::open(path).recordCount(), 1u);
}

TEST(ProjectDatabase, CreateReplacesExistingFile) {
  auto path = test::scratchDir() / "again.db";
  {
    auto db = ProjectDatabase::create(path);
    db.put(pumpRecord());
    db.commit();
  }
  auto db = ProjectDatabase::create(path);
  EXPECT_EQ(db.recordCount(), 0u);
  // Even a file that is not a database is replaced.
  test::writeFile(path, "not a database at all");
  auto db2 = ProjectDatabase::create(path);
  EXPECT_EQ(db2.recordCount(), 0u);
}

TEST(ProjectDatabase, MoveKeepsTheConnection) {
  auto db = ProjectDatabase::create(test::scratchDir() / "moved.db");
  db.put(pumpRecord());
  ProjectDatabase moved = std::move(db);
  moved.commit();
  EXPECT_EQ(moved.recordCount(), 1u);
}

TEST(ProjectDatabase, MissingFileIsAnErrorNamingIt) {
  auto path = test::scratchDir() / "missing.db";
  try {
    ProjectDatabase::open(path);
    FAIL() << "opening a missing database succeeded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.db"), std::string::npos) << e.what();
  }
}

TEST(ProjectDatabase, NotADatabaseIsAnError) {
  auto path = test::scratchDir() / "garbage.db";
  test::writeFile(path, std::string(4096, 'x'));
  EXPECT_THROW(ProjectDatabase::open(path), std::runtime_error);
}

TEST(ProjectDatabase, DatabaseWithoutRecordsTableIsAnError) {
  auto path = test::scratchDir() / "other.db";
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(path.string().c_str(), &raw), SQLITE_OK);
  sqlite3_exec(raw, "CREATE TABLE other(x)", nullptr, nullptr, nullptr);
  sqlite3_close(raw);
  try {
    ProjectDatabase::open(path);
    FAIL() << "opening a database without the records table succeeded";
  } catch (const std::runtime_error& e) {
    std::string what = e.what();
    EXPECT_NE(what.find("other.db"), std::string::npos) << what;
    EXPECT_NE(what.find("records"), std::string::npos) << what;
  }
}

// Generic properties: several per key, in the order put, values with quotes kept, read back
// read-only; a database from before the table has none.
TEST(ProjectDatabase, PropertiesOfAKeyComeBackInOrder) {
  const auto dir = test::scratchDir();
  auto path = dir / "props.db";
  {
    auto db = ProjectDatabase::create(path);
    db.put(pumpRecord());
    db.putProperty({"P-1203-A", "Pset_PumpTypeCommon", "FlowRate", "12.5", "m3/h"});
    db.putProperty({"P-1203-A", "Pset_PumpTypeCommon", "Note", "it's \"A\"; DROP TABLE x", ""});
    db.putProperty({"V-1204", "STEP attributes", "part", "vessel", ""});
    db.commit();
  }
  auto db = ProjectDatabase::open(path);
  const auto props = db.properties("P-1203-A");
  ASSERT_EQ(props.size(), 2u);
  EXPECT_EQ(props[0].set, "Pset_PumpTypeCommon");
  EXPECT_EQ(props[0].name, "FlowRate");
  EXPECT_EQ(props[0].value, "12.5");
  EXPECT_EQ(props[0].unit, "m3/h");
  EXPECT_EQ(props[1].value, "it's \"A\"; DROP TABLE x");
  EXPECT_EQ(db.properties("V-1204").size(), 1u);
  EXPECT_TRUE(db.properties("nothing").empty());
  EXPECT_THROW(db.putProperty({"k", "s", "n", "v", ""}), std::runtime_error);  // read-only

  auto old_path = dir / "old.db";
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(old_path.string().c_str(), &raw), SQLITE_OK);
  sqlite3_exec(raw,
               "CREATE TABLE records (db_key TEXT PRIMARY KEY, type TEXT, line_number TEXT, "
               "service TEXT, material TEXT, nominal_diameter_mm REAL, design_pressure_bar REAL, "
               "design_temperature_c REAL, description TEXT)",
               nullptr, nullptr, nullptr);
  sqlite3_close(raw);
  EXPECT_TRUE(ProjectDatabase::open(old_path).properties("P-1203-A").empty());
}

TEST(ProjectDatabase, UnwritableLocationIsAnError) {
  auto path = test::scratchDir() / "no-such-dir" / "plant.db";
  EXPECT_THROW(ProjectDatabase::create(path), std::runtime_error);
}

}  // namespace
}  // namespace tw
