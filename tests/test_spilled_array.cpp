// The spilled array gives back what was appended, in memory or past its limit from its file,
// read in order and at random while it still grows, and leaves no file behind.
#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include <glm/glm.hpp>

#include "spilled_array.h"
#include "test_support.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

size_t filesIn(const fs::path& dir) {
  size_t n = 0;
  for (const auto& entry : fs::directory_iterator(dir)) n += entry.is_regular_file();
  return n;
}

glm::vec3 valueFor(uint64_t i) { return {float(i), float(i) * 0.5f, -float(i % 1000)}; }

TEST(SpilledArray, StaysInMemoryWithoutALimit) {
  SpilledArray<glm::vec3> values;
  for (uint64_t i = 0; i < 100000; ++i) values.push_back(valueFor(i));
  EXPECT_FALSE(values.spilled());
  for (uint64_t i = 0; i < values.size(); i += 7) ASSERT_EQ(values[i], valueFor(i));
}

TEST(SpilledArray, PastItsLimitReadsBackFromAnUnlinkedFile) {
  const fs::path dir = test::scratchDir() / "spill";
  fs::create_directories(dir);
  const uint64_t count = 1000000;  // 12 MB against a 256 KB limit
  SpilledArray<glm::vec3> values(256 * 1024, dir);
  std::mt19937_64 rng(5);
  for (uint64_t i = 0; i < count; ++i) {
    values.push_back(valueFor(i));
    // Reads while it grows: the block being filled, the one before, anywhere.
    if (i % 1000 == 999) {
      ASSERT_EQ(values[i], valueFor(i));
      ASSERT_EQ(values[i - 999], valueFor(i - 999));
      const uint64_t j = rng() % (i + 1);
      ASSERT_EQ(values[j], valueFor(j)) << j;
    }
  }
  EXPECT_TRUE(values.spilled());
  EXPECT_GT(values.spilledBytes(), 10u * 1024 * 1024);
  EXPECT_EQ(filesIn(dir), 0u) << "the spill file is unlinked at once";
  for (uint64_t i = 0; i < count; i += 13) ASSERT_EQ(values[i], valueFor(i));
  for (int k = 0; k < 100000; ++k) {
    const uint64_t j = rng() % count;
    ASSERT_EQ(values[j], valueFor(j)) << j;
  }
}

TEST(SpilledArray, AMissingFolderIsMadeAndAnImpossibleOneIsAClearError) {
  const fs::path missing = test::scratchDir() / "made" / "on" / "demand";
  fs::remove_all(test::scratchDir() / "made");
  SpilledArray<uint32_t> made(1024, missing);
  for (uint32_t i = 0; i < 100000; ++i) made.push_back(i);
  EXPECT_TRUE(made.spilled());
  EXPECT_EQ(made[77777], 77777u);
  EXPECT_TRUE(fs::is_directory(missing));

  const fs::path file = test::scratchDir() / "a-file";
  test::writeFile(file, "not a folder");
  SpilledArray<uint32_t> values(1024, file / "folder");
  try {
    for (uint32_t i = 0; i < 100000; ++i) values.push_back(i);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("a-file/folder"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cannot create"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tw
