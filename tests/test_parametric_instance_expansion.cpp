// The batch of expanded parametric instances, without GL: appending batches, and leaving out
// the points a nearer point hides in the same pixel (dropHiddenPoints).
#include <gtest/gtest.h>

#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "parametric_instance_expansion.h"

namespace tw {
namespace {

using namespace instance_forms;

constexpr glm::ivec2 kViewport(100, 80);

// An orthographic view whose pixel (x, y) holds the eye-relative points (x..x+1, y..y+1, z); its
// clip z falls as z grows, so here the smaller z is the nearer (larger depth, as reversed depth).
glm::mat4 pixelView() {
  return glm::ortho(0.0f, float(kViewport.x), 0.0f, float(kViewport.y), -100.0f, 100.0f);
}

InstanceBatch pointsAt(const std::vector<glm::vec3>& at) {
  InstanceBatch batch;
  for (size_t k = 0; k < at.size(); ++k) appendPoint(batch, uint32_t(k), at[k]);
  return batch;
}

std::vector<uint32_t> objectsOf(const InstanceBatch& batch) {
  std::vector<uint32_t> objects;
  for (uint32_t index : batch.indices[kPoints]) objects.push_back(batch.vertices[index].object);
  return objects;
}

TEST(DropHiddenPoints, KeepsTheNearestInEachPixelAndTheOrder) {
  InstanceBatch batch = pointsAt({{10.5f, 10.5f, 5.0f},    // 0: pixel (10, 10), farther
                                  {20.3f, 30.7f, 0.0f},    // 1: alone
                                  {10.2f, 10.8f, -5.0f},   // 2: pixel (10, 10), nearer: kept
                                  {10.9f, 10.1f, 9.0f},    // 3: pixel (10, 10), farthest
                                  {20.6f, 30.4f, 0.0f}});  // 4: pixel of 1, same depth: kept
  std::vector<PointSample> scratch;
  const glm::mat4 view = pixelView();
  const float depth_0 = (view * glm::vec4(10.5f, 10.5f, 5.0f, 1.0f)).z;
  const float depth_2 = (view * glm::vec4(10.2f, 10.8f, -5.0f, 1.0f)).z;
  ASSERT_GT(depth_2, depth_0);  // point 2 is the nearer
  EXPECT_EQ(dropHiddenPoints(batch, view, kViewport, scratch), 2u);
  EXPECT_EQ(objectsOf(batch), (std::vector<uint32_t>{1, 2, 4}));
}

TEST(DropHiddenPoints, KeepsPointsNearAPixelEdgeOrOffScreen) {
  InstanceBatch batch = pointsAt({{10.5f, 10.5f, -5.0f},    // 0: the nearest of pixel (10, 10)
                                  {10.02f, 10.5f, 5.0f},    // 1: within 1/16 px of its left edge
                                  {10.5f, 10.97f, 5.0f},    // 2: within 1/16 px of its top edge
                                  {-3.5f, 10.5f, 5.0f},     // 3: off screen
                                  {-3.5f, 10.5f, 6.0f},     // 4: off screen, same place
                                  {10.5f, 10.5f, 7.0f}});   // 5: hidden by 0
  std::vector<PointSample> scratch;
  EXPECT_EQ(dropHiddenPoints(batch, pixelView(), kViewport, scratch), 1u);
  EXPECT_EQ(objectsOf(batch), (std::vector<uint32_t>{0, 1, 2, 3, 4}));
  // No viewport: nothing is dropped.
  InstanceBatch again = pointsAt({{10.5f, 10.5f, -5.0f}, {10.5f, 10.5f, 7.0f}});
  EXPECT_EQ(dropHiddenPoints(again, pixelView(), glm::ivec2(0), scratch), 0u);
  EXPECT_EQ(again.indices[kPoints].size(), 2u);
}

TEST(DropHiddenPoints, LeavesTheOtherBatchesAndTheVerticesAlone) {
  InstanceBatch batch = pointsAt({{10.5f, 10.5f, -5.0f}, {10.5f, 10.5f, 7.0f}});
  batch.indices[kTwoSided] = {0, 1, 0};
  const size_t vertices = batch.vertices.size();
  std::vector<PointSample> scratch;
  EXPECT_EQ(dropHiddenPoints(batch, pixelView(), kViewport, scratch), 1u);
  EXPECT_EQ(batch.vertices.size(), vertices);
  EXPECT_EQ(batch.indices[kTwoSided], (std::vector<uint32_t>{0, 1, 0}));
  EXPECT_EQ(batch.primitives(), 2u);  // one point, one triangle
}

TEST(InstanceBatch, AppendOffsetsEachBatchsIndices) {
  InstanceBatch a = pointsAt({{1, 1, 0}, {2, 2, 0}});
  InstanceBatch b = pointsAt({{3, 3, 0}});
  b.beam_vertices.push_back({glm::vec3(0.0f), 7u, 0u, 0u, 0.0f});
  b.indices[kBeams] = {0};
  a.beam_vertices.push_back({glm::vec3(0.0f), 6u, 0u, 0u, 0.0f});
  a.append(b);
  EXPECT_EQ(a.indices[kPoints], (std::vector<uint32_t>{0, 1, 2}));
  EXPECT_EQ(a.indices[kBeams], (std::vector<uint32_t>{1}));
  EXPECT_EQ(a.beam_vertices[1].object, 7u);
  a.clear();
  EXPECT_EQ(a.primitives(), 0u);
  EXPECT_TRUE(a.vertices.empty());
}

}  // namespace
}  // namespace tw
