// EmbreeScene: hits at known distances far from the world origin, ids, misses, batches and
// argument checks.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "embree_scene.h"

namespace {

using tw::EmbreeScene;
using tw::Ray;

// A unit cube [0,1]^3 (in the given frame), 12 outward-wound triangles.
void unitCube(const glm::vec3& offset, std::vector<glm::vec3>& positions, std::vector<uint32_t>& indices) {
  positions.clear();
  for (int i = 0; i < 8; ++i)
    positions.push_back(offset + glm::vec3(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1)));
  indices = {0, 2, 1, 1, 2, 3,   // z = 0, normal -z
             4, 5, 6, 5, 7, 6,   // z = 1, normal +z
             0, 1, 4, 1, 5, 4,   // y = 0, normal -y
             2, 6, 3, 3, 6, 7,   // y = 1, normal +y
             0, 4, 2, 2, 4, 6,   // x = 0, normal -x
             1, 3, 5, 3, 7, 5};  // x = 1, normal +x
}

constexpr glm::dvec3 kFarOrigin{6.0e6, 2.0e6, 100.0};

TEST(EmbreeScene, CubeAtFarOriginHitAtKnownDistance) {
  // The cube sits at world (6e6, 2e6, 100) .. +1; as floats in world space its faces would be
  // quantised to 0.5 m, relative to the origin they are exact.
  EmbreeScene scene(kFarOrigin);
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;
  unitCube(glm::vec3(0.0f), positions, indices);
  uint32_t geometry = scene.addMesh(positions, indices, 4242);
  scene.commit();
  EXPECT_EQ(geometry, 0u);
  EXPECT_EQ(scene.triangleCount(), 12u);
  EXPECT_EQ(scene.geometryCount(), 1u);

  // From world x = origin.x - 2.5 along +x through the cube's middle: hits the x = 0 face at t = 2.5.
  glm::dvec3 world_start = kFarOrigin + glm::dvec3(-2.5, 0.5, 0.25);
  Ray ray;
  ray.origin = scene.toScene(world_start);
  ray.direction = {1.0f, 0.0f, 0.0f};
  EmbreeScene::Hit hit = scene.intersect(ray);
  ASSERT_TRUE(hit.hit);
  EXPECT_NEAR(hit.t, 2.5f, 1e-5f);
  EXPECT_EQ(hit.user_id, 4242u);
  EXPECT_EQ(hit.geometry, 0u);
  EXPECT_LT(hit.primitive, 12u);
  EXPECT_NEAR(std::abs(hit.normal.x), 1.0f, 1e-5f);
  EXPECT_NEAR(hit.normal.y, 0.0f, 1e-5f);
  // The hit point, taken back to world coordinates, lies on the face at millimetre accuracy.
  glm::dvec3 world_hit = scene.toWorld(ray.origin + hit.t * ray.direction);
  EXPECT_NEAR(world_hit.x, kFarOrigin.x, 1e-4);
  EXPECT_NEAR(world_hit.y, kFarOrigin.y + 0.5, 1e-4);

  // Straight down onto the top face from 10 units above: t = 9 with a non-unit direction scaled.
  ray.origin = scene.toScene(kFarOrigin + glm::dvec3(0.5, 0.5, 10.0));
  ray.direction = {0.0f, 0.0f, -2.0f};
  hit = scene.intersect(ray);
  ASSERT_TRUE(hit.hit);
  EXPECT_NEAR(hit.t, 4.5f, 1e-5f);  // t in multiples of the direction's length
  EXPECT_NEAR(hit.normal.z, 1.0f, 1e-5f);  // outward winding on the top face
  EXPECT_TRUE(scene.occluded(ray));
}

TEST(EmbreeScene, MissesAndRayInterval) {
  EmbreeScene scene(kFarOrigin);
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;
  unitCube(glm::vec3(0.0f), positions, indices);
  scene.addMesh(positions, indices, 1);
  scene.commit();

  Ray ray;
  ray.origin = {-2.0f, 3.0f, 0.5f};  // passes beside the cube
  ray.direction = {1.0f, 0.0f, 0.0f};
  EXPECT_FALSE(scene.intersect(ray).hit);
  EXPECT_FALSE(scene.occluded(ray));

  ray.origin = {-2.0f, 0.5f, 0.5f};
  ray.direction = {-1.0f, 0.0f, 0.0f};  // pointing away
  EXPECT_FALSE(scene.intersect(ray).hit);

  ray.direction = {1.0f, 0.0f, 0.0f};
  ray.t_far = 1.5f;  // stops short of the face at t = 2
  EXPECT_FALSE(scene.intersect(ray).hit);
  EXPECT_FALSE(scene.occluded(ray));
  ray.t_far = 2.5f;
  EXPECT_TRUE(scene.occluded(ray));
  ray.t_near = 2.5f;  // starts inside: the next face is the far one at t = 3
  ray.t_far = 100.0f;
  EmbreeScene::Hit hit = scene.intersect(ray);
  ASSERT_TRUE(hit.hit);
  EXPECT_NEAR(hit.t, 3.0f, 1e-5f);
}

TEST(EmbreeScene, UserIdsRoundTripAcrossCopiedAndMovedMeshes) {
  EmbreeScene scene(glm::dvec3(-3.0e5, 7.0e5, -50.0));
  // Three cubes along x at 0, 3 and 6; the middle one is handed over by move, and an empty mesh
  // in between still takes an id.
  std::vector<uint32_t> user_ids = {10, 20, 30};
  std::vector<uint32_t> geometry_ids;
  for (int i = 0; i < 3; ++i) {
    std::vector<glm::vec3> positions;
    std::vector<uint32_t> indices;
    unitCube(glm::vec3(3.0f * float(i), 0.0f, 0.0f), positions, indices);
    if (i == 1) {
      geometry_ids.push_back(scene.addMesh(std::move(positions), std::move(indices), user_ids[i]));
      EXPECT_EQ(scene.addMesh(std::vector<glm::vec3>{}, std::vector<uint32_t>{}, 99), 2u);
    } else {
      geometry_ids.push_back(scene.addMesh(positions, indices, user_ids[i]));
    }
  }
  scene.commit();
  EXPECT_EQ(scene.geometryCount(), 4u);
  EXPECT_EQ(scene.triangleCount(), 36u);
  EXPECT_EQ(geometry_ids, (std::vector<uint32_t>{0, 1, 3}));

  for (int i = 0; i < 3; ++i) {
    Ray ray;
    ray.origin = {3.0f * float(i) + 0.5f, 0.5f, 5.0f};
    ray.direction = {0.0f, 0.0f, -1.0f};
    EmbreeScene::Hit hit = scene.intersect(ray);
    ASSERT_TRUE(hit.hit) << i;
    EXPECT_EQ(hit.user_id, user_ids[i]);
    EXPECT_EQ(hit.geometry, geometry_ids[i]);
    EXPECT_NEAR(hit.t, 4.0f, 1e-5f);
  }
}

TEST(EmbreeScene, BatchMatchesSingleRays) {
  EmbreeScene scene(glm::dvec3(1.0e6, 0.0, 0.0));
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;
  unitCube(glm::vec3(-0.5f), positions, indices);
  scene.addMesh(positions, indices, 7);
  scene.commit();

  // Random rays from a sphere of radius 3 towards random points near the cube: some hit, some miss.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::vector<Ray> rays(5000);
  for (Ray& r : rays) {
    glm::vec3 from(unit(rng), unit(rng), unit(rng));
    r.origin = 3.0f * glm::normalize(from + glm::vec3(1e-3f));
    glm::vec3 to(unit(rng), unit(rng), unit(rng));
    r.direction = glm::normalize(to - r.origin);
  }
  std::vector<EmbreeScene::Hit> hits(rays.size());
  std::vector<uint8_t> blocked(rays.size());
  scene.intersect(rays, hits);
  scene.occluded(rays, blocked, true);
  size_t hit_count = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    EmbreeScene::Hit single = scene.intersect(rays[i]);
    ASSERT_EQ(single.hit, hits[i].hit) << i;
    EXPECT_EQ(blocked[i] != 0, hits[i].hit) << i;
    if (single.hit) {
      ++hit_count;
      EXPECT_EQ(single.t, hits[i].t);
      EXPECT_EQ(hits[i].user_id, 7u);
      // The hit point lies on the cube's surface.
      glm::vec3 p = rays[i].origin + hits[i].t * rays[i].direction;
      float max_abs = std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)});
      EXPECT_NEAR(max_abs, 0.5f, 1e-4f);
    }
  }
  EXPECT_GT(hit_count, rays.size() / 4);
  EXPECT_LT(hit_count, rays.size());
}

TEST(EmbreeScene, EmptySceneMissesEverything) {
  EmbreeScene scene(glm::dvec3(0.0));
  scene.commit();
  Ray ray;
  EXPECT_FALSE(scene.intersect(ray).hit);
  EXPECT_FALSE(scene.occluded(ray));
}

TEST(EmbreeScene, RejectsBadMeshesAndMisuse) {
  EmbreeScene scene(glm::dvec3(0.0));
  std::vector<glm::vec3> positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_THROW(scene.addMesh(positions, std::vector<uint32_t>{0, 1}, 0), std::invalid_argument);
  EXPECT_THROW(scene.addMesh(positions, std::vector<uint32_t>{0, 1, 3}, 0), std::invalid_argument);
  EXPECT_THROW(scene.intersect(Ray{}), std::logic_error);
  EXPECT_EQ(scene.addMesh(positions, std::vector<uint32_t>{0, 1, 2}, 5), 0u);
  scene.commit();
  EXPECT_THROW(scene.addMesh(positions, std::vector<uint32_t>{0, 1, 2}, 0), std::logic_error);
  EXPECT_THROW(scene.commit(), std::logic_error);
}

}  // namespace
