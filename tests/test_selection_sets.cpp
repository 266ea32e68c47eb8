// The selection-sets file (runtime/selection_sets.h): what is written reads back, a missing file
// is no sets, and a damaged one is refused with the file and the reason.
#include <gtest/gtest.h>

#include <string>

#include "selection_sets.h"
#include "test_support.h"

namespace tw {
namespace {

TEST(SelectionSets, WrittenSetsReadBack) {
  const auto dir = test::scratchDir();
  EXPECT_EQ(selectionSetsPathFor(dir / "plant.twk"), dir / "plant.sets.json");
  const auto file = dir / "plant.sets.json";
  EXPECT_TRUE(readSelectionSets(file).empty()) << "no file: no sets";
  SelectionSet selection{"fire valves", SelectionSet::Kind::Selection, {812, 813}, {}, {}};
  SelectionSet visibility{"no hull", SelectionSet::Kind::Visibility, {}, {1, 2}, {7}};
  writeSelectionSets(file, {selection, visibility});
  const std::vector<SelectionSet> back = readSelectionSets(file);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].name, "fire valves");
  EXPECT_EQ(back[0].kind, SelectionSet::Kind::Selection);
  EXPECT_EQ(back[0].selected, (std::vector<uint32_t>{812, 813}));
  EXPECT_EQ(back[1].kind, SelectionSet::Kind::Visibility);
  EXPECT_EQ(back[1].hidden, (std::vector<uint32_t>{1, 2}));
  EXPECT_EQ(back[1].xray, (std::vector<uint32_t>{7}));
  EXPECT_FALSE(std::filesystem::exists(file.string() + ".tmp"));
}

TEST(SelectionSets, DamagedFilesAreRefusedWithTheReason) {
  const auto dir = test::scratchDir();
  const auto file = dir / "plant.sets.json";
  writeSelectionSets(file, {{"a", SelectionSet::Kind::Selection, {1, 2, 3}, {}, {}}});
  const std::string good = test::readFile(file);
  struct Case {
    std::string text, reason;
  };
  const Case cases[] = {
      {good.substr(0, good.size() / 2), "not JSON"},
      {"[1, 2]", "not a TeraWalk selection sets file"},
      {R"({"terawalk_selection_sets": 2, "sets": []})", "not a TeraWalk selection sets file"},
      {R"({"terawalk_selection_sets": 1})", "'sets' is missing"},
      {R"({"terawalk_selection_sets": 1, "sets": [{"kind": "selection"}]})", "set 1: no name"},
      {R"({"terawalk_selection_sets": 1, "sets": [{"name": "a", "kind": "colour"}]})",
       "kind 'colour'"},
      {R"({"terawalk_selection_sets": 1, "sets": [{"name": "a", "kind": "selection",
           "selected": [1, -2]}]})",
       "'selected' holds -2"},
      {R"({"terawalk_selection_sets": 1, "sets": [{"name": "a", "kind": "visibility",
           "hidden": 5}]})",
       "'hidden' is not a list"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    test::writeFile(file, c.text);
    try {
      readSelectionSets(file);
      ADD_FAILURE() << "accepted";
    } catch (const std::runtime_error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(file.string()), std::string::npos) << message;
      EXPECT_NE(message.find(c.reason), std::string::npos) << message;
    }
  }
}

}  // namespace
}  // namespace tw
