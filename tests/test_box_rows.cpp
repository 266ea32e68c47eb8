// Rows of equal boxes end to end (box_rows.h): a deck's plates along each frame line are rows,
// across clusters too; a gap in the object order, another size, a turn or a missing covered face
// ends a row; the row's record is the one long box, with its own covered faces. Beams
// (extrusions) end to end are rows too; a gap or another profile ends them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "parametrics/box_rows.h"
#include "covered_box_faces.h"

namespace tw {
namespace {

constexpr uint8_t kMinusX = 1, kPlusX = 2, kMinusY = 4, kPlusY = 8;

pkg::InstanceRecord box(const glm::vec3& centre, const glm::vec3& half, uint32_t object,
                        const glm::mat3& axes = glm::mat3(1.0f)) {
  pkg::InstanceRecord r{};
  for (int k = 0; k < 3; ++k) r.origin[k] = centre[k];
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k) r.linear[c * 3 + k] = axes[c][k];
  for (int k = 0; k < 3; ++k) r.params[k] = half[k];
  r.type = static_cast<uint32_t>(pkg::PrimitiveType::Box);
  r.object = object;
  return r;
}

// A deck of nx by ny plates of 8 m by 7 m, objects in order along X, then Y.
std::vector<pkg::InstanceRecord> deck(int nx, int ny, const glm::mat3& axes = glm::mat3(1.0f)) {
  std::vector<pkg::InstanceRecord> plates;
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x)
      plates.push_back(box(axes * glm::vec3(4.0f + 8.0f * x, 3.5f + 7.0f * y, -0.075f),
                           {4.0f, 3.5f, 0.075f}, uint32_t(y * nx + x), axes));
  return plates;
}

// Marks the covered faces as the preprocessor does (one layer).
void markCovered(std::vector<pkg::InstanceRecord>& instances) {
  const std::vector<uint32_t> layers(instances.size() + 8, 0);
  const std::vector<uint8_t> faces = findCoveredBoxFaces(instances, layers);
  for (size_t i = 0; i < instances.size(); ++i) instances[i].flags |= coveredFaceInstanceFlags(faces[i]);
}

// Parametric clusters of at most `size` consecutive instances.
std::vector<pkg::ClusterRecord> clustersOf(size_t instances, uint32_t size) {
  std::vector<pkg::ClusterRecord> clusters;
  for (uint32_t first = 0; first < instances; first += size) {
    pkg::ClusterRecord c{};
    c.kind = static_cast<uint8_t>(pkg::ClusterKind::Parametric);
    c.instance_first = first;
    c.instance_count = std::min<uint32_t>(size, uint32_t(instances) - first);
    clusters.push_back(c);
  }
  return clusters;
}

TEST(BoxRows, ADecksPlatesAreRowsAlongEachFrameLine) {
  auto plates = deck(4, 3);
  markCovered(plates);
  const std::vector<BoxRow> rows = findBoxRows(plates, clustersOf(plates.size(), 64), {});
  ASSERT_EQ(rows.size(), 3u);
  for (uint32_t y = 0; y < 3; ++y) {
    const BoxRow& row = rows[y];
    EXPECT_EQ(row.axis, 0);
    EXPECT_EQ(row.cluster, 0u);
    ASSERT_EQ(row.instances.size(), 4u);
    for (uint32_t x = 0; x < 4; ++x) EXPECT_EQ(row.instances[x], y * 4 + x);
    // One box 32 m long, centred on the row, the first plate's object.
    EXPECT_FLOAT_EQ(row.record.params[0], 16.0f);
    EXPECT_FLOAT_EQ(row.record.params[1], 3.5f);
    EXPECT_FLOAT_EQ(row.record.origin[0], 16.0f);
    EXPECT_FLOAT_EQ(row.record.origin[1], 3.5f + 7.0f * float(y));
    EXPECT_EQ(row.record.object, y * 4);
    // Its ends are the deck's edge; its long sides are covered where another row lies beside it.
    uint8_t expected = 0;
    if (y > 0) expected |= kMinusY;
    if (y < 2) expected |= kPlusY;
    EXPECT_EQ(coveredFaces(row.record.flags), expected) << "row " << y;
  }
}

TEST(BoxRows, RowsRunAcrossClustersAndTurnedFrames) {
  const glm::mat3 turned = glm::mat3(glm::rotate(glm::mat4(1.0f), 0.3f, glm::vec3(0.0f, 0.0f, 1.0f)));
  auto plates = deck(4, 3, turned);
  markCovered(plates);
  const std::vector<BoxRow> rows = findBoxRows(plates, clustersOf(plates.size(), 5), {});
  ASSERT_EQ(rows.size(), 3u);
  // Clusters of five: the second row's plates 4, 5, 6, 7 lie in clusters 0, 1, 1, 1.
  EXPECT_EQ(rows[1].cluster, 0u);
  EXPECT_EQ(rows[1].member_clusters, (std::vector<uint32_t>{0, 1, 1, 1}));
  // The row's centre is the middle of its frame line, in the turned frame.
  const glm::vec3 centre = turned * glm::vec3(16.0f, 10.5f, -0.075f);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(rows[1].record.origin[k], centre[k], 1e-4f);
}

TEST(BoxRows, AGapInTheObjectsAnotherSizeOrAnUncoveredFaceEndsARow) {
  auto plates = deck(4, 1);
  plates[2].object = 7;  // 0, 1 | 7 | 3: the first two make a row
  plates[3].object = 8;  // 7, 8: and these
  markCovered(plates);
  std::vector<BoxRow> rows = findBoxRows(plates, clustersOf(plates.size(), 64), {});
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].instances, (std::vector<uint32_t>{0, 1}));
  EXPECT_EQ(rows[1].instances, (std::vector<uint32_t>{2, 3}));

  // Thicker plates are not the same box: no face is covered between them, no row.
  auto mixed = deck(4, 1);
  mixed[2].params[2] = 0.1f;
  markCovered(mixed);
  rows = findBoxRows(mixed, clustersOf(mixed.size(), 64), {});
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].instances, (std::vector<uint32_t>{0, 1}));

  // Without the covered faces marked there are no rows: the faces between members are what the
  // row leaves out.
  auto unmarked = deck(4, 1);
  EXPECT_TRUE(findBoxRows(unmarked, clustersOf(unmarked.size(), 64), {}).empty());
}

TEST(BoxRows, ARowKeepsOneAxis) {
  // An L: plates 0, 1, 2 along X, then 3 beside plate 2 along Y.
  std::vector<pkg::InstanceRecord> plates;
  for (int x = 0; x < 3; ++x)
    plates.push_back(box({4.0f + 8.0f * x, 4.0f, 0.0f}, {4.0f, 4.0f, 0.075f}, uint32_t(x)));
  plates.push_back(box({20.0f, 12.0f, 0.0f}, {4.0f, 4.0f, 0.075f}, 3));
  markCovered(plates);
  const std::vector<BoxRow> rows = findBoxRows(plates, clustersOf(plates.size(), 64), {});
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].axis, 0);
  EXPECT_EQ(rows[0].instances, (std::vector<uint32_t>{0, 1, 2}));
}

TEST(BoxRows, ALongChainIsSplitIntoRowsAByteCanCount) {
  std::vector<pkg::InstanceRecord> boxes;
  for (uint32_t k = 0; k < 300; ++k)
    boxes.push_back(box({0.5f + float(k), 0.0f, 0.0f}, {0.5f, 0.5f, 0.5f}, k));
  markCovered(boxes);
  const std::vector<BoxRow> rows = findBoxRows(boxes, clustersOf(boxes.size(), 64), {});
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].instances.size(), kMaxBoxRowMembers);
  EXPECT_EQ(rows[1].instances.size(), 300u - kMaxBoxRowMembers);
  EXPECT_EQ(rows[1].instances.front(), kMaxBoxRowMembers);
  // The split leaves the face between the two rows covered on both.
  EXPECT_TRUE(coveredFaces(rows[0].record.flags) & kPlusX);
  EXPECT_TRUE(coveredFaces(rows[1].record.flags) & kMinusX);
}

TEST(BoxRows, ClustersOutsideTheInstanceTableArePassedOver) {
  auto plates = deck(4, 1);
  markCovered(plates);
  std::vector<pkg::ClusterRecord> clusters = clustersOf(plates.size(), 2);
  clusters[1].instance_first = 100;  // plates 2 and 3 are in no cluster
  const std::vector<BoxRow> rows = findBoxRows(plates, clusters, {});
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].instances, (std::vector<uint32_t>{0, 1}));
}

// Beams as the plant's frame lines have them: extrusions `height` long along world X, end to end
// when `pitch` is their height; each its own copy of one profile (profile k at points 4k).
std::vector<pkg::InstanceRecord> beamLine(int n, float height, float pitch, std::vector<glm::vec2>& profiles) {
  const std::vector<glm::vec2> rectangle = {{-0.1f, -0.2f}, {0.1f, -0.2f}, {0.1f, 0.2f}, {-0.1f, 0.2f}};
  std::vector<pkg::InstanceRecord> beams;
  for (int k = 0; k < n; ++k) {
    pkg::InstanceRecord r{};
    r.origin[0] = pitch * float(k);
    // Local X to world Y, local Y to world Z, the extrusion axis (local Z) to world X.
    const float columns[9] = {0, 1, 0, 0, 0, 1, 1, 0, 0};
    std::copy(columns, columns + 9, r.linear);
    r.params[0] = height;
    r.type = static_cast<uint32_t>(pkg::PrimitiveType::Extrusion);
    r.object = uint32_t(10 + k);
    r.profile_first = uint32_t(profiles.size());
    r.profile_count = uint32_t(rectangle.size());
    profiles.insert(profiles.end(), rectangle.begin(), rectangle.end());
    beams.push_back(r);
  }
  return beams;
}

TEST(BoxRows, BeamsEndToEndAreRowsAlongTheirAxis) {
  std::vector<glm::vec2> profiles;
  const auto beams = beamLine(4, 8.0f, 8.0f, profiles);
  const std::vector<BoxRow> rows = findBoxRows(beams, clustersOf(beams.size(), 64), profiles);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].axis, 2);
  EXPECT_EQ(rows[0].instances, (std::vector<uint32_t>{0, 1, 2, 3}));
  // One extrusion four heights long from the first beam's start, the first beam's object.
  EXPECT_FLOAT_EQ(rows[0].record.params[0], 32.0f);
  EXPECT_FLOAT_EQ(rows[0].record.origin[0], 0.0f);
  EXPECT_EQ(rows[0].record.object, 10u);
  EXPECT_EQ(rows[0].record.profile_first, 0u);
}

TEST(BoxRows, BeamsWithGapsOrOtherProfilesAreNoRow) {
  // A cable tray's sections: a centimetre apart.
  std::vector<glm::vec2> profiles;
  auto beams = beamLine(4, 5.99f, 6.0f, profiles);
  EXPECT_TRUE(findBoxRows(beams, clustersOf(beams.size(), 64), profiles).empty());
  // The third beam's profile is deeper: the first two make a row, the last one stands alone.
  profiles.clear();
  beams = beamLine(4, 8.0f, 8.0f, profiles);
  profiles[beams[2].profile_first + 2].y = 0.25f;
  std::vector<BoxRow> rows = findBoxRows(beams, clustersOf(beams.size(), 64), profiles);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].instances, (std::vector<uint32_t>{0, 1}));
  // A profile outside the table: that beam is passed over, never read.
  profiles.clear();
  beams = beamLine(4, 8.0f, 8.0f, profiles);
  beams[1].profile_first = 1000;
  rows = findBoxRows(beams, clustersOf(beams.size(), 64), profiles);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].instances, (std::vector<uint32_t>{2, 3}));
}

}  // namespace
}  // namespace tw
