// The closed-surface test behind back-face culling (preprocess/closed_surface.h): closed and
// outward boxes and spheres pass, also with split vertices and overlapping pieces; holes,
// flipped triangles, inside-out pieces and flat double-sided sheets fail; the generated plant's
// equipment meshes pass.
#include <gtest/gtest.h>

#include <algorithm>

#include "closed_surface.h"
#include "plant_parts.h"
#include "tessellate.h"

namespace tw {
namespace {

// An axis-aligned box, counter-clockwise seen from outside, four vertices per face (as a mesh
// with hard normals comes).
TriangleMesh splitBox(const glm::vec3& lo, const glm::vec3& hi) {
  TriangleMesh m;
  auto corner = [&](int i) {
    return glm::vec3((i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z);
  };
  // Faces as corner quads, counter-clockwise from outside.
  const int kQuads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                            {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : kQuads) {
    const uint32_t base = static_cast<uint32_t>(m.positions.size());
    for (int k = 0; k < 4; ++k) m.positions.push_back(corner(q[k]));
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  }
  return m;
}

void append(TriangleMesh& to, const TriangleMesh& from) {
  const uint32_t base = static_cast<uint32_t>(to.positions.size());
  to.positions.insert(to.positions.end(), from.positions.begin(), from.positions.end());
  for (uint32_t i : from.indices) to.indices.push_back(base + i);
}

void flipAll(TriangleMesh& m) {
  for (size_t t = 0; t + 2 < m.indices.size(); t += 3) std::swap(m.indices[t + 1], m.indices[t + 2]);
}

TEST(ClosedSurface, BoxWithSplitVerticesEnclosesASolid) {
  const ClosedSurfaceReport r = checkClosedSurface(splitBox(glm::vec3(0.0f), glm::vec3(1, 2, 3)));
  EXPECT_TRUE(r.enclosesSolid());
  EXPECT_EQ(r.triangles, 12u);
  EXPECT_EQ(r.components, 1u);
  EXPECT_EQ(r.unpaired_edges, 0u);
}

TEST(ClosedSurface, TessellatedPrimitivesEncloseSolids) {
  for (const Primitive& p : {Primitive{Sphere{0.5f}}, Primitive{Box{{1.0f, 0.2f, 0.3f}}},
                             Primitive{Cylinder{0.3f, 2.0f, true}}}) {
    TriangleMesh m;
    tessellatePrimitive(p, 0.001f, m);
    EXPECT_TRUE(checkClosedSurface(m).enclosesSolid()) << p.index();
  }
  TriangleMesh open_pipe;
  tessellatePrimitive(Cylinder{0.3f, 2.0f, false}, 0.001f, open_pipe);
  const ClosedSurfaceReport r = checkClosedSurface(open_pipe);
  EXPECT_FALSE(r.enclosesSolid());
  EXPECT_GT(r.unpaired_edges, 0u);
}

TEST(ClosedSurface, OverlappingPiecesEachClosedPass) {
  TriangleMesh m = splitBox(glm::vec3(0.0f), glm::vec3(2.0f));
  append(m, splitBox(glm::vec3(1.0f), glm::vec3(3.0f)));  // intersects the first
  const ClosedSurfaceReport r = checkClosedSurface(m);
  EXPECT_TRUE(r.enclosesSolid());
  EXPECT_EQ(r.components, 2u);
}

TEST(ClosedSurface, HolesFlipsAndInsideOutPiecesFail) {
  TriangleMesh hole = splitBox(glm::vec3(0.0f), glm::vec3(1.0f));
  hole.indices.resize(hole.indices.size() - 3);  // one triangle missing
  EXPECT_FALSE(checkClosedSurface(hole).enclosesSolid());
  EXPECT_EQ(checkClosedSurface(hole).unpaired_edges, 3u);

  TriangleMesh flipped_one = splitBox(glm::vec3(0.0f), glm::vec3(1.0f));
  std::swap(flipped_one.indices[1], flipped_one.indices[2]);
  EXPECT_FALSE(checkClosedSurface(flipped_one).enclosesSolid());

  TriangleMesh inside_out = splitBox(glm::vec3(0.0f), glm::vec3(1.0f));
  flipAll(inside_out);
  ClosedSurfaceReport r = checkClosedSurface(inside_out);
  EXPECT_EQ(r.unpaired_edges, 0u);
  EXPECT_EQ(r.inward_components, 1u);
  EXPECT_FALSE(r.enclosesSolid());

  // One good piece does not excuse an inside-out one beside it.
  TriangleMesh mixed = splitBox(glm::vec3(5.0f), glm::vec3(6.0f));
  append(mixed, inside_out);
  r = checkClosedSurface(mixed);
  EXPECT_EQ(r.components, 2u);
  EXPECT_EQ(r.inward_components, 1u);
  EXPECT_FALSE(r.enclosesSolid());
}

TEST(ClosedSurface, FlatDoubleSidedSheetFails) {
  // Two triangles back to back: every edge is used once each way, but nothing is enclosed, and
  // culling would hide the sheet from one side.
  TriangleMesh sheet;
  sheet.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  sheet.indices = {0, 1, 2, 0, 2, 1};
  const ClosedSurfaceReport r = checkClosedSurface(sheet);
  EXPECT_EQ(r.unpaired_edges, 0u);
  EXPECT_FALSE(r.enclosesSolid());
}

TEST(ClosedSurface, EmptyOrDegenerateMeshFails) {
  EXPECT_FALSE(checkClosedSurface(TriangleMesh{}).enclosesSolid());
  TriangleMesh bad = splitBox(glm::vec3(0.0f), glm::vec3(1.0f));
  bad.indices.push_back(0);
  bad.indices.push_back(0);
  bad.indices.push_back(1);  // a repeated vertex
  EXPECT_FALSE(checkClosedSurface(bad).enclosesSolid());
  bad.indices.back() = 9999;  // out of range
  EXPECT_FALSE(checkClosedSurface(bad).enclosesSolid());
}

// The generated plant's rotating equipment comes as meshes of overlapping closed parts; all of
// them face outward, so the runtime may cull their back faces.
TEST(ClosedSurface, PlantEquipmentMeshesEncloseSolids) {
  const plant::EquipmentTemplates templates;
  for (const SceneObject* object : {&templates.pump, &templates.compressor}) {
    const ClosedSurfaceReport r = checkClosedSurface(std::get<TriangleMesh>(object->geometry));
    EXPECT_TRUE(r.enclosesSolid()) << object->info.name << ": unpaired " << r.unpaired_edges
                                   << " inward " << r.inward_components << " of "
                                   << r.components << " skipped " << r.skipped;
    EXPECT_GT(r.components, 10u);
  }
}

}  // namespace
}  // namespace tw
