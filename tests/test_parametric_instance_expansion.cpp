// The batch of expanded parametric instances, without GL: appending one to another.
#include <gtest/gtest.h>

#include <vector>

#include "parametrics/parametric_instance_expansion.h"

namespace tw {
namespace {

using namespace instance_forms;

InstanceBatch pointsAt(const std::vector<glm::vec3>& at) {
  InstanceBatch batch;
  for (size_t k = 0; k < at.size(); ++k) appendPoint(batch, uint32_t(k), at[k]);
  return batch;
}

TEST(InstanceBatch, AppendOffsetsEachBatchsIndices) {
  InstanceBatch a = pointsAt({{1, 1, 0}, {2, 2, 0}});
  InstanceBatch b = pointsAt({{3, 3, 0}});
  b.beam_vertices.push_back({glm::vec3(0.0f), 7u, 0u, 0u, 0.0f, 0.0f, 0u});
  b.indices[kBeams] = {0, 0, 0};
  b.indices[kTwoSided] = {0, 0, 0};
  a.beam_vertices.push_back({glm::vec3(0.0f), 6u, 0u, 0u, 0.0f, 0.0f, 0u});
  a.append(b);
  // Points and triangles index the smooth vertices, beams their own.
  EXPECT_EQ(a.indices[kPoints], (std::vector<uint32_t>{0, 1, 2}));
  EXPECT_EQ(a.indices[kTwoSided], (std::vector<uint32_t>{2, 2, 2}));
  EXPECT_EQ(a.indices[kBeams], (std::vector<uint32_t>{1, 1, 1}));
  EXPECT_EQ(a.beam_vertices[1].object, 7u);
  EXPECT_EQ(a.primitives(), 5u);  // three points, two triangles
  a.clear();
  EXPECT_EQ(a.primitives(), 0u);
  EXPECT_TRUE(a.vertices.empty());
}

}  // namespace
}  // namespace tw
