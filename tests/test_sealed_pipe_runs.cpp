// Sealed pipe runs: which open tubes and elbows form runs closed at every end (flanges, boxes,
// other parts' solids), and which do not (an open end, a gap, a radius step, a sheared part).
#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <numbers>
#include <random>
#include <vector>

#include <glm/glm.hpp>

#include "sealed_pipe_runs.h"

namespace tw {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

// A rigid frame whose z axis is `dir` (x, y completed), scaled by `scale`, optionally mirrored.
glm::mat3 frameAlong(const glm::vec3& dir, float scale = 1.0f, bool mirrored = false) {
  const glm::vec3 z = glm::normalize(dir);
  const glm::vec3 helper = std::abs(z.z) < 0.9f ? glm::vec3(0, 0, 1) : glm::vec3(1, 0, 0);
  const glm::vec3 x = glm::normalize(glm::cross(helper, z));
  const glm::vec3 y = glm::cross(z, x);
  return glm::mat3(x * scale, (mirrored ? -y : y) * scale, z * scale);
}

pkg::InstanceRecord record(pkg::PrimitiveType type, const glm::vec3& origin, const glm::mat3& linear,
                           std::initializer_list<float> params, bool capped = false) {
  pkg::InstanceRecord r{};
  for (int k = 0; k < 3; ++k) r.origin[k] = origin[k];
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k) r.linear[c * 3 + k] = linear[c][k];
  int k = 0;
  for (float p : params) r.params[k++] = p;
  r.type = static_cast<uint32_t>(type);
  r.flags = capped ? pkg::kInstanceCapped : 0u;
  return r;
}

// An open or capped cylinder from `from` along `dir` (unit) for `length`.
pkg::InstanceRecord tube(const glm::vec3& from, const glm::vec3& dir, float length, float radius,
                         bool capped = false, float scale = 1.0f, bool mirrored = false) {
  return record(pkg::PrimitiveType::Cylinder, from, frameAlong(dir, scale, mirrored),
                {radius / scale, length / scale}, capped);
}

// A flange: a capped cylinder of 1.5 times the pipe's radius centred on `at`, across `dir`.
pkg::InstanceRecord flange(const glm::vec3& at, const glm::vec3& dir, float pipe_radius) {
  return tube(at - 0.02f * dir, dir, 0.04f, 1.5f * pipe_radius, true);
}

// The run of the plant generator's shape: flange, spool along +x to (2, 0, 0), a 90 degree
// elbow of bend radius 0.3 turning to +y, spool up to (2.3, 2.3, 0), flange.
struct PipeRun {
  std::vector<pkg::InstanceRecord> parts;
  static constexpr float kRadius = 0.05f, kBend = 0.3f;
};

PipeRun lRun() {
  PipeRun run;
  const glm::vec3 x(1, 0, 0), y(0, 1, 0);
  run.parts.push_back(flange({0, 0, 0}, x, PipeRun::kRadius));
  run.parts.push_back(tube({0, 0, 0}, x, 2.0f, PipeRun::kRadius));
  // Torus frame: local x from the bend centre to the elbow's start, local y along the incoming
  // pipe, turning counter-clockwise about local z.
  const glm::vec3 centre(2.0f, PipeRun::kBend, 0.0f);
  run.parts.push_back(record(pkg::PrimitiveType::TorusSegment, centre,
                             glm::mat3(glm::vec3(0, -1, 0), x, glm::vec3(0, 0, 1)),
                             {PipeRun::kBend, PipeRun::kRadius, 0.5f * kPi}));
  run.parts.push_back(tube({2.0f + PipeRun::kBend, PipeRun::kBend, 0.0f}, y, 2.0f, PipeRun::kRadius));
  run.parts.push_back(flange({2.0f + PipeRun::kBend, 2.0f + PipeRun::kBend, 0.0f}, y, PipeRun::kRadius));
  return run;
}

TEST(SealedPipeRuns, RunClosedByFlangesIsSealed) {
  const PipeRun run = lRun();
  SealedRunStats stats;
  const std::vector<uint8_t> roles = findSealedRuns(run.parts, &stats);
  ASSERT_EQ(roles.size(), 5u);
  EXPECT_EQ(roles[0], kSealedRunCloser);
  EXPECT_EQ(roles[1], kSealedRunMember);
  EXPECT_EQ(roles[2], kSealedRunMember);
  EXPECT_EQ(roles[3], kSealedRunMember);
  EXPECT_EQ(roles[4], kSealedRunCloser);
  EXPECT_EQ(stats.open_parts, 3u);
  EXPECT_EQ(stats.runs, 1u);
  EXPECT_EQ(stats.sealed_runs, 1u);
  EXPECT_EQ(stats.sealed_members, 3u);
  EXPECT_EQ(stats.closers, 2u);
}

TEST(SealedPipeRuns, OneOpenEndLeavesTheWholeRunOpen) {
  PipeRun run = lRun();
  run.parts.pop_back();  // the far flange
  SealedRunStats stats;
  const std::vector<uint8_t> roles = findSealedRuns(run.parts, &stats);
  for (uint8_t role : roles) EXPECT_EQ(role, 0u);
  EXPECT_EQ(stats.runs, 1u);
  EXPECT_EQ(stats.sealed_runs, 0u);
}

TEST(SealedPipeRuns, GapsAndRadiusStepsDoNotJoin) {
  const glm::vec3 x(1, 0, 0);
  const float r = 0.05f;
  // Two spools 1 mm apart between flanges.
  std::vector<pkg::InstanceRecord> gap = {flange({0, 0, 0}, x, r), tube({0, 0, 0}, x, 1.0f, r),
                                          tube({1.001f, 0, 0}, x, 1.0f, r),
                                          flange({2.001f, 0, 0}, x, r)};
  for (uint8_t role : findSealedRuns(gap)) EXPECT_EQ(role, 0u);
  // Touching, but the second is 5 mm wider: the step's ring opens into both.
  std::vector<pkg::InstanceRecord> step = {flange({0, 0, 0}, x, r), tube({0, 0, 0}, x, 1.0f, r),
                                           tube({1.0f, 0, 0}, x, 1.0f, r + 0.005f),
                                           flange({2.0f, 0, 0}, x, r + 0.005f)};
  for (uint8_t role : findSealedRuns(step)) EXPECT_EQ(role, 0u);
  // Touching and equal: sealed (the same set-up, so the two above fail for their own reason).
  std::vector<pkg::InstanceRecord> joined = {flange({0, 0, 0}, x, r), tube({0, 0, 0}, x, 1.0f, r),
                                             tube({1.0f, 0, 0}, x, 1.0f, r),
                                             flange({2.0f, 0, 0}, x, r)};
  SealedRunStats stats;
  findSealedRuns(joined, &stats);
  EXPECT_EQ(stats.sealed_members, 2u);
}

TEST(SealedPipeRuns, BranchEndingInsideAnotherPartJoinsItsRun) {
  const glm::vec3 x(1, 0, 0), z(0, 0, 1);
  const float header_r = 0.2f, branch_r = 0.05f;
  std::vector<pkg::InstanceRecord> parts = {
      flange({0, 0, 0}, x, header_r), tube({0, 0, 0}, x, 3.0f, header_r),
      flange({3, 0, 0}, x, header_r),
      // A branch rising from inside the header (its lower end 0.1 m below the header's axis).
      tube({1.5f, 0, -0.1f}, z, 2.0f, branch_r), flange({1.5f, 0, 1.9f}, z, branch_r)};
  SealedRunStats stats;
  std::vector<uint8_t> roles = findSealedRuns(parts, &stats);
  EXPECT_EQ(roles[1], kSealedRunMember);
  EXPECT_EQ(roles[3], kSealedRunMember);
  EXPECT_EQ(stats.runs, 1u);  // the branch joined the header's run
  // The header's far end open: the branch sees into it, so neither is sealed.
  parts.erase(parts.begin() + 2);
  roles = findSealedRuns(parts);
  EXPECT_EQ(roles[1], 0u);
  EXPECT_EQ(roles[2], 0u);
  // A branch sticking out of the header's side (its end disc not wholly inside): open.
  std::vector<pkg::InstanceRecord> poking = {
      flange({0, 0, 0}, x, header_r), tube({0, 0, 0}, x, 3.0f, header_r),
      flange({3, 0, 0}, x, header_r), tube({1.5f, 0, 0.19f}, z, 2.0f, branch_r),
      flange({1.5f, 0, 2.19f}, z, branch_r)};
  roles = findSealedRuns(poking);
  EXPECT_EQ(roles[3], 0u);
  EXPECT_EQ(roles[1], kSealedRunMember);  // the header alone stays sealed
}

// The roles do not depend on the order of the instances: the preprocessor searches them in input
// order and `terawalk verify` in package order. A branch whose lower end lies inside both the
// header's solid and a flange (two holders) is the case that once did: it joined whichever was
// found first. Here the header's far end is open, so the branch is open exactly when it joins.
TEST(SealedPipeRuns, RolesDoNotDependOnInstanceOrder) {
  const glm::vec3 x(1, 0, 0), z(0, 0, 1);
  const float header_r = 0.2f, branch_r = 0.05f;
  std::vector<pkg::InstanceRecord> parts = {
      flange({0, 0, 0}, x, header_r), tube({0, 0, 0}, x, 3.0f, header_r),  // far end open
      tube({1.5f, 0, -0.1f}, z, 2.0f, branch_r), flange({1.5f, 0, 1.9f}, z, branch_r),
      // A wide capped disc around the branch's lower end, inside the header.
      tube({1.5f, 0, -0.12f}, z, 0.04f, 0.1f, true)};
  for (pkg::InstanceRecord part : lRun().parts) {  // a sealed run 10 m away
    part.origin[1] += 10.0f;
    parts.push_back(part);
  }
  const std::vector<uint8_t> roles = findSealedRuns(parts);
  EXPECT_EQ(roles[2], 0u);  // joined the open header's run
  EXPECT_EQ(roles[6], kSealedRunMember);  // the L run stays sealed
  std::vector<uint32_t> order(parts.size());
  for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::mt19937 rng(3);
  for (int trial = 0; trial < 50; ++trial) {
    std::shuffle(order.begin(), order.end(), rng);
    std::vector<pkg::InstanceRecord> shuffled;
    for (uint32_t i : order) shuffled.push_back(parts[i]);
    const std::vector<uint8_t> got = findSealedRuns(shuffled);
    for (uint32_t k = 0; k < order.size(); ++k)
      EXPECT_EQ(got[k], roles[order[k]]) << "instance " << order[k] << ", trial " << trial;
  }
}

TEST(SealedPipeRuns, PipeEndingInsideABoxIsClosed) {
  const glm::vec3 z(0, 0, 1);
  // A deck plate 0.15 m thick, 12 m wide (a holder too large for the fine grid), and a pipe that
  // rises from a flange into it and ends 5 cm inside.
  const pkg::InstanceRecord deck =
      record(pkg::PrimitiveType::Box, {6.0f, 6.0f, 3.075f}, glm::mat3(1.0f), {6.0f, 6.0f, 0.075f},
             true);
  std::vector<pkg::InstanceRecord> parts = {deck, flange({1, 1, 0}, z, 0.05f),
                                            tube({1, 1, 0}, z, 3.05f, 0.05f)};
  std::vector<uint8_t> roles = findSealedRuns(parts);
  EXPECT_EQ(roles[2], kSealedRunMember);
  EXPECT_EQ(roles[0], kSealedRunCloser);
  // Ending 5 cm short of the plate: open.
  parts[2] = tube({1, 1, 0}, z, 2.95f, 0.05f);
  roles = findSealedRuns(parts);
  EXPECT_EQ(roles[2], 0u);
}

TEST(SealedPipeRuns, UniformScaleAndMirroringAreKeptShearIsNot) {
  const glm::vec3 x(1, 0, 0);
  const float r = 0.05f;
  std::vector<pkg::InstanceRecord> parts = {flange({0, 0, 0}, x, r),
                                            tube({0, 0, 0}, x, 1.0f, r, false, 0.001f, true),
                                            flange({1, 0, 0}, x, r)};
  EXPECT_EQ(findSealedRuns(parts)[1], kSealedRunMember);
  // Stretched along one axis: its cross-section is an ellipse, never a member.
  parts[1].linear[0] *= 1.5f;
  parts[1].linear[1] *= 1.5f;
  parts[1].linear[2] *= 1.5f;
  EXPECT_EQ(findSealedRuns(parts)[1], 0u);
}

TEST(SealedPipeRuns, FullTorusAndCappedPartsAreNotParts) {
  std::vector<pkg::InstanceRecord> parts = {
      record(pkg::PrimitiveType::TorusSegment, {0, 0, 0}, glm::mat3(1.0f), {0.3f, 0.02f, 2.0f * kPi}),
      tube({0, 0, 0}, {0, 0, 1}, 1.0f, 0.1f, true)};
  SealedRunStats stats;
  const std::vector<uint8_t> roles = findSealedRuns(parts, &stats);
  EXPECT_EQ(stats.open_parts, 0u);
  EXPECT_EQ(roles[0], 0u);
  EXPECT_EQ(roles[1], 0u);
}

}  // namespace
}  // namespace tw
