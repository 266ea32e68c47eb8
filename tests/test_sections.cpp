// Section planes (runtime/section_planes.h) as `terawalk render --section` shows them on a
// generated plant: what a plane removes is gone from the id images at every level of detail and
// for every way parametrics are drawn (impostors, tessellated), what it keeps is untouched, and
// the cut is capped in the section colour.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "generated_plant_support.h"
#include "image_compare.h"
#include "package_view.h"
#include "section_planes.h"
#include "test_support.h"

namespace tw {
namespace {

// The frames' ids and colours of one render of the generated plant.
struct Frames {
  std::vector<std::vector<uint32_t>> ids;
  std::vector<std::vector<uint8_t>> rgba;
};

Frames render(const std::filesystem::path& dir, const std::string& name, const std::string& args) {
  const auto out = dir / name;
  const test::CommandResult r = test::runTerawalk(
      "render --quiet " + test::generatedPlant().package.string() + " --orbit 3 --size 320x180 " +
      "--png --out " + out.string() + " " + args);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  Frames frames;
  for (int i = 0;; ++i) {
    char ids[32], colour[32];
    std::snprintf(ids, sizeof ids, "ids_%05d.png", i);
    std::snprintf(colour, sizeof colour, "frame_%05d.png", i);
    if (!std::filesystem::exists(out / ids)) break;
    frames.ids.push_back(idsFromRgba(readPngRgba(out / ids).rgba));
    frames.rgba.push_back(readPngRgba(out / colour).rgba);
  }
  return frames;
}

// Where an object's box lies against the plane, with `margin` metres to spare.
enum class Side { Kept, Removed, Cut };

TEST(Sections, APlaneRemovesItsSideAtEveryLevelOfDetailAndForImpostors) {
  const PackageView view = PackageView::open(test::generatedPlant().package);
  // A vertical plane through the middle of the plant, removing the +X half.
  const glm::dvec3 lo = view.origin() + glm::dvec3(view.header().bounds_min[0], 0, 0);
  const glm::dvec3 hi = view.origin() + glm::dvec3(view.header().bounds_max[0], 0, 0);
  const SectionPlane plane{0.5 * (lo + hi), {1.0, 0.0, 0.0}};
  const std::string section = "--section " + test::vec3Arg(plane.point) + ",1,0,0";
  // Coarse clusters stray from their objects' boxes by their error: a metre covers the levels
  // drawn here.
  constexpr double kMargin = 1.0;
  std::vector<Side> side(view.objects().size());
  for (size_t o = 0; o < side.size(); ++o) {
    const pkg::ObjectRecord& r = view.objects()[o];
    const double x0 = view.origin().x + r.aabb_min[0], x1 = view.origin().x + r.aabb_max[0];
    side[o] = x1 < plane.point.x - kMargin   ? Side::Kept
              : x0 > plane.point.x + kMargin ? Side::Removed
                                             : Side::Cut;
  }

  const auto dir = test::scratchDir();
  for (const std::string variant : {"--tau 1", "--tau 24", "--reference",
                                    "--parametrics impostor", "--parametrics tessellated"}) {
    SCOPED_TRACE(variant);
    const Frames whole = render(dir, "whole", variant);
    const Frames cut = render(dir, "cut", variant + " " + section);
    ASSERT_FALSE(whole.ids.empty());
    ASSERT_EQ(whole.ids.size(), cut.ids.size());
    uint64_t removed_before = 0, removed_after = 0, kept = 0, kept_changed = 0, caps = 0;
    for (size_t f = 0; f < whole.ids.size(); ++f) {
      for (size_t p = 0; p < whole.ids[f].size(); ++p) {
        const uint32_t before = whole.ids[f][p], after = cut.ids[f][p];
        if (before != 0 && side[before - 1] == Side::Removed) ++removed_before;
        if (after != 0 && side[after - 1] == Side::Removed) ++removed_after;
        if (before != 0 && side[before - 1] == Side::Kept) {
          ++kept;
          kept_changed += after != before;

        }
        // The section colour (gl_shaders.h kSectionCap), where the cut opened a solid.
        const uint8_t* c = &cut.rgba[f][4 * p];
        caps += after != 0 && c[0] == 199 && c[1] == 56 && c[2] == 46;
      }
    }
    EXPECT_GT(removed_before, 1000u) << "the removed half shows without the section";
    EXPECT_EQ(removed_after, 0u) << "nothing of the removed half shows with it";
    EXPECT_GT(kept, 1000u);
    // A section draws back faces, and where one lies in the plane of another object's front face
    // (a wall standing on a deck: its bottom on the deck's top) the two tie in depth: 7 of
    // 1,172 such pixels here go to the other kept object. Nothing else may change.
    EXPECT_LE(kept_changed * 100, kept) << "of " << kept << " pixels of the kept half";
    EXPECT_GT(caps, 50u) << "the cut solids are capped";
  }
}

TEST(Sections, PlanesAndBoxesAreCheckedOnTheCommandLine) {
  EXPECT_THROW(parseSectionPlane("1,2,3,0,0"), std::invalid_argument);
  EXPECT_THROW(parseSectionPlane("1,2,3,0,0,0"), std::invalid_argument);
  EXPECT_THROW(parseSectionPlane("1,2,x,0,0,1"), std::invalid_argument);
  EXPECT_THROW(parseSectionPlane("1,2,3,0,0,inf"), std::invalid_argument);
  const SectionPlane p = parseSectionPlane("1,2,3,0,0,-2");
  EXPECT_EQ(p.normal, glm::dvec3(0, 0, -1));
  EXPECT_TRUE(sectionRemoves(p, {1, 2, 2.5}));
  EXPECT_FALSE(sectionRemoves(p, {1, 2, 3.5}));
  int removing = 0;
  for (const SectionPlane& face : sectionBoxPlanes({0, 0, 0}, {1, 1, 1}))
    removing += sectionRemoves(face, {2.0, 0.5, 0.5});
  EXPECT_EQ(removing, 1) << "outside the box across one face";
  for (const SectionPlane& face : sectionBoxPlanes({0, 0, 0}, {1, 1, 1}))
    EXPECT_FALSE(sectionRemoves(face, {0.5, 0.5, 0.5}));

  const std::string package = test::generatedPlant().package.string();
  const test::CommandResult bad = test::runTerawalk("render --quiet " + package +
                                                    " --orbit 1 --section 0,0,0,0,0,0");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("the normal is zero"), std::string::npos) << bad.output;
  const test::CommandResult box = test::runTerawalk("render --quiet " + package +
                                                    " --orbit 1 --section-box 1,1,1 0,0,0");
  EXPECT_NE(box.exit_code, 0);
  EXPECT_NE(box.output.find("is not below MAX"), std::string::npos) << box.output;
}

}  // namespace
}  // namespace tw
