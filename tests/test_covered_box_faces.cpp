// Covered box faces: which faces of box instances another box of the same layer covers with the
// same rectangle facing it (a deck of plates, one per bay), and which it does not (a gap, a
// smaller neighbour, another layer, a sheared box, boxes that only overlap).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "covered_box_faces.h"

namespace tw {
namespace {

// Face bits, in the order -X, +X, -Y, +Y, -Z, +Z.
constexpr uint8_t kMinusX = 1, kPlusX = 2, kMinusY = 4, kPlusY = 8;

// A box of half sizes `half` centred on `centre`, its axes the columns of `axes`, of `object`.
pkg::InstanceRecord box(const glm::vec3& centre, const glm::vec3& half,
                        const glm::mat3& axes = glm::mat3(1.0f), uint32_t object = 0) {
  pkg::InstanceRecord r{};
  for (int k = 0; k < 3; ++k) r.origin[k] = centre[k];
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k) r.linear[c * 3 + k] = axes[c][k];
  for (int k = 0; k < 3; ++k) r.params[k] = half[k];
  r.type = static_cast<uint32_t>(pkg::PrimitiveType::Box);
  r.object = object;
  return r;
}

// A deck of nx by ny plates, each 8 m by 7 m and 0.15 m thick, meeting edge to edge.
std::vector<pkg::InstanceRecord> deck(int nx, int ny, const glm::vec3& at = glm::vec3(0.0f)) {
  std::vector<pkg::InstanceRecord> plates;
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x)
      plates.push_back(box(at + glm::vec3(4.0f + 8.0f * x, 3.5f + 7.0f * y, -0.075f),
                           {4.0f, 3.5f, 0.075f}));
  return plates;
}

const std::vector<uint32_t> kOneLayer = {0, 0, 0, 0};

TEST(CoveredBoxFaces, PlatesOfADeckCoverEachOthersSides) {
  const auto plates = deck(4, 3);
  CoveredFaceStats stats;
  const std::vector<uint8_t> faces = findCoveredBoxFaces(plates, kOneLayer, &stats);
  ASSERT_EQ(faces.size(), 12u);
  // Interior sides only: the deck's rim and every top and bottom stay.
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) {
      uint8_t expected = 0;
      if (x > 0) expected |= kMinusX;
      if (x < 3) expected |= kPlusX;
      if (y > 0) expected |= kMinusY;
      if (y < 2) expected |= kPlusY;
      EXPECT_EQ(faces[size_t(y * 4 + x)], expected) << "plate " << x << ", " << y;
    }
  EXPECT_EQ(stats.boxes, 12u);
  EXPECT_EQ(stats.covered_faces, 2u * (3 * 3 + 4 * 2));  // each shared side, both ways
  EXPECT_EQ(stats.boxes_with_covered_faces, 12u);
}

TEST(CoveredBoxFaces, FarFromTheOriginWithinFloatRounding) {
  // A plant frame far out: float rounding of the centres (about 0.06 mm at 1 km) is within the
  // tolerance, a 1 mm gap is not.
  const auto plates = deck(2, 1, {1234.5f, -987.25f, 40.0f});
  EXPECT_EQ(findCoveredBoxFaces(plates, kOneLayer)[0], kPlusX);
  auto apart = plates;
  apart[1].origin[0] += 0.001f;
  EXPECT_EQ(findCoveredBoxFaces(apart, kOneLayer)[0], 0);
}

TEST(CoveredBoxFaces, OnlyTheSameRectangleOfTheSameLayerFacingIt) {
  const auto plates = deck(2, 1);
  // A narrower neighbour covers part of the side: nothing (its side is inside ours, not equal).
  auto narrow = plates;
  narrow[1].params[1] = 3.0f;
  EXPECT_EQ(findCoveredBoxFaces(narrow, kOneLayer)[0], 0);
  EXPECT_EQ(findCoveredBoxFaces(narrow, kOneLayer)[1], 0);
  // A thicker one: nothing.
  auto thick = plates;
  thick[1].params[2] = 0.1f;
  EXPECT_EQ(findCoveredBoxFaces(thick, kOneLayer)[0], 0);
  // Another layer: nothing (hiding one layer must not open the other's boxes).
  auto other = plates;
  other[1].object = 1;
  const std::vector<uint32_t> two_layers = {0, 1};
  EXPECT_EQ(findCoveredBoxFaces(other, two_layers)[0], 0);
  EXPECT_EQ(findCoveredBoxFaces(other, kOneLayer)[0], kPlusX);
  // An object beyond the layer table pairs with nothing.
  EXPECT_EQ(findCoveredBoxFaces(other, std::vector<uint32_t>{0})[0], 0);
  // Two boxes in the same place overlap; their faces face the same way: nothing.
  std::vector<pkg::InstanceRecord> twins = {plates[0], plates[0]};
  EXPECT_EQ(findCoveredBoxFaces(twins, kOneLayer)[0], 0);
}

TEST(CoveredBoxFaces, TurnedScaledAndMirroredBoxesPairByTheirGeometry) {
  // Two unit cubes meeting at x = 0, the second turned 90 degrees about z, scaled by 2 in its
  // frame (half sizes 0.25) and mirrored: the shared face is found whatever the frames.
  const glm::mat3 turned_mirrored =
      glm::mat3(glm::vec3(0, 2, 0), glm::vec3(2, 0, 0), glm::vec3(0, 0, 2));
  std::vector<pkg::InstanceRecord> cubes = {box({-0.5f, 0, 0}, glm::vec3(0.5f)),
                                            box({0.5f, 0, 0}, glm::vec3(0.25f), turned_mirrored)};
  const std::vector<uint8_t> faces = findCoveredBoxFaces(cubes, kOneLayer);
  EXPECT_EQ(faces[0], kPlusX);
  // The second's face toward -x is its local -Y face (its local y is world x).
  EXPECT_EQ(faces[1], kMinusY);
  // Turned by 45 degrees about z, the pair still meets face to face.
  const glm::mat3 turn = glm::mat3(glm::rotate(glm::mat4(1.0f), std::numbers::pi_v<float> / 4,
                                               glm::vec3(0, 0, 1)));
  const glm::vec3 step = turn * glm::vec3(1, 0, 0);
  std::vector<pkg::InstanceRecord> turned = {box(glm::vec3(10.0f), glm::vec3(0.5f), turn),
                                             box(glm::vec3(10.0f) + step, glm::vec3(0.5f), turn)};
  const std::vector<uint8_t> turned_faces = findCoveredBoxFaces(turned, kOneLayer);
  EXPECT_EQ(turned_faces[0], kPlusX);
  EXPECT_EQ(turned_faces[1], kMinusX);
}

TEST(CoveredBoxFaces, ShearedDegenerateAndOtherTypesAreLeftAlone) {
  auto plates = deck(2, 1);
  // Sheared: the columns are not perpendicular.
  auto sheared = plates;
  sheared[1].linear[3] = 0.3f;  // the y column leans toward x
  EXPECT_EQ(findCoveredBoxFaces(sheared, kOneLayer)[0], 0);
  // A zero or non-finite size.
  auto flat = plates;
  flat[1].params[0] = 0.0f;
  EXPECT_EQ(findCoveredBoxFaces(flat, kOneLayer)[0], 0);
  auto bad = plates;
  bad[1].origin[1] = std::nanf("");
  EXPECT_EQ(findCoveredBoxFaces(bad, kOneLayer)[0], 0);
  // A cylinder where the neighbour was: not a box.
  auto other = plates;
  other[1].type = static_cast<uint32_t>(pkg::PrimitiveType::Cylinder);
  const std::vector<uint8_t> faces = findCoveredBoxFaces(other, kOneLayer);
  EXPECT_EQ(faces[0], 0);
  EXPECT_EQ(faces[1], 0);
  EXPECT_TRUE(findCoveredBoxFaces({}, kOneLayer).empty());
}

TEST(CoveredBoxFaces, FlagsRoundTrip) {
  for (uint32_t faces = 0; faces < 64; ++faces) {
    const uint32_t flags = coveredFaceInstanceFlags(uint8_t(faces));
    EXPECT_EQ(flags & ~pkg::kInstanceCoveredFaces, 0u);
    EXPECT_EQ(coveredFaces(flags | pkg::kInstanceCapped | pkg::kInstanceSealedRunCloser), faces);
  }
}

// Thousands of coincident copies (a legal but pathological input: an export that repeats its
// parts) are indexed once: every copy of the left box gets its +X face covered by the right box,
// the right box its -X face, the counts include every copy, and a copy on another layer is not
// taken for one (its face stays uncovered).
TEST(CoveredBoxFaces, CoincidentCopiesShareTheirFacesResult) {
  std::vector<pkg::InstanceRecord> boxes;
  const int kCopies = 3000;
  for (int i = 0; i < kCopies; ++i) boxes.push_back(box({0.5f, 0.0f, 0.0f}, {0.5f, 0.5f, 0.5f}, glm::mat3(1.0f), 0));
  boxes.push_back(box({1.5f, 0.0f, 0.0f}, {0.5f, 0.5f, 0.5f}, glm::mat3(1.0f), 0));
  boxes.push_back(box({0.5f, 0.0f, 0.0f}, {0.5f, 0.5f, 0.5f}, glm::mat3(1.0f), 1));  // other layer
  const std::vector<uint32_t> layers = {0, 1};
  CoveredFaceStats stats;
  const std::vector<uint8_t> faces = findCoveredBoxFaces(boxes, layers, &stats);
  for (int i = 0; i < kCopies; ++i) ASSERT_EQ(faces[size_t(i)], kPlusX) << "copy " << i;
  EXPECT_EQ(faces[kCopies], kMinusX);
  EXPECT_EQ(faces[kCopies + 1], 0) << "the copy on another layer";
  EXPECT_EQ(stats.boxes, uint64_t(kCopies + 2));
  EXPECT_EQ(stats.covered_faces, uint64_t(kCopies + 1));
  EXPECT_EQ(stats.boxes_with_covered_faces, uint64_t(kCopies + 1));
}

}  // namespace
}  // namespace tw
