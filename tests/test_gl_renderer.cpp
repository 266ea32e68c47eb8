// The GL geometry pool and mesh renderer on llvmpipe: coverage and background, object ids per
// triangle (gl_PrimitiveID inside multi-draws), reversed-Z depth, eye-relative precision at plant
// coordinates, colours, backface flag, stats and timer, bounds checks, and a real bunny package
// decoded into the pool by hand.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>
#include <thread>
#include <vector>

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>
#include <glm/gtc/matrix_transform.hpp>

#include "bunny_package_support.h"
#include "egl_context.h"
#include "geometry_pool.h"
#include "gl_renderer.h"
#include "image_compare.h"
#include "package_view.h"
#include "pager.h"
#include "test_support.h"
#include "vertex_object_tags.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 128;
constexpr int kHeight = 96;
constexpr double kFovY = 1.0471975511965976;  // 60 degrees
// 2^-13 m: the finest cell; 16-bit grid units then span 8 m (larger clusters use coarser cells).
constexpr double kCellM = 1.0 / 8192.0;

// A camera for tests, independent of camera.cpp: eye in world metres and a look direction.
struct TestView {
  glm::dvec3 eye{0.0};
  glm::dvec3 forward{1.0, 0.0, 0.0};
  double near_m = 0.1, far_m = 1000.0;

  glm::mat4 rotation() const {
    return glm::mat4(glm::lookAt(glm::dvec3(0.0), forward, glm::dvec3(0.0, 0.0, 1.0)));
  }
  // Reversed Z: perspectiveRH_ZO maps its first plane to depth 0, so far goes first.
  glm::mat4 projection() const {
    return glm::mat4(
        glm::perspectiveRH_ZO(kFovY, double(kWidth) / kHeight, far_m, near_m));
  }
  // Image position (x right, y down, pixels) of a world point.
  glm::dvec2 project(const glm::dvec3& world) const {
    glm::dvec4 clip = glm::dmat4(projection()) * glm::dmat4(rotation()) *
                      glm::dvec4(world - eye, 1.0);
    glm::dvec2 ndc(clip.x / clip.w, clip.y / clip.w);
    return {(ndc.x * 0.5 + 0.5) * kWidth, (0.5 - ndc.y * 0.5) * kHeight};
  }
};

// Builds one page by hand: clusters appended one after the other, positions quantized the way
// the package does (grid origin + 16-bit units of kCellM, relative to a package origin).
class PoolBuilder {
 public:
  explicit PoolBuilder(glm::dvec3 origin = glm::dvec3(0.0)) : origin_(origin) {}

  // positions: world metres; indices: cluster-local; objects: one per triangle.
  size_t addCluster(const std::vector<glm::dvec3>& world, const std::vector<uint16_t>& indices,
                    const std::vector<uint32_t>& objects) {
    glm::dvec3 lo(1e300), hi(-1e300);
    for (const auto& p : world) lo = glm::min(lo, p - origin_), hi = glm::max(hi, p - origin_);
    // The package's rule: the smallest power-of-two cell that fits the extent in 16 bits.
    uint32_t shift = 0;
    const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    while (extent / (kCellM * std::ldexp(1.0, static_cast<int>(shift))) > 65000.0) ++shift;
    GpuCluster c;
    c.first_vertex = upload_.vertices.size();
    c.first_index = upload_.indices.size();
    c.first_triangle = upload_.triangle_objects.size();
    c.vertex_count = static_cast<uint32_t>(world.size());
    c.triangle_count = static_cast<uint32_t>(indices.size() / 3);
    c.shift = shift;
    c.cell_m = kCellM * std::ldexp(1.0, static_cast<int>(shift));
    c.grid_origin = glm::ivec3(glm::floor(lo / c.cell_m));
    for (const auto& p : world) {
      glm::dvec3 q = glm::round((p - origin_) / c.cell_m - glm::dvec3(c.grid_origin));
      EXPECT_TRUE(q.x >= 0 && q.y >= 0 && q.z >= 0 && q.x < 65536 && q.y < 65536 && q.z < 65536);
      pkg::EncodedVertex v{};
      v.q[0] = static_cast<uint16_t>(q.x);
      v.q[1] = static_cast<uint16_t>(q.y);
      v.q[2] = static_cast<uint16_t>(q.z);
      upload_.vertices.push_back(v);
    }
    upload_.indices.insert(upload_.indices.end(), indices.begin(), indices.end());
    upload_.triangle_objects.insert(upload_.triangle_objects.end(), objects.begin(),
                                    objects.end());
    const std::span<const uint32_t> all_objects(upload_.triangle_objects);
    c.object_per_triangle = tagVertexObjects(std::span(upload_.vertices).subspan(c.first_vertex),
                                             std::span(upload_.indices).subspan(c.first_index),
                                             all_objects.subspan(c.first_triangle)) > 0;
    clusters_.push_back(c);
    return clusters_.size() - 1;
  }

  // A quad facing a camera that looks along +X (counter-clockwise on screen), at x = depth,
  // centred on (y, z), one object for both triangles.
  size_t addQuad(double depth, double y, double z, double half_w, double half_h, uint32_t object) {
    return addQuads({{depth, y, z, half_w, half_h, object}});
  }
  struct Quad {
    double depth, y, z, half_w, half_h;
    uint32_t object;
  };
  size_t addQuads(const std::vector<Quad>& quads) {
    std::vector<glm::dvec3> world;
    std::vector<uint16_t> indices;
    std::vector<uint32_t> objects;
    for (const Quad& q : quads) {
      auto base = static_cast<uint16_t>(world.size());
      // Screen x is world -y for this camera.
      world.push_back(origin_ + glm::dvec3(q.depth, q.y + q.half_w, q.z - q.half_h));
      world.push_back(origin_ + glm::dvec3(q.depth, q.y - q.half_w, q.z - q.half_h));
      world.push_back(origin_ + glm::dvec3(q.depth, q.y - q.half_w, q.z + q.half_h));
      world.push_back(origin_ + glm::dvec3(q.depth, q.y + q.half_w, q.z + q.half_h));
      for (int k : {0, 1, 2, 0, 2, 3}) indices.push_back(static_cast<uint16_t>(base + k));
      objects.insert(objects.end(), {q.object, q.object});
    }
    return addCluster(world, indices, objects);
  }

  std::unique_ptr<GeometryPool> makePool() {
    PoolLayout layout;
    layout.vertices = upload_.vertices.size() + 16;
    layout.indices = upload_.indices.size() + 16;
    layout.triangles = upload_.triangle_objects.size() + 16;
    auto pool = std::make_unique<GeometryPool>(layout);
    EXPECT_EQ(pool->upload(upload_), upload_.bytes());
    return pool;
  }

  // Draw items for the given clusters (all when empty), offsets computed in double.
  std::vector<DrawItem> items(const glm::dvec3& eye, std::vector<size_t> which = {}) const {
    if (which.empty())
      for (size_t i = 0; i < clusters_.size(); ++i) which.push_back(i);
    std::vector<DrawItem> out;
    for (size_t i : which) {
      DrawItem item;
      item.placement = clusters_[i];
      item.offset_eye =
          glm::vec3(glm::dvec3(clusters_[i].grid_origin) * clusters_[i].cell_m + origin_ - eye);
      out.push_back(item);
    }
    return out;
  }

  const std::vector<GpuCluster>& clusters() const { return clusters_; }
  const PageUpload& upload() const { return upload_; }
  glm::dvec3 origin() const { return origin_; }

 private:
  glm::dvec3 origin_;
  PageUpload upload_;
  std::vector<GpuCluster> clusters_;
};

struct Frame {
  std::vector<uint8_t> rgba;
  std::vector<uint32_t> ids;
  RenderStats stats;
  uint32_t id(int x, int y) const { return ids[static_cast<size_t>(y) * kWidth + x]; }
  const uint8_t* pixel(int x, int y) const {
    return &rgba[(static_cast<size_t>(y) * kWidth + x) * 4];
  }
};

Frame render(GlRenderer& renderer, const GeometryPool& pool, const TestView& view,
             const std::vector<DrawItem>& items) {
  Frame frame;
  renderer.beginFrame(view.rotation(), view.projection());
  renderer.draw(pool, items);
  frame.stats = renderer.endFrame();
  renderer.readColor(frame.rgba);
  renderer.readObjectIds(frame.ids);
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  return frame;
}

RendererOptions smallOptions() {
  RendererOptions options;
  options.width = kWidth;
  options.height = kHeight;
  return options;
}

// The background colour as RGBA8 reads it back.
void expectBackground(const uint8_t* p, const RendererOptions& options) {
  EXPECT_NEAR(p[0], options.background.r * 255.0f, 1.0f);
  EXPECT_NEAR(p[1], options.background.g * 255.0f, 1.0f);
  EXPECT_NEAR(p[2], options.background.b * 255.0f, 1.0f);
}

// Grey lit by the slightly blue sky light: channels within a few levels of each other.
void expectGreyish(const uint8_t* p) {
  EXPECT_LE(std::abs(int(p[0]) - int(p[1])), 8) << int(p[0]) << " " << int(p[1]);
  EXPECT_LE(std::abs(int(p[1]) - int(p[2])), 8) << int(p[1]) << " " << int(p[2]);
  EXPECT_GT(p[0], 40);
  EXPECT_LT(p[0], 250);
}

class GlRendererTest : public ::testing::Test {
 protected:
  EglContext context_;
};

TEST_F(GlRendererTest, CoversTheProjectedQuadAndLeavesTheBackground) {
  PoolBuilder builder;
  builder.addQuad(10.0, 0.0, 0.0, 2.0, 1.5, 6);
  auto pool = builder.makePool();
  GlRenderer renderer(smallOptions());
  TestView view;
  Frame frame = render(renderer, *pool, view, builder.items(view.eye));

  // The quad's image rectangle, from the same projection in double.
  glm::dvec2 a = view.project({10.0, 2.0, 1.5}), b = view.project({10.0, -2.0, -1.5});
  int covered = 0, mismatched = 0;
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const double cx = x + 0.5, cy = y + 0.5;
      const bool inside = cx > a.x && cx < b.x && cy > a.y && cy < b.y;
      const bool near_edge = std::abs(cx - a.x) < 1 || std::abs(cx - b.x) < 1 ||
                             std::abs(cy - a.y) < 1 || std::abs(cy - b.y) < 1;
      const uint32_t id = frame.id(x, y);
      EXPECT_TRUE(id == 0 || id == 7) << id;
      covered += id != 0;
      if (!near_edge && (id == 7) != inside) ++mismatched;
    }
  EXPECT_EQ(mismatched, 0);
  const double expected = (b.x - a.x) * (b.y - a.y);
  EXPECT_NEAR(covered, expected, 0.03 * expected);
  EXPECT_GT(covered, 500);

  // Background colour and id 0 outside; a lit, non-background colour inside.
  expectBackground(frame.pixel(0, 0), smallOptions());
  expectBackground(frame.pixel(kWidth - 1, kHeight - 1), smallOptions());
  EXPECT_EQ(frame.id(0, 0), 0u);
  const uint8_t* centre = frame.pixel(kWidth / 2, kHeight / 2);
  EXPECT_EQ(frame.id(kWidth / 2, kHeight / 2), 7u);
  EXPECT_GT(std::abs(centre[2] - smallOptions().background.b * 255.0f), 10.0f);
  expectGreyish(centre);  // no colour set
}

TEST_F(GlRendererTest, ObjectIdsFollowTrianglesAcrossClustersOfOneMultiDraw) {
  PoolBuilder builder;
  builder.addQuad(10.0, 4.0, 0.0, 1.0, 1.0, 0);  // left on screen (screen x is -y)
  // One cluster with three quads of different objects: the second and third need
  // gl_PrimitiveID and the cluster's first_triangle (here 2, not 0).
  builder.addQuads({{10.0, 0.0, 0.0, 1.0, 1.0, 5},
                    {10.0, -4.0, 0.0, 1.0, 1.0, 9},
                    {10.0, 0.0, -3.5, 1.0, 1.0, 11}});
  builder.addQuad(10.0, -4.0, -3.5, 1.0, 1.0, 2);
  auto pool = builder.makePool();
  GlRenderer renderer(smallOptions());
  TestView view;
  Frame frame = render(renderer, *pool, view, builder.items(view.eye));
  EXPECT_EQ(frame.stats.draws, 3u);
  EXPECT_EQ(frame.stats.triangles, 10u);
  auto idAt = [&](double y, double z) {
    glm::dvec2 p = view.project({10.0, y, z});
    return frame.id(static_cast<int>(p.x), static_cast<int>(p.y));
  };
  EXPECT_EQ(idAt(4.0, 0.0), 1u);
  EXPECT_EQ(idAt(0.0, 0.0), 6u);
  EXPECT_EQ(idAt(-4.0, 0.0), 10u);
  EXPECT_EQ(idAt(0.0, -3.5), 12u);
  EXPECT_EQ(idAt(-4.0, -3.5), 3u);
  EXPECT_EQ(idAt(2.0, 2.0), 0u);
}

TEST_F(GlRendererTest, TriangleWhoseVerticesObjectsShareTakesItsOwnObjectAndColour) {
  // A middle triangle of object 4 whose three corners are each shared with an outer triangle of
  // object 6: no corner is its own, so its fragments look its object up per triangle, while the
  // outer ones take theirs flat from their own vertex (vertex_object_tags.h).
  PoolBuilder builder;
  auto at = [](double y, double z) { return glm::dvec3(10.0, y, z); };
  const std::vector<glm::dvec3> world = {at(2.0, -1.5), at(-2.0, -1.5), at(0.0, 2.0),  // middle
                                         at(0.0, -4.0), at(-3.5, 1.5), at(3.5, 1.5)};   // outer
  // Counter-clockwise on screen (screen x is -y): the middle, then one outer triangle per edge.
  const size_t cluster =
      builder.addCluster(world, {0, 1, 2, 0, 3, 1, 1, 4, 2, 2, 5, 0}, {4, 6, 6, 6});
  ASSERT_TRUE(builder.clusters()[cluster].object_per_triangle)
      << "the middle triangle must need the per-triangle look-up";
  auto pool = builder.makePool();
  GlRenderer renderer(smallOptions());
  std::vector<uint32_t> colors(7, 0u);
  colors[4] = 0xff0000ffu;  // red
  colors[6] = 0xffff0000u;  // blue
  renderer.setObjectColors(colors);
  TestView view;
  Frame frame = render(renderer, *pool, view, builder.items(view.eye));
  auto pixelAt = [&](double y, double z) {
    glm::dvec2 p = view.project({10.0, y, z});
    return std::pair(frame.id(static_cast<int>(p.x), static_cast<int>(p.y)),
                     frame.pixel(static_cast<int>(p.x), static_cast<int>(p.y)));
  };
  const auto [middle_id, middle] = pixelAt(0.0, -0.3);
  EXPECT_EQ(middle_id, 5u);
  EXPECT_GT(middle[0], 100);
  EXPECT_LT(middle[2], 10);
  for (const glm::dvec2& outer :
       {glm::dvec2(0.0, -2.5), glm::dvec2(-2.0, 1.0), glm::dvec2(2.0, 1.0)}) {
    const auto [id, rgba] = pixelAt(outer.x, outer.y);
    EXPECT_EQ(id, 7u) << outer.x << ", " << outer.y;
    EXPECT_LT(rgba[0], 10);
    EXPECT_GT(rgba[2], 100);
  }
}

TEST_F(GlRendererTest, NearerSurfaceWinsWhateverTheDrawOrder) {
  PoolBuilder builder;
  size_t far_quad = builder.addQuad(20.0, 0.0, 0.0, 6.0, 4.0, 1);
  size_t near_quad = builder.addQuad(8.0, 0.0, 0.0, 1.0, 1.0, 2);
  // Nearly coplanar pair far away: 5 cm apart at 400 m, which reversed-Z float depth resolves.
  size_t distant_back = builder.addQuad(400.0, 0.0, 100.0, 20.0, 20.0, 3);
  size_t distant_front = builder.addQuad(399.95, 0.0, 100.0, 20.0, 20.0, 4);
  auto pool = builder.makePool();
  GlRenderer renderer(smallOptions());
  TestView view;
  view.near_m = 0.05;
  view.far_m = 20000.0;
  glm::dvec2 centre = view.project({8.0, 0.0, 0.0});
  glm::dvec2 distant = view.project({400.0, 0.0, 100.0});
  for (bool near_first : {false, true}) {
    std::vector<size_t> order = near_first
                                    ? std::vector<size_t>{near_quad, far_quad, distant_front,
                                                          distant_back}
                                    : std::vector<size_t>{far_quad, near_quad, distant_back,
                                                          distant_front};
    Frame frame = render(renderer, *pool, view, builder.items(view.eye, order));
    EXPECT_EQ(frame.id(static_cast<int>(centre.x), static_cast<int>(centre.y)), 3u)
        << "near first: " << near_first;
    EXPECT_EQ(frame.id(static_cast<int>(distant.x), static_cast<int>(distant.y)), 5u)
        << "near first: " << near_first;
    glm::dvec2 side = view.project({20.0, 4.0, 0.0});
    EXPECT_EQ(frame.id(static_cast<int>(side.x), static_cast<int>(side.y)), 2u);
  }
}

TEST_F(GlRendererTest, PlantCoordinatesRenderLikeTheOriginThanksToEyeRelativeOffsets) {
  // Edges and eye at positions that are not multiples of the 0.5 m float step at 7e6 m.
  const glm::dvec3 plant(500000.0, 7000000.0, 0.0);
  const glm::dvec3 eye_local(0.3, 0.17, 0.11);
  auto build = [](PoolBuilder& b) {
    b.addQuads({{10.0, 0.37, 0.21, 1.23, 0.91, 0}, {12.0, -2.13, -0.77, 0.61, 1.37, 1}});
    b.addQuads({{9.0, 2.71, -1.93, 0.33, 0.29, 2}});
  };
  PoolBuilder near_builder;
  build(near_builder);
  PoolBuilder far_builder(plant);
  build(far_builder);
  auto near_pool = near_builder.makePool();
  auto far_pool = far_builder.makePool();
  GlRenderer renderer(smallOptions());
  TestView near_view, far_view;
  near_view.eye = eye_local;
  near_view.forward = glm::normalize(glm::dvec3(1.0, -0.05, 0.03));
  far_view = near_view;
  far_view.eye = plant + eye_local;
  Frame near_frame = render(renderer, *near_pool, near_view, near_builder.items(near_view.eye));
  Frame far_frame = render(renderer, *far_pool, far_view, far_builder.items(far_view.eye));
  EXPECT_GT(std::count(near_frame.ids.begin(), near_frame.ids.end(), 1u), 200);
  EXPECT_GT(std::count(near_frame.ids.begin(), near_frame.ids.end(), 3u), 10);
  EXPECT_TRUE(near_frame.ids == far_frame.ids) << "ids differ far from the origin";
  EXPECT_TRUE(near_frame.rgba == far_frame.rgba) << "colours differ far from the origin";

  // The control: offsets computed in float, as a naive renderer would, move the image.
  std::vector<DrawItem> naive = far_builder.items(far_view.eye);
  for (size_t i = 0; i < naive.size(); ++i) {
    const GpuCluster& c = far_builder.clusters()[i];
    glm::vec3 cluster_world = glm::vec3(glm::dvec3(c.grid_origin) * c.cell_m + plant);
    naive[i].offset_eye = cluster_world - glm::vec3(far_view.eye);
  }
  Frame naive_frame = render(renderer, *far_pool, far_view, naive);
  EXPECT_FALSE(naive_frame.ids == near_frame.ids) << "the precision test has no teeth";
}

TEST_F(GlRendererTest, ColoursComeFromTheObjectTableWithGreyForUnsetAndMissing) {
  PoolBuilder builder;
  builder.addQuads({{10.0, 4.0, 0.0, 1.5, 1.5, 0},
                    {10.0, 0.0, 0.0, 1.5, 1.5, 1},
                    {10.0, -4.0, 0.0, 1.5, 1.5, 2},
                    {10.0, 0.0, -3.5, 1.5, 1.0, 7}});
  auto pool = builder.makePool();
  GlRenderer renderer(smallOptions());
  renderer.setObjectColors(std::vector<uint32_t>{0xff0000ffu, 0xffff0000u, 0u});  // red, blue, unset
  TestView view;
  Frame frame = render(renderer, *pool, view, builder.items(view.eye));
  auto at = [&](double y, double z) {
    glm::dvec2 p = view.project({10.0, y, z});
    return frame.pixel(static_cast<int>(p.x), static_cast<int>(p.y));
  };
  const uint8_t* red = at(4.0, 0.0);
  EXPECT_GT(red[0], 100);
  EXPECT_LT(red[1], 10);
  EXPECT_LT(red[2], 10);
  const uint8_t* blue = at(0.0, 0.0);
  EXPECT_LT(blue[0], 10);
  EXPECT_LT(blue[1], 10);
  EXPECT_GT(blue[2], 100);
  for (const uint8_t* grey : {at(-4.0, 0.0), at(0.0, -3.5)}) {  // colour 0 and beyond the table
    expectGreyish(grey);
  }
  // Lighting: same colour, different orientation, different shade would need another face; at
  // least the lit red is not saturated black or white.
  EXPECT_LT(red[0], 255);

  // Clearing the table makes everything grey.
  renderer.setObjectColors({});
  frame = render(renderer, *pool, view, builder.items(view.eye));
  expectGreyish(at(4.0, 0.0));
}

TEST_F(GlRendererTest, FacesAreShadedByOrientation) {
  // Two faces of a box corner seen from above at an angle: the face toward the sun and sky is
  // brighter than the vertical one facing away from the sun.
  PoolBuilder builder;
  const double s = 2.0;
  std::vector<glm::dvec3> world = {{10, -s, 0}, {10, s, 0}, {10 + 2 * s, s, 0}, {10 + 2 * s, -s, 0},
                                   {10, -s, -2 * s}, {10, s, -2 * s}};
  // Top face (z = 0) and front face (x = 10, facing -x, away from the sun at +x).
  builder.addCluster(world, {0, 1, 2, 0, 2, 3, 4, 5, 1, 4, 1, 0}, {0, 0, 1, 1});
  auto pool = builder.makePool();
  GlRenderer renderer(smallOptions());
  TestView view;
  view.eye = {0.0, 0.0, 6.0};
  view.forward = glm::normalize(glm::dvec3(10.0, 0.0, -7.0));
  Frame frame = render(renderer, *pool, view, builder.items(view.eye));
  glm::dvec2 top = view.project({10 + s, 0, 0}), front = view.project({10, 0, -s});
  const uint8_t* t = frame.pixel(static_cast<int>(top.x), static_cast<int>(top.y));
  const uint8_t* f = frame.pixel(static_cast<int>(front.x), static_cast<int>(front.y));
  EXPECT_EQ(frame.id(static_cast<int>(top.x), static_cast<int>(top.y)), 1u);
  EXPECT_EQ(frame.id(static_cast<int>(front.x), static_cast<int>(front.y)), 2u);
  EXPECT_GT(int(t[0]), int(f[0]) + 20);
}

TEST_F(GlRendererTest, BackfaceCullingIsOffByDefaultAndCanBeTurnedOn) {
  PoolBuilder builder;
  builder.addQuad(10.0, 2.0, 0.0, 1.0, 1.0, 0);  // facing the camera
  // The same quad reversed: seen from its back.
  builder.addCluster({{10, -1, -1}, {10, -3, -1}, {10, -3, 1}, {10, -1, 1}}, {0, 2, 1, 0, 3, 2},
                     {1, 1});
  auto pool = builder.makePool();
  GlRenderer renderer(smallOptions());
  TestView view;
  glm::dvec2 front = view.project({10, 2, 0}), back = view.project({10, -2, 0});
  Frame frame = render(renderer, *pool, view, builder.items(view.eye));
  EXPECT_EQ(frame.id(static_cast<int>(front.x), static_cast<int>(front.y)), 1u);
  EXPECT_EQ(frame.id(static_cast<int>(back.x), static_cast<int>(back.y)), 2u);
  // Two-sided lighting: the back face is lit like the front one.
  const uint8_t* pf = frame.pixel(static_cast<int>(front.x), static_cast<int>(front.y));
  const uint8_t* pb = frame.pixel(static_cast<int>(back.x), static_cast<int>(back.y));
  EXPECT_NEAR(pf[0], pb[0], 3);
  renderer.setCullBackfaces(true);
  frame = render(renderer, *pool, view, builder.items(view.eye));
  EXPECT_EQ(frame.id(static_cast<int>(front.x), static_cast<int>(front.y)), 1u);
  EXPECT_EQ(frame.id(static_cast<int>(back.x), static_cast<int>(back.y)), 0u);
}

TEST_F(GlRendererTest, StatsTimerAndEmptyDraws) {
  PoolBuilder builder;
  builder.addQuad(10.0, 0.0, 0.0, 2.0, 1.5, 0);
  builder.addQuad(10.0, 3.0, 0.0, 0.5, 0.5, 1);
  auto pool = builder.makePool();
  GlRenderer renderer(smallOptions());
  TestView view;
  EXPECT_EQ(renderer.waitForGpuMs(), 0.0);

  // Nothing to draw: an empty span, and an item with no triangles.
  renderer.beginFrame(view.rotation(), view.projection());
  renderer.draw(*pool, {});
  std::vector<DrawItem> empty_item(1);
  renderer.draw(*pool, empty_item);
  RenderStats stats = renderer.endFrame();
  EXPECT_EQ(stats.draws, 0u);
  EXPECT_EQ(stats.triangles, 0u);
  std::vector<uint32_t> ids;
  renderer.readObjectIds(ids);
  EXPECT_EQ(std::count(ids.begin(), ids.end(), 0u), kWidth * kHeight);

  // Two draw calls in one frame add up.
  double gpu_ms = -1.0;
  for (int frame = 0; frame < 6; ++frame) {
    auto items = builder.items(view.eye);
    renderer.beginFrame(view.rotation(), view.projection());
    renderer.draw(*pool, std::span(items).first(1));
    renderer.draw(*pool, std::span(items).subspan(1));
    stats = renderer.endFrame();
    EXPECT_EQ(stats.draws, 2u);
    EXPECT_EQ(stats.triangles, 4u);
    EXPECT_GE(stats.gpu_ms, 0.0);
    EXPECT_LT(stats.gpu_ms, 10000.0);
    gpu_ms = renderer.waitForGpuMs();
    EXPECT_GE(gpu_ms, 0.0);
  }
  EXPECT_LT(gpu_ms, 10000.0);
  std::printf("gpu ms of a 4-triangle frame: %.3f\n", gpu_ms);
  // After waiting, endFrame's non-blocking figure is a finished frame's.
  renderer.readObjectIds(ids);
  EXPECT_GT(std::count(ids.begin(), ids.end(), 1u), 100);
  EXPECT_GT(std::count(ids.begin(), ids.end(), 2u), 10);
}

TEST_F(GlRendererTest, ResizeChangesTheTargetsAndReadbackFlipsRows) {
  PoolBuilder builder;
  builder.addQuad(10.0, 0.0, 3.0, 2.0, 1.0, 0);  // upper half of the image
  auto pool = builder.makePool();
  GlRenderer renderer(smallOptions());
  TestView view;
  Frame frame = render(renderer, *pool, view, builder.items(view.eye));
  glm::dvec2 p = view.project({10.0, 0.0, 3.0});
  ASSERT_LT(p.y, kHeight / 2);
  EXPECT_EQ(frame.id(static_cast<int>(p.x), static_cast<int>(p.y)), 1u);
  std::vector<uint32_t> bottom_up;
  renderer.readObjectIds(bottom_up, false);
  EXPECT_EQ(bottom_up[static_cast<size_t>(kHeight - 1 - static_cast<int>(p.y)) * kWidth +
                      static_cast<int>(p.x)],
            1u);

  renderer.resize(64, 48);
  EXPECT_EQ(renderer.width(), 64);
  EXPECT_EQ(renderer.height(), 48);
  renderer.beginFrame(view.rotation(), glm::mat4(glm::perspectiveRH_ZO(kFovY, 64.0 / 48.0,
                                                                        1000.0, 0.1)));
  renderer.draw(*pool, builder.items(view.eye));
  renderer.endFrame();
  std::vector<uint8_t> rgba;
  std::vector<uint32_t> ids;
  renderer.readColor(rgba);
  renderer.readObjectIds(ids);
  EXPECT_EQ(rgba.size(), 64u * 48u * 4u);
  ASSERT_EQ(ids.size(), 64u * 48u);
  EXPECT_EQ(ids[static_cast<size_t>(p.y / 2) * 64 + static_cast<size_t>(p.x / 2)], 1u);
  EXPECT_THROW(renderer.resize(0, 10), std::invalid_argument);
  // Larger than any GL implementation's texture limit: refused, and the old targets stay usable.
  EXPECT_THROW(renderer.resize(1 << 20, 48), std::runtime_error);
  EXPECT_EQ(renderer.width(), 64);
  renderer.beginFrame(view.rotation(), glm::mat4(glm::perspectiveRH_ZO(kFovY, 64.0 / 48.0,
                                                                        1000.0, 0.1)));
  renderer.draw(*pool, builder.items(view.eye));
  renderer.endFrame();
  renderer.readObjectIds(ids);
  EXPECT_EQ(ids[static_cast<size_t>(p.y / 2) * 64 + static_cast<size_t>(p.x / 2)], 1u);
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
}

TEST_F(GlRendererTest, RejectsPlacementsOutsideThePool) {
  PoolBuilder builder;
  builder.addQuad(10.0, 0.0, 0.0, 2.0, 1.5, 0);
  auto pool = builder.makePool();
  GlRenderer renderer(smallOptions());
  TestView view;
  renderer.beginFrame(view.rotation(), view.projection());
  auto items = builder.items(view.eye);
  auto bad = items;
  bad[0].placement.first_index = pool->layout().indices - 3;
  EXPECT_THROW(renderer.draw(*pool, bad), std::out_of_range);
  bad = items;
  bad[0].placement.first_vertex = pool->layout().vertices;
  EXPECT_THROW(renderer.draw(*pool, bad), std::out_of_range);
  bad = items;
  bad[0].placement.first_triangle = ~0ull;
  EXPECT_THROW(renderer.draw(*pool, bad), std::out_of_range);
  // A bad item after a good one: nothing of the call is drawn or counted.
  bad = items;
  bad.push_back(items[0]);
  bad[1].placement.first_index = pool->layout().indices + 1;
  EXPECT_THROW(renderer.draw(*pool, bad), std::out_of_range);
  renderer.draw(*pool, items);
  RenderStats stats = renderer.endFrame();
  EXPECT_EQ(stats.draws, 1u);
  EXPECT_EQ(stats.triangles, 2u);

  PageUpload too_big;
  too_big.first_vertex = pool->layout().vertices - 1;
  too_big.vertices.resize(2);
  EXPECT_THROW(pool->upload(too_big), std::out_of_range);
  PageUpload wrapped;
  wrapped.first_index = ~0ull;
  wrapped.indices.resize(3);
  EXPECT_THROW(pool->upload(wrapped), std::out_of_range);
}

TEST_F(GlRendererTest, TriangleObjectsBeyondTheShaderStorageBlockLimit) {
  // llvmpipe limits one shader storage binding to 128 MiB (32M triangle objects), while a 1 GiB
  // pool holds more triangles than that: clusters placed past the limit keep their ids, also
  // when one multi-draw mixes clusters from both ends of the pool.
  PoolBuilder builder;
  builder.addQuad(10.0, 2.0, 0.0, 1.0, 1.0, 3);
  builder.addQuad(10.0, -2.0, 0.0, 1.0, 1.0, 4);
  PoolLayout layout{64, 64, 40'000'000};
  GeometryPool pool(layout);
  PageUpload geometry = builder.upload();
  geometry.triangle_objects.resize(2);  // the first cluster's objects stay at 0
  pool.upload(geometry);
  constexpr uint64_t kFarTriangle = 36'000'001;  // odd: not aligned to anything
  PageUpload far_objects;
  far_objects.first_triangle = kFarTriangle;
  far_objects.triangle_objects = {4, 4};
  pool.upload(far_objects);
  std::vector<DrawItem> items = builder.items(glm::dvec3(0.0));
  items[1].placement.first_triangle = kFarTriangle;
  GlRenderer renderer(smallOptions());
  TestView view;
  glm::dvec2 left = view.project({10.0, 2.0, 0.0}), right = view.project({10.0, -2.0, 0.0});
  for (bool both : {true, false}) {
    Frame frame = render(renderer, pool, view,
                         both ? items : std::vector<DrawItem>{items[1]});
    EXPECT_EQ(frame.id(static_cast<int>(left.x), static_cast<int>(left.y)), both ? 4u : 0u);
    EXPECT_EQ(frame.id(static_cast<int>(right.x), static_cast<int>(right.y)), 5u);
  }
}

// --- A real package: the Stanford bunny, preprocessed once for this program. ---

using test::bunnyPackage;

// Every level-0 mesh cluster decoded by hand into one page-like upload, as the pager does.
struct LevelZero {
  PageUpload upload;
  std::vector<uint32_t> clusters;  // cluster indices, in upload order
  std::vector<GpuCluster> placements;
  uint64_t triangles = 0;
  glm::dvec3 lo{1e300}, hi{-1e300};  // package frame
  std::vector<glm::dvec3> positions;  // package frame
};

LevelZero decodeLevelZero(const PackageView& view) {
  LevelZero out;
  std::map<uint32_t, std::vector<uint8_t>> pages;
  DecodedCluster decoded;
  for (uint32_t i = 0; i < view.clusters().size(); ++i) {
    const pkg::ClusterRecord& record = view.clusters()[i];
    if (record.level != 0 || record.kind != static_cast<uint8_t>(pkg::ClusterKind::Mesh)) continue;
    auto [it, fresh] = pages.try_emplace(record.page);
    if (fresh) view.readPage(record.page, it->second);
    view.decodeCluster(i, it->second, decoded);
    PageUpload& upload = out.upload;
    GpuCluster c;
    c.first_vertex = upload.vertices.size();
    c.first_index = upload.indices.size();
    c.first_triangle = upload.triangle_objects.size();
    c.vertex_count = static_cast<uint32_t>(decoded.vertices.size());
    c.triangle_count = static_cast<uint32_t>(decoded.triangle_objects.size());
    c.shift = decoded.shift;
    c.grid_origin = decoded.grid_origin;
    c.cell_m = decoded.cell_m;
    out.clusters.push_back(i);
    out.placements.push_back(c);
    upload.vertices.insert(upload.vertices.end(), decoded.vertices.begin(),
                           decoded.vertices.end());
    for (uint32_t index : decoded.indices) upload.indices.push_back(static_cast<uint16_t>(index));
    upload.triangle_objects.insert(upload.triangle_objects.end(),
                                   decoded.triangle_objects.begin(),
                                   decoded.triangle_objects.end());
    out.triangles += c.triangle_count;
    for (const glm::vec3& p : decoded.positions) {
      out.lo = glm::min(out.lo, glm::dvec3(p));
      out.hi = glm::max(out.hi, glm::dvec3(p));
      out.positions.push_back(glm::dvec3(p));
    }
  }
  return out;
}

// A view that fits the bunny's bounding sphere, in world metres.
TestView bunnyCamera(const LevelZero& scene, const glm::dvec3& origin) {
  const glm::dvec3 centre = origin + 0.5 * (scene.lo + scene.hi);
  const double radius = 0.5 * glm::length(scene.hi - scene.lo);
  TestView camera;
  // Nearly straight down -Z: the bunny is Y-up, so its up is the image up (lookAt keeps Z up).
  camera.forward = glm::normalize(glm::dvec3(0.35, 0.3, -1.0));
  camera.eye = centre - camera.forward * (radius / std::sin(kFovY / 2) * 1.05);
  camera.near_m = radius * 0.05;
  camera.far_m = radius * 100.0;
  return camera;
}

std::vector<DrawItem> itemsFor(const std::vector<GpuCluster>& placements,
                               const glm::dvec3& origin, const glm::dvec3& eye) {
  std::vector<DrawItem> items;
  for (const GpuCluster& c : placements) {
    DrawItem item;
    item.placement = c;
    item.offset_eye = glm::vec3(glm::dvec3(c.grid_origin) * c.cell_m + origin - eye);
    items.push_back(item);
  }
  return items;
}

TEST_F(GlRendererTest, DrawsTheLevelZeroClustersOfABunnyPackage) {
  PackageView view = PackageView::open(bunnyPackage());
  LevelZero scene = decodeLevelZero(view);
  const uint64_t triangles = scene.triangles;
  const std::vector<GpuCluster>& placements = scene.placements;
  ASSERT_EQ(triangles, view.header().total_triangles);
  EXPECT_EQ(triangles, 69451u);
  PoolLayout layout{scene.upload.vertices.size(), scene.upload.indices.size(),
                    scene.upload.triangle_objects.size()};
  GeometryPool pool(layout);
  pool.upload(scene.upload);
  const glm::dvec3 origin = view.origin();
  TestView camera = bunnyCamera(scene, origin);
  const double radius = 0.5 * glm::length(scene.hi - scene.lo);
  std::vector<DrawItem> items = itemsFor(placements, origin, camera.eye);
  GlRenderer renderer(smallOptions());
  Frame frame = render(renderer, pool, camera, items);
  EXPECT_EQ(frame.stats.triangles, triangles);
  EXPECT_EQ(frame.stats.draws, placements.size());

  // Covered pixels: a healthy share, valid ids, and the same extent as the projected vertices.
  int covered = 0, min_x = kWidth, max_x = -1, min_y = kHeight, max_y = -1;
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      uint32_t id = frame.id(x, y);
      if (id == 0) continue;
      ++covered;
      EXPECT_LE(id, view.objects().size());
      min_x = std::min(min_x, x), max_x = std::max(max_x, x);
      min_y = std::min(min_y, y), max_y = std::max(max_y, y);
    }
  double px_lo_x = 1e9, px_hi_x = -1e9, px_lo_y = 1e9, px_hi_y = -1e9;
  for (const glm::dvec3& p : scene.positions) {
    glm::dvec2 s = camera.project(origin + p);
    px_lo_x = std::min(px_lo_x, s.x), px_hi_x = std::max(px_hi_x, s.x);
    px_lo_y = std::min(px_lo_y, s.y), px_hi_y = std::max(px_hi_y, s.y);
  }
  const double share = double(covered) / (kWidth * kHeight);
  EXPECT_GT(share, 0.12) << covered;
  EXPECT_LT(share, 0.9);
  EXPECT_NEAR(min_x, px_lo_x, 1.5);
  EXPECT_NEAR(max_x + 1, px_hi_x, 1.5);
  EXPECT_NEAR(min_y, px_lo_y, 1.5);
  EXPECT_NEAR(max_y + 1, px_hi_y, 1.5);

  // Shading varies over the surface (derivative normals work), and nothing is black or NaN-white.
  int darkest = 255, brightest = 0;
  for (int i = 0; i < kWidth * kHeight; ++i) {
    if (frame.ids[i] == 0) continue;
    darkest = std::min<int>(darkest, frame.rgba[i * 4]);
    brightest = std::max<int>(brightest, frame.rgba[i * 4]);
  }
  EXPECT_GT(brightest - darkest, 40);
  EXPECT_GT(darkest, 10);

  // A larger picture for a person to look at.
  renderer.resize(640, 480);
  camera.near_m = radius * 0.05;
  renderer.beginFrame(camera.rotation(),
                      glm::mat4(glm::perspectiveRH_ZO(kFovY, 640.0 / 480.0, camera.far_m,
                                                      camera.near_m)));
  renderer.draw(pool, items);
  renderer.endFrame();
  std::vector<uint8_t> rgba;
  renderer.readColor(rgba);
  fs::path png = test::scratchDir() / "bunny.png";
  writePngRgba(png, 640, 480, rgba);
  EXPECT_TRUE(fs::exists(png));
  std::printf("bunny image: %s\n", png.c_str());
}

TEST_F(GlRendererTest, PagesFromThePagerDrawTheSameImageAsHandDecodedClusters) {
  // The pager's uploads and placements, fed to the pool as the frame loop does, give exactly the
  // image of the hand-built pool: the two agree on the pool layout and on GpuCluster.
  PackageView view = PackageView::open(bunnyPackage());
  LevelZero scene = decodeLevelZero(view);
  const glm::dvec3 origin = view.origin();
  const TestView camera = bunnyCamera(scene, origin);
  GlRenderer renderer(smallOptions());

  PoolLayout layout{scene.upload.vertices.size(), scene.upload.indices.size(),
                    scene.upload.triangle_objects.size()};
  GeometryPool hand_pool(layout);
  hand_pool.upload(scene.upload);
  Frame expected = render(renderer, hand_pool, camera, itemsFor(scene.placements, origin,
                                                                camera.eye));

  PagerOptions options;
  options.gpu_budget_bytes = 32ull << 20;
  Pager pager(view, makePackagePageSource(view), options);
  GeometryPool pool(pager.poolLayout());
  std::vector<uint32_t> pages;
  for (uint32_t c : scene.clusters) pages.push_back(view.clusters()[c].page);
  std::sort(pages.begin(), pages.end());
  pages.erase(std::unique(pages.begin(), pages.end()), pages.end());
  uint64_t uploaded = 0;
  for (uint64_t frame = 1; frame < 5000; ++frame) {
    pager.beginFrame(frame);
    bool all = true;
    for (uint32_t page : pages) {
      if (pager.resident(page)) {
        pager.touch(page);
      } else {
        all = false;
        pager.request(page, 1.0f);
      }
    }
    if (all) break;
    for (const PageUpload& up : pager.takeUploads()) uploaded += pool.upload(up);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  for (uint32_t page : pages) ASSERT_TRUE(pager.resident(page)) << page;
  EXPECT_GE(uploaded, scene.upload.bytes());
  std::vector<GpuCluster> placements;
  for (uint32_t c : scene.clusters) placements.push_back(pager.gpuCluster(c));
  Frame paged = render(renderer, pool, camera, itemsFor(placements, origin, camera.eye));
  EXPECT_EQ(paged.stats.triangles, scene.triangles);
  EXPECT_GT(std::count_if(paged.ids.begin(), paged.ids.end(), [](uint32_t id) { return id; }),
            kWidth * kHeight / 10);
  EXPECT_TRUE(paged.ids == expected.ids);
  EXPECT_TRUE(paged.rgba == expected.rgba);
}

}  // namespace
}  // namespace tw
