// Tests for addParametricClustersOutOfCore: it must write exactly the records the in-memory
// clustering writes (instances, profile points, clusters, byte for byte) whatever the budget, keep
// within the budget, clean its work directory, and reject damaged run files with a FormatError.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "covered_box_faces.h"
#include "parametrics/parametric_external_sort.h"
#include "test_support.h"

namespace {

using tw::ParametricItem;
using tw::PackageStorage;

const glm::dvec3 kOrigin(500000.0, 6000000.0, 12.0);

struct ItemShape {
  uint32_t min_profile_points = 3;
  uint32_t max_profile_points = 12;
  uint32_t profile_percent = 28;  // share of extrusions and revolutions
  uint32_t duplicate_percent = 10;  // exact copies of an earlier item (equal Morton keys)
};

// Deterministic items of every primitive type around kOrigin, rotated and scaled.
std::vector<ParametricItem> makeItems(size_t count, uint32_t seed, const ItemShape& shape = {}) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<ParametricItem> items;
  items.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    if (!items.empty() && rng() % 100 < shape.duplicate_percent) {
      ParametricItem copy = items[rng() % items.size()];
      copy.object = uint32_t(i % 97);  // same key, different record: tie order is visible
      items.push_back(copy);
      continue;
    }
    ParametricItem it;
    it.object = uint32_t(i % 97);
    it.transform.origin = kOrigin + glm::dvec3(2000.0 * u(rng) - 1000.0, 2000.0 * u(rng) - 1000.0,
                                               100.0 * u(rng));
    const float angle = float(6.28 * u(rng)), scale = float(0.5 + u(rng));
    it.transform.linear = glm::mat3(scale * std::cos(angle), scale * std::sin(angle), 0.0f,
                                    -scale * std::sin(angle), scale * std::cos(angle), 0.0f, 0.0f,
                                    0.0f, scale);
    const float r = float(0.05 + 2.0 * u(rng));
    if (rng() % 100 < shape.profile_percent) {
      const uint32_t points =
          shape.min_profile_points +
          uint32_t(rng() % (shape.max_profile_points - shape.min_profile_points + 1));
      std::vector<glm::vec2> profile;
      if (rng() % 2) {
        for (uint32_t k = 0; k < points; ++k) {
          const float a = 6.2831853f * float(k) / float(points);
          profile.push_back({r * std::cos(a), r * std::sin(a)});
        }
        it.primitive = tw::Extrusion{profile, 3.0f * r};
      } else {
        for (uint32_t k = 0; k < points; ++k)
          profile.push_back({r * float(u(rng)), r * float(k) / float(points)});
        it.primitive = tw::Revolution{profile, float(6.28 * u(rng))};
      }
    } else {
      switch (rng() % 5) {
        case 0: it.primitive = tw::Cylinder{r, 4.0f * r, rng() % 2 == 0}; break;
        case 1: it.primitive = tw::Cone{r, 0.5f * r, 2.0f * r, rng() % 2 == 0}; break;
        case 2: it.primitive = tw::Sphere{r}; break;
        case 3: it.primitive = tw::TorusSegment{3.0f * r, 0.5f * r, 1.57f}; break;
        default: it.primitive = tw::Box{glm::vec3(r, 0.5f * r, 2.0f * r)}; break;
      }
    }
    items.push_back(std::move(it));
  }
  return items;
}

// Gives `items` in batches of `batch`; counts its calls.
tw::ParametricStream streamOf(const std::vector<ParametricItem>& items, size_t batch = 97,
                              int* calls = nullptr) {
  return [&items, batch, calls](const auto& sink) {
    if (calls) ++*calls;
    for (size_t i = 0; i < items.size(); i += batch)
      sink(std::span<const ParametricItem>(items.data() + i, std::min(batch, items.size() - i)));
  };
}

PackageStorage reference(const std::vector<ParametricItem>& items, uint32_t max_per_cluster,
                         std::span<const uint16_t> role_flags = {}) {
  PackageStorage storage;
  storage.origin = kOrigin;
  tw::addParametricClusters(items, tw::clusterPrimitives(items, kOrigin, max_per_cluster),
                            storage, role_flags);
  return storage;
}

template <typename T>
bool sameBytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(),
                                                           a.size() * sizeof(T)) == 0);
}

void expectSameRecords(const PackageStorage& expected, const PackageStorage& got) {
  EXPECT_EQ(expected.instances.size(), got.instances.size());
  EXPECT_TRUE(sameBytes(expected.instances, got.instances)) << "instance records differ";
  EXPECT_EQ(expected.profile_points.size(), got.profile_points.size());
  EXPECT_TRUE(sameBytes(expected.profile_points, got.profile_points)) << "profile points differ";
  EXPECT_EQ(expected.clusters.size(), got.clusters.size());
  EXPECT_TRUE(sameBytes(expected.clusters, got.clusters)) << "cluster records differ";
}

size_t filesIn(const std::filesystem::path& dir) {
  std::error_code ec;
  if (!std::filesystem::exists(dir, ec)) return 0;
  return size_t(std::distance(std::filesystem::directory_iterator(dir),
                              std::filesystem::directory_iterator()));
}

struct Outcome {
  PackageStorage storage;
  tw::ParametricSortStats stats;
};

Outcome sortOutOfCore(const std::vector<ParametricItem>& items, uint64_t budget,
                      uint32_t max_per_cluster, const std::filesystem::path& work_dir,
                      std::span<const uint16_t> role_flags = {}) {
  Outcome out;
  out.storage.origin = kOrigin;
  tw::ParametricSortOptions options;
  options.work_dir = work_dir;
  options.memory_budget_bytes = budget;
  options.max_per_cluster = max_per_cluster;
  options.instance_role_flags = role_flags;
  int calls = 0;
  out.stats = tw::addParametricClustersOutOfCore(streamOf(items, 97, &calls), options, out.storage);
  EXPECT_EQ(calls, 2);
  return out;
}

constexpr uint64_t kMiB = 1ull << 20;

// Items with large profiles: a few thousand of them fill tens of 1 MiB runs.
const ItemShape kHeavyProfiles{1000, 3000, 50, 10};

TEST(ParametricExternalSort, EveryTypeInMemoryMatches) {
  const auto items = makeItems(4000, 1);
  const auto work = tw::test::scratchDir() / "work";
  const Outcome got = sortOutOfCore(items, 64 * kMiB, 256, work);
  expectSameRecords(reference(items, 256), got.storage);
  EXPECT_EQ(got.stats.items, items.size());
  EXPECT_EQ(got.stats.clusters, got.storage.clusters.size());
  EXPECT_EQ(got.stats.runs, 0u);  // it fits: no run file at all
  EXPECT_EQ(got.stats.run_bytes, 0u);
  EXPECT_EQ(got.stats.merges, 0u);
  EXPECT_LE(got.stats.peak_held_bytes, 64 * kMiB);
  EXPECT_FALSE(std::filesystem::exists(work));  // not even created
  // Every type is present, so the comparison covers each record layout.
  std::vector<int> types(7, 0);
  for (const auto& in : got.storage.instances) ++types.at(in.type);
  for (int t = 0; t < 7; ++t) EXPECT_GT(types[t], 0) << "type " << t;
}

TEST(ParametricExternalSort, SmallItemsInSeveralRunsMatch) {
  ItemShape shape;
  shape.profile_percent = 10;
  const auto items = makeItems(40000, 2, shape);
  const auto work = tw::test::scratchDir() / "work";
  for (uint32_t max_per_cluster : {1u, 7u, 256u}) {
    SCOPED_TRACE("max_per_cluster " + std::to_string(max_per_cluster));
    const Outcome got = sortOutOfCore(items, kMiB, max_per_cluster, work);
    expectSameRecords(reference(items, max_per_cluster), got.storage);
    EXPECT_GE(got.stats.runs, 3u);
    EXPECT_EQ(got.stats.merges, 1u);
    EXPECT_GT(got.stats.run_bytes, 3 * kMiB);
    EXPECT_LE(got.stats.peak_held_bytes, kMiB);
    EXPECT_EQ(filesIn(work), 0u);
  }
}

TEST(ParametricExternalSort, ProfilesForceManyRunsAndSeveralMerges) {
  const auto items = makeItems(3000, 3, kHeavyProfiles);
  const auto work = tw::test::scratchDir() / "work";
  for (uint32_t max_per_cluster : {1u, 7u}) {
    SCOPED_TRACE("max_per_cluster " + std::to_string(max_per_cluster));
    const Outcome got = sortOutOfCore(items, kMiB, max_per_cluster, work);
    expectSameRecords(reference(items, max_per_cluster), got.storage);
    EXPECT_GE(got.stats.runs, 20u);   // ~24 MB of profiles in 1 MiB runs
    EXPECT_GE(got.stats.merges, 2u);  // more runs than 1 MiB of read buffers can take at once
    EXPECT_LE(got.stats.peak_held_bytes, kMiB);  // profiles are counted
    EXPECT_EQ(got.stats.clusters, got.storage.clusters.size());
    EXPECT_EQ(filesIn(work), 0u);
  }
}

// Role flags (sealed runs, covered box faces) are given by input index and must reach each
// item's own record, in memory and through run files alike; a list of the wrong length is refused.
TEST(ParametricExternalSort, RoleFlagsFollowTheirItems) {
  const auto items = makeItems(20000, 5);
  std::vector<uint16_t> flags(items.size());
  std::mt19937 rng(9);
  const uint16_t choices[] = {0, tw::pkg::kInstanceSealedRunMember, tw::pkg::kInstanceSealedRunCloser,
                              tw::pkg::kInstanceSealedRunMember | tw::pkg::kInstanceSealedRunCloser};
  int boxes = 0;
  for (size_t i = 0; i < items.size(); ++i) {
    flags[i] = choices[rng() % 4];
    if (std::holds_alternative<tw::Box>(items[i].primitive)) {
      flags[i] |= uint16_t(tw::coveredFaceInstanceFlags(uint8_t(rng() % 64)));
      ++boxes;
    }
  }
  EXPECT_GT(boxes, 100);
  const PackageStorage expected = reference(items, 64, flags);
  // Against the items' own flags: records keep each item's object, so count by object.
  std::map<uint32_t, std::pair<int, int>> by_object;  // object -> (flags given, flags stored)
  auto weight = [](uint32_t f) {  // members, and covered faces apart from them
    return int((f & tw::pkg::kInstanceSealedRunMember) != 0) +
           1000 * int(tw::coveredFaces(f));
  };
  for (size_t i = 0; i < items.size(); ++i) by_object[items[i].object].first += weight(flags[i]);
  for (const tw::pkg::InstanceRecord& in : expected.instances)
    by_object[in.object].second += weight(in.flags);
  for (const auto& [object, counts] : by_object) EXPECT_EQ(counts.first, counts.second) << object;
  const auto work = tw::test::scratchDir() / "work";
  for (uint64_t budget : {64 * kMiB, kMiB}) {
    SCOPED_TRACE("budget " + std::to_string(budget));
    const Outcome got = sortOutOfCore(items, budget, 64, work, flags);
    expectSameRecords(expected, got.storage);
    if (budget == kMiB) {
      EXPECT_GE(got.stats.runs, 2u);
    }
  }
  const std::vector<uint16_t> short_list(items.size() - 1, 0);
  PackageStorage storage;
  storage.origin = kOrigin;
  tw::ParametricSortOptions options;
  options.work_dir = work;
  options.instance_role_flags = short_list;
  EXPECT_THROW(tw::addParametricClustersOutOfCore(streamOf(items, 97, nullptr), options, storage),
               std::invalid_argument);
  EXPECT_THROW(reference(items, 64, short_list), std::invalid_argument);
}

TEST(ParametricExternalSort, EqualKeysKeepInputOrderAcrossRuns) {
  // Identical extrusions at one place (one Morton key) and identical spheres at another,
  // interleaved, told apart only by their object: the order must be the input order, also when
  // the ties are spread over several runs.
  std::vector<ParametricItem> items;
  std::vector<glm::vec2> profile;
  for (int k = 0; k < 1500; ++k) {
    const float a = 6.2831853f * float(k) / 1500.0f;
    profile.push_back({std::cos(a), std::sin(a)});
  }
  for (uint32_t i = 0; i < 1200; ++i) {
    ParametricItem it;
    it.object = i;
    if (i % 3 == 0) {
      it.primitive = tw::Sphere{0.5f};
      it.transform.origin = kOrigin + glm::dvec3(10.0, 0.0, 0.0);
    } else {
      it.primitive = tw::Extrusion{profile, 2.0f};
      it.transform.origin = kOrigin;
    }
    items.push_back(std::move(it));
  }
  const auto work = tw::test::scratchDir() / "work";
  for (uint64_t budget : {kMiB, 64 * kMiB}) {
    SCOPED_TRACE("budget " + std::to_string(budget));
    const Outcome got = sortOutOfCore(items, budget, 7, work);
    expectSameRecords(reference(items, 7), got.storage);
    EXPECT_EQ(got.stats.runs > 0, budget == kMiB);
    // Within a type, objects come out in input order.
    for (size_t i = 1; i < got.storage.instances.size(); ++i) {
      if (got.storage.instances[i].type == got.storage.instances[i - 1].type) {
        EXPECT_LT(got.storage.instances[i - 1].object, got.storage.instances[i].object);
      }
    }
  }
}

TEST(ParametricExternalSort, EmptyStream) {
  const std::vector<ParametricItem> none;
  const auto work = tw::test::scratchDir() / "work";
  const Outcome got = sortOutOfCore(none, kMiB, 8, work);
  EXPECT_EQ(got.stats.items, 0u);
  EXPECT_EQ(got.stats.clusters, 0u);
  EXPECT_EQ(got.stats.runs, 0u);
  EXPECT_TRUE(got.storage.instances.empty());
  EXPECT_TRUE(got.storage.clusters.empty());
  EXPECT_EQ(filesIn(work), 0u);
}

TEST(ParametricExternalSort, BadParametersThrowAndAddNothing) {
  const auto items = makeItems(50, 4);
  const auto work = tw::test::scratchDir() / "work";
  PackageStorage storage;
  storage.origin = kOrigin;
  tw::ParametricSortOptions options;
  options.work_dir = work;
  options.max_per_cluster = 0;
  EXPECT_THROW(tw::addParametricClustersOutOfCore(streamOf(items), options, storage),
               std::invalid_argument);
  options.max_per_cluster = 8;
  options.memory_budget_bytes = kMiB - 1;
  EXPECT_THROW(tw::addParametricClustersOutOfCore(streamOf(items), options, storage),
               std::invalid_argument);
  options.memory_budget_bytes = kMiB;
  options.work_dir.clear();
  EXPECT_THROW(tw::addParametricClustersOutOfCore(streamOf(items), options, storage),
               std::invalid_argument);
  options.work_dir = work;

  // A forbidden parameter late in the stream: the same error as clusterPrimitives, nothing added.
  auto bad = items;
  bad[40].primitive = tw::Cylinder{-1.0f, 1.0f, true};
  std::string expected;
  try {
    tw::clusterPrimitives(bad, kOrigin, 8);
  } catch (const std::invalid_argument& e) {
    expected = e.what();
  }
  ASSERT_FALSE(expected.empty());
  try {
    tw::addParametricClustersOutOfCore(streamOf(bad), options, storage);
    ADD_FAILURE() << "a negative radius was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), expected);
  }
  auto huge = items;  // more profile points than the format allows
  huge[3].primitive = tw::Extrusion{std::vector<glm::vec2>(70000, glm::vec2(1.0f)), 1.0f};
  EXPECT_THROW(tw::addParametricClustersOutOfCore(streamOf(huge), options, storage),
               std::invalid_argument);
  EXPECT_TRUE(storage.instances.empty());
  EXPECT_TRUE(storage.clusters.empty());

  // A stream that changes between its passes is refused before anything is added.
  int calls = 0;
  auto shrinking = [&](const auto& sink) {
    ++calls;
    sink(std::span<const ParametricItem>(items.data(), calls == 1 ? items.size() : 10));
  };
  try {
    tw::addParametricClustersOutOfCore(shrinking, options, storage);
    ADD_FAILURE() << "a stream that changed was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("second pass"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(storage.instances.empty());
  EXPECT_EQ(filesIn(work), 0u);
}

TEST(ParametricExternalSort, WorkDirIsEmptyAfterTheStreamThrows) {
  const auto items = makeItems(3000, 5, kHeavyProfiles);
  const auto work = tw::test::scratchDir() / "work";
  PackageStorage storage;
  storage.origin = kOrigin;
  tw::ParametricSortOptions options;
  options.work_dir = work;
  options.memory_budget_bytes = kMiB;
  int calls = 0;
  size_t files_seen = 0;
  auto failing = [&](const auto& sink) {
    ++calls;
    for (size_t i = 0; i < items.size(); i += 100) {
      if (calls == 2 && i >= items.size() / 2) {
        files_seen = filesIn(work);
        throw std::runtime_error("stream failed");
      }
      sink(std::span<const ParametricItem>(items.data() + i,
                                           std::min<size_t>(100, items.size() - i)));
    }
  };
  EXPECT_THROW(tw::addParametricClustersOutOfCore(failing, options, storage), std::runtime_error);
  EXPECT_GE(files_seen, 5u);  // runs existed when it failed...
  EXPECT_EQ(filesIn(work), 0u);  // ...and are gone
}

TEST(ParametricExternalSort, IoFailureThrowsRuntimeErrorNamingThePath) {
  const auto items = makeItems(3000, 8, kHeavyProfiles);
  const auto dir = tw::test::scratchDir();
  tw::test::writeFile(dir / "plain-file", "not a directory");
  PackageStorage storage;
  storage.origin = kOrigin;
  tw::ParametricSortOptions options;
  options.work_dir = dir / "plain-file" / "work";
  options.memory_budget_bytes = kMiB;
  try {
    tw::addParametricClustersOutOfCore(streamOf(items), options, storage);
    ADD_FAILURE() << "a work directory under a file was accepted";
  } catch (const tw::FormatError& e) {
    ADD_FAILURE() << "an I/O failure is not a format error: " << e.what();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("plain-file"), std::string::npos) << e.what();
  }
  // Everything fits: the work directory is never touched, so the same options succeed.
  const auto small = makeItems(100, 8);
  EXPECT_NO_THROW(tw::addParametricClustersOutOfCore(streamOf(small), options, storage));
  EXPECT_EQ(storage.instances.size(), small.size());
}

// Runs the sort over heavy items with `damage` applied to the first run file once the second
// pass has written it (the stream's last batch has been given by then).
Outcome sortWithDamagedRun(const std::vector<ParametricItem>& items,
                           const std::filesystem::path& work,
                           const std::function<void(const std::filesystem::path&)>& damage,
                           std::string* run_name) {
  Outcome out;
  out.storage.origin = kOrigin;
  tw::ParametricSortOptions options;
  options.work_dir = work;
  options.memory_budget_bytes = kMiB;
  options.max_per_cluster = 16;
  int calls = 0;
  auto stream = [&](const auto& sink) {
    ++calls;
    streamOf(items)(sink);
    if (calls != 2) return;
    std::vector<std::filesystem::path> runs;
    for (const auto& entry : std::filesystem::directory_iterator(work)) runs.push_back(entry);
    std::sort(runs.begin(), runs.end());
    ASSERT_FALSE(runs.empty());
    *run_name = runs.front().filename().string();
    damage(runs.front());
  };
  out.stats = tw::addParametricClustersOutOfCore(stream, options, out.storage);
  return out;
}

TEST(ParametricExternalSort, DamagedRunFileThrowsFormatErrorNamingFileAndOffset) {
  const auto items = makeItems(300, 6, kHeavyProfiles);
  const auto work = tw::test::scratchDir() / "work";
  std::string name;
  auto expectRejected = [&](const std::function<void(const std::filesystem::path&)>& damage,
                            const std::string& reason) {
    try {
      sortWithDamagedRun(items, work, damage, &name);
      ADD_FAILURE() << "damage accepted, expected: " << reason;
    } catch (const tw::FormatError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(name), std::string::npos) << what;
      EXPECT_EQ(e.where(), tw::FormatError::Where::Byte) << what;
      EXPECT_NE(what.find(reason), std::string::npos) << what;
    }
    EXPECT_EQ(filesIn(work), 0u);
  };
  // Truncated: caught before a record is read.
  expectRejected(
      [](const std::filesystem::path& p) {
        std::filesystem::resize_file(p, std::filesystem::file_size(p) - 100);
      },
      "were written");
  // A flipped byte in the middle of a profile: caught by the checksum.
  expectRejected(
      [](const std::filesystem::path& p) {
        std::string bytes = tw::test::readFile(p);
        bytes[bytes.size() / 2] ^= 0x40;
        tw::test::writeFile(p, bytes);
      },
      "checksum mismatch");
  // A record's type byte: caught where it is read.
  expectRejected(
      [](const std::filesystem::path& p) {
        std::string bytes = tw::test::readFile(p);
        bytes[24] = char(9);  // the first record starts right after the 24-byte header
        tw::test::writeFile(p, bytes);
      },
      "byte 24: record 0: primitive type 9 is out of range");
}

TEST(ParametricExternalSort, RobustToTruncatedAndCorruptedRuns) {
  const auto items = makeItems(300, 7, kHeavyProfiles);
  const auto work = tw::test::scratchDir() / "work";
  std::string name;
  std::string original;
  const Outcome clean = sortWithDamagedRun(
      items, work, [&](const std::filesystem::path& p) { original = tw::test::readFile(p); },
      &name);
  ASSERT_GT(original.size(), 100000u);
  int rejected = 0, attempts = 0;
  auto attempt = [&](const std::string& bytes, const std::string& what) {
    ++attempts;
    try {
      const Outcome got = sortWithDamagedRun(
          items, work, [&](const std::filesystem::path& p) { tw::test::writeFile(p, bytes); },
          &name);
      // Accepted: only possible when the damage changed nothing.
      EXPECT_EQ(bytes, original) << what;
      expectSameRecords(clean.storage, got.storage);
    } catch (const tw::FormatError& e) {
      ++rejected;
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << what << ": " << e.what();
    } catch (const std::exception& e) {
      ADD_FAILURE() << what << ": unexpected exception: " << e.what();
    }
    EXPECT_EQ(filesIn(work), 0u) << what;
  };
  for (size_t cut = 0; cut < original.size(); cut += original.size() / 60)
    attempt(original.substr(0, cut), "truncated to " + std::to_string(cut));
  std::mt19937 rng(99);
  for (int i = 0; i < 80; ++i) {
    std::string bytes = original;
    // Half near the start (header, first records' fixed parts), half anywhere.
    const size_t span = i % 2 ? bytes.size() : std::min<size_t>(bytes.size(), 2000);
    for (int hits = 1 + int(rng() % 3); hits > 0; --hits)
      bytes[rng() % span] = char(rng() & 0xff);
    attempt(bytes, "corruption " + std::to_string(i));
  }
  EXPECT_GE(rejected, attempts - 3);  // a corruption may rewrite a byte with its own value
}

}  // namespace
