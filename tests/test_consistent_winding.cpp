// Consistent winding before simplification (preprocess/consistent_winding.h): flipped faces of
// closed pieces are turned back and inside-out pieces turned outward, open pieces keep the
// orientation most of their area has, non-manifold edges and non-orientable strips do not break it,
// bad indices are left alone, and a capped pipe whose caps were wound inward simplifies further
// once turned (the reason the preprocessor turns them).
#include <gtest/gtest.h>
#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>

#include "closed_surface.h"
#include "consistent_winding.h"
#include "exact_weld.h"
#include "tessellate.h"

namespace tw {
namespace {

// An axis-aligned unit cube with shared corners, counter-clockwise seen from outside.
TriangleMesh cube() {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i) m.positions.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  const uint32_t kQuads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                 {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : kQuads)
    m.indices.insert(m.indices.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  return m;
}

// A flat strip of `quads` unit squares along x, facing +z.
TriangleMesh strip(uint32_t quads) {
  TriangleMesh m;
  for (uint32_t i = 0; i <= quads; ++i) {
    m.positions.emplace_back(float(i), 0.0f, 0.0f);
    m.positions.emplace_back(float(i), 1.0f, 0.0f);
  }
  for (uint32_t i = 0; i < quads; ++i) {
    const uint32_t a = 2 * i, b = 2 * i + 2, c = 2 * i + 3, d = 2 * i + 1;
    m.indices.insert(m.indices.end(), {a, b, c, a, c, d});
  }
  return m;
}

void turn(TriangleMesh& m, uint32_t triangle) {
  std::swap(m.indices[3 * triangle + 1], m.indices[3 * triangle + 2]);
}

TEST(ConsistentWinding, ConsistentClosedPieceIsLeftAlone) {
  WindingReport r;
  EXPECT_TRUE(trianglesToTurn(cube(), &r).empty());
  EXPECT_EQ(r.triangles, 12u);
  EXPECT_EQ(r.pieces, 1u);
  EXPECT_EQ(r.conflicts, 0u);
}

TEST(ConsistentWinding, FlippedFaceOfAClosedPieceIsTurnedBack) {
  TriangleMesh m = cube();
  turn(m, 4);
  turn(m, 5);
  ASSERT_FALSE(checkClosedSurface(m).enclosesSolid());
  WindingReport r;
  const std::vector<uint32_t> t = trianglesToTurn(m, &r);
  EXPECT_EQ(t, (std::vector<uint32_t>{4, 5}));
  EXPECT_EQ(r.turned, 2u);
  turnTriangles(m, t);
  EXPECT_TRUE(checkClosedSurface(m).enclosesSolid());
}

TEST(ConsistentWinding, InsideOutClosedPieceIsTurnedOutward) {
  // Ten of twelve triangles inward: the volume decides, not the majority.
  TriangleMesh m = cube();
  for (uint32_t t = 0; t < 10; ++t) turn(m, t);
  const std::vector<uint32_t> t = trianglesToTurn(m);
  EXPECT_EQ(t.size(), 10u);
  turnTriangles(m, t);
  EXPECT_TRUE(checkClosedSurface(m).enclosesSolid());
}

TEST(ConsistentWinding, OpenPieceKeepsTheOrientationOfMostOfItsArea) {
  TriangleMesh m = strip(4);
  turn(m, 3);
  EXPECT_EQ(trianglesToTurn(m), (std::vector<uint32_t>{3}));
  // Most of it flipped: the few that were right are the ones turned.
  TriangleMesh n = strip(4);
  for (uint32_t t = 0; t < 8; ++t)
    if (t != 2 && t != 6) turn(n, t);
  EXPECT_EQ(trianglesToTurn(n), (std::vector<uint32_t>{2, 6}));
}

TEST(ConsistentWinding, PiecesAreOrientedEachOnItsOwn) {
  // Two cubes apart, the second inside out: one piece each, and only the second is turned.
  TriangleMesh m = cube();
  TriangleMesh second = cube();
  for (uint32_t t = 0; t < 12; ++t) turn(second, t);
  for (const TriangleMesh* part : {&second}) {
    const uint32_t base = static_cast<uint32_t>(m.positions.size());
    for (const glm::vec3& p : part->positions) m.positions.push_back(p + glm::vec3(3, 0, 0));
    for (uint32_t i : part->indices) m.indices.push_back(base + i);
  }
  WindingReport r;
  const std::vector<uint32_t> t = trianglesToTurn(m, &r);
  EXPECT_EQ(r.pieces, 2u);
  ASSERT_EQ(t.size(), 12u);
  EXPECT_EQ(t.front(), 12u);
  EXPECT_EQ(t.back(), 23u);
}

TEST(ConsistentWinding, NonManifoldEdgesDoNotJoinPieces) {
  // Three fins on one edge, the third wound the other way: no edge is shared by exactly two, so
  // each fin is its own open piece and keeps its winding.
  TriangleMesh m;
  m.positions = {{0, 0, 0}, {0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {-1, -1, 0}};
  m.indices = {0, 1, 2, 0, 1, 3, 1, 0, 4};
  WindingReport r;
  EXPECT_TRUE(trianglesToTurn(m, &r).empty());
  EXPECT_EQ(r.pieces, 3u);
}

TEST(ConsistentWinding, MoebiusStripIsCountedAsAConflict) {
  // A strip of 12 quads around a circle with a half twist: it cannot be oriented.
  TriangleMesh m;
  const uint32_t n = 12;
  for (uint32_t i = 0; i < n; ++i) {
    const float a = 6.2831853f * float(i) / float(n), twist = 0.5f * a;
    const glm::vec3 centre(std::cos(a), std::sin(a), 0.0f);
    const glm::vec3 across =
        0.3f * (std::cos(twist) * centre + std::sin(twist) * glm::vec3(0, 0, 1));
    m.positions.push_back(centre - across);
    m.positions.push_back(centre + across);
  }
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t a = 2 * i, b = 2 * i + 1;
    // The last quad joins the first with its sides swapped.
    const uint32_t c = i + 1 < n ? 2 * i + 2 : 1, d = i + 1 < n ? 2 * i + 3 : 0;
    m.indices.insert(m.indices.end(), {a, c, d, a, d, b});
  }
  WindingReport r;
  trianglesToTurn(m, &r);
  EXPECT_EQ(r.pieces, 1u);
  EXPECT_GE(r.conflicts, 1u);
}

TEST(ConsistentWinding, BadAndDegenerateTrianglesAreLeftAlone) {
  TriangleMesh m = cube();
  turn(m, 0);
  m.indices.insert(m.indices.end(), {0, 0, 1, 2, 3, 99});  // repeated vertex, out of range
  m.indices.push_back(5);                                  // a trailing partial triangle
  WindingReport r;
  const std::vector<uint32_t> t = trianglesToTurn(m, &r);
  EXPECT_EQ(r.triangles, 12u);
  EXPECT_EQ(t, (std::vector<uint32_t>{0}));
  // Triangle 14 would need indices 42-44 of 43 (a partial triangle), 1000 is past the end.
  turnTriangles(m, {0, 14, 1000});
  ASSERT_EQ(m.indices.size(), 43u);
  EXPECT_EQ(m.indices[42], 5u);
  EXPECT_TRUE(std::equal(m.indices.begin(), m.indices.begin() + 36, cube().indices.begin()));
  EXPECT_TRUE(trianglesToTurn(TriangleMesh{}).empty());
}

// Triangles meshopt_simplify keeps of a welded mesh at a 1 % target and an error of 5 % of its
// size.
size_t simplifiedTriangles(const TriangleMesh& mesh) {
  const WeldedTriangles w = weldExactly(mesh);
  std::vector<uint32_t> indices;
  for (const auto& t : w.triangles) indices.insert(indices.end(), t.begin(), t.end());
  std::vector<uint32_t> out(indices.size());
  const size_t count =
      meshopt_simplify(out.data(), indices.data(), indices.size(), &w.points[0].x, w.points.size(),
                       sizeof(glm::vec3), indices.size() / 100, 0.05f, 0, nullptr);
  return count / 3;
}

TEST(ConsistentWinding, CappedPipeWithInwardCapsSimplifiesFurtherOnceTurned) {
  TriangleMesh pipe;
  tessellatePrimitive(Cylinder{0.5f, 4.0f, true}, 0.0005f, pipe);
  // Wind the caps (triangles whose corners share one height) inward.
  TriangleMesh flipped = pipe;
  uint32_t caps = 0;
  for (uint32_t t = 0; 3 * t + 2 < flipped.indices.size(); ++t) {
    const float z0 = flipped.positions[flipped.indices[3 * t]].z;
    if (flipped.positions[flipped.indices[3 * t + 1]].z == z0 &&
        flipped.positions[flipped.indices[3 * t + 2]].z == z0) {
      turn(flipped, t);
      ++caps;
    }
  }
  ASSERT_GT(caps, 0u);
  TriangleMesh turned = flipped;
  turnTriangles(turned, trianglesToTurn(flipped));
  EXPECT_TRUE(checkClosedSurface(turned).enclosesSolid());
  const size_t before = simplifiedTriangles(flipped), after = simplifiedTriangles(turned);
  EXPECT_LT(after * 2, before) << "inward caps " << before << ", turned " << after;
}

}  // namespace
}  // namespace tw
