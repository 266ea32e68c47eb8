// BCF archives: what TeraWalk writes validates against buildingSMART's schemas, a viewpoint
// exported from a review comes back (camera to 1e-9, selection, visibility, clipping planes, the
// same picture), the official test cases import and render bcf-architectural.ifc from their
// cameras, and broken archives get clear errors without losing the review's topics.
#include <cstdio>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <zip.h>

#include "bcf_archive.h"
#include "bcf_ids.h"
#include "change_set.h"
#include "format_error.h"
#include "generated_plant_support.h"
#include "image_compare.h"
#include "test_support.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

const fs::path kCases = fs::path(TW_SHARED_DATA_DIR) / ".." / "bcf" / "cases-2.0";
const fs::path kSchemas = fs::path(TW_SHARED_DATA_DIR) / ".." / "bcf";
const char* kCaseNames[] = {"Clippingplane", "ComponentSelection", "MinimumInformation",
                            "MultipleTopics", "PerspectiveCamera"};

// Every entry of a zip archive, by name.
std::vector<std::pair<std::string, std::string>> zipEntries(const fs::path& path) {
  std::vector<std::pair<std::string, std::string>> out;
  int code = 0;
  zip_t* zip = zip_open(path.string().c_str(), ZIP_RDONLY, &code);
  if (!zip) return out;
  for (zip_int64_t i = 0; i < zip_get_num_entries(zip, 0); ++i) {
    zip_stat_t st;
    zip_stat_index(zip, static_cast<zip_uint64_t>(i), 0, &st);
    std::string bytes(st.size, '\0');
    zip_file_t* f = zip_fopen_index(zip, static_cast<zip_uint64_t>(i), 0);
    zip_fread(f, bytes.data(), bytes.size());
    zip_fclose(f);
    out.emplace_back(st.name, bytes);
  }
  zip_discard(zip);
  return out;
}

// Writes a zip of the given entries (a hand-made archive, well-formed or not).
void writeZip(const fs::path& path, const std::vector<std::pair<std::string, std::string>>& entries) {
  int code = 0;
  zip_t* zip = zip_open(path.string().c_str(), ZIP_CREATE | ZIP_TRUNCATE, &code);
  ASSERT_NE(zip, nullptr);
  for (const auto& [name, bytes] : entries) {
    zip_source_t* s = zip_source_buffer(zip, bytes.data(), bytes.size(), 0);
    zip_file_add(zip, name.c_str(), s, ZIP_FL_OVERWRITE);
  }
  ASSERT_EQ(zip_close(zip), 0);
}

// xmllint's verdict on every document of an archive, against the schemas of `version`.
void expectArchiveValidates(const fs::path& archive, const std::string& version, const fs::path& work) {
  const fs::path schemas = kSchemas / ("schemas-" + version);
  int documents = 0;
  for (const auto& [name, bytes] : zipEntries(archive)) {
    std::string schema;
    if (name.ends_with(".bcfv")) schema = "visinfo.xsd";
    else if (name.ends_with("markup.bcf")) schema = "markup.xsd";
    else if (name == "bcf.version") schema = "version.xsd";
    else if (name.ends_with(".bcfp")) schema = "project.xsd";
    else continue;
    const fs::path file = work / ("doc" + std::to_string(documents++) + ".xml");
    std::ofstream(file, std::ios::binary) << bytes;
    const test::CommandResult r = test::runShell("xmllint --noout --schema " +
                                                 (schemas / schema).string() + " " + file.string());
    EXPECT_EQ(r.exit_code, 0) << archive << ": " << name << " (BCF " << version << "):\n" << r.output;
  }
  EXPECT_GE(documents, 2) << archive;  // at least bcf.version and a markup
}

// A viewpoint that uses every part TeraWalk writes.
bcf::Archive fullArchive() {
  bcf::Archive archive;
  archive.project_id = "terawalk-test";
  archive.project_name = "Plant review";
  bcf::Topic t;
  t.guid = bcf::newGuid();
  t.title = "Pump P-101 clashes with the walkway";
  t.status = "Open";
  t.type = "Clash";
  t.creation_author = "reviewer@example.com";
  t.creation_date = "2026-12-06T10:00:00Z";
  t.description = "Moved 400 mm east in the review";
  t.labels = {"mechanical", "walkway"};
  t.index = 3;
  t.files.push_back({"plant.ifc", "2026-12-01T00:00:00Z", "2SugUv4EX5LAhcVpDp2dUH", ""});
  for (int k = 0; k < 2; ++k) {
    bcf::Viewpoint v;
    v.guid = bcf::newGuid();
    bcf::Camera c;
    c.orthogonal = k == 1;
    c.position = {1234.5678901234567, -0.1000000000000001, 7.25e-3};
    c.direction = glm::normalize(glm::dvec3(0.3, 0.7, -0.2));
    c.up = glm::normalize(glm::dvec3(0.1, 0.2, 0.9));
    c.field_of_view_deg = 52.5;
    c.view_to_world_scale = 17.125;
    c.aspect_ratio = 16.0 / 9.0;
    v.camera = c;
    v.selection = {{"1E8YkwPMfB$h99jtn_uAjI", "", ""}, {"", "P-101", "TeraWalk"}};
    v.default_visibility = k == 0;
    v.exceptions = {{"1BGpia0iv9cfH1lqT0_P80", "", ""}};
    v.colours = {{0xffff8000u, {{"2eKNhkT$f0P8WjqeWWO9d3", "", ""}}},
                 {0x80112233u, {{"", "P-101", "TeraWalk"}}}};
    v.clipping_planes = {{{0.0, 0.0, 7.5}, {0.0, 0.0, 1.0}}, {{1.0, 2.0, 3.0}, {0.6, 0.0, -0.8}}};
    v.snapshot_png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R',
                      0, 0, 2, 0, 0, 0, 1, 0};
    v.index = k;
    t.viewpoints.push_back(v);
  }
  t.comments.push_back({bcf::newGuid(), "2026-12-06T10:05:00Z", "reviewer@example.com",
                        "Please move it east", t.viewpoints[0].guid, "", ""});
  t.comments.push_back({bcf::newGuid(), "2026-12-06T10:06:00Z", "designer@example.com", "", "", "", ""});
  archive.topics.push_back(t);
  return archive;
}

TEST(Bcf, EveryArchiveWrittenValidatesAgainstTheSchemas) {
  const fs::path dir = test::scratchDir();
  std::vector<bcf::Archive> archives = {fullArchive()};
  for (const char* name : kCaseNames) {
    std::vector<std::string> warnings;
    archives.push_back(bcf::readArchive(kCases / (std::string(name) + ".bcfzip"), warnings));
  }
  int k = 0;
  for (const bcf::Archive& archive : archives)
    for (const auto& [version, id] : {std::pair{bcf::Version::V2_1, "2.1"}, {bcf::Version::V3_0, "3.0"}}) {
      const fs::path out = dir / ("a" + std::to_string(k++) + ".bcfzip");
      std::vector<std::string> notes;
      bcf::writeArchive(out, archive, version, notes);
      expectArchiveValidates(out, id, dir);
    }
}

TEST(Bcf, WrittenThenReadGivesBackEveryField) {
  const fs::path dir = test::scratchDir();
  const bcf::Archive original = fullArchive();
  for (const auto version : {bcf::Version::V2_1, bcf::Version::V3_0}) {
    std::vector<std::string> notes, warnings;
    bcf::writeArchive(dir / "rt.bcfzip", original, version, notes);
    const bcf::Archive back = bcf::readArchive(dir / "rt.bcfzip", warnings);
    EXPECT_TRUE(warnings.empty()) << warnings.front();
    ASSERT_EQ(back.topics.size(), 1u);
    const bcf::Topic &a = original.topics[0], &b = back.topics[0];
    EXPECT_EQ(b.guid, a.guid);
    EXPECT_EQ(b.title, a.title);
    EXPECT_EQ(b.status, a.status);
    EXPECT_EQ(b.type, a.type);
    EXPECT_EQ(b.creation_author, a.creation_author);
    EXPECT_EQ(b.creation_date, a.creation_date);
    EXPECT_EQ(b.labels, a.labels);
    EXPECT_EQ(back.project_name, original.project_name);
    ASSERT_EQ(b.comments.size(), 2u);
    EXPECT_EQ(b.comments[0].text, "Please move it east");
    EXPECT_EQ(b.comments[0].viewpoint_guid, a.viewpoints[0].guid);
    ASSERT_EQ(b.viewpoints.size(), 2u);
    for (size_t k = 0; k < 2; ++k) {
      const bcf::Viewpoint &va = a.viewpoints[k], &vb = b.viewpoints[k];
      EXPECT_EQ(vb.guid, va.guid);
      ASSERT_TRUE(vb.camera);
      EXPECT_EQ(vb.camera->orthogonal, va.camera->orthogonal);
      EXPECT_LE(glm::length(vb.camera->position - va.camera->position), 1e-9);
      EXPECT_LE(glm::length(vb.camera->direction - va.camera->direction), 1e-9);
      EXPECT_LE(glm::length(vb.camera->up - va.camera->up), 1e-9);
      if (!va.camera->orthogonal) EXPECT_DOUBLE_EQ(vb.camera->field_of_view_deg, 52.5);
      else EXPECT_DOUBLE_EQ(vb.camera->view_to_world_scale, 17.125);
      ASSERT_EQ(vb.selection.size(), 2u);
      EXPECT_EQ(vb.selection[0].ifc_guid, "1E8YkwPMfB$h99jtn_uAjI");
      EXPECT_EQ(vb.selection[1].authoring_tool_id, "P-101");
      EXPECT_EQ(vb.selection[1].originating_system, "TeraWalk");
      EXPECT_EQ(vb.default_visibility, va.default_visibility);
      ASSERT_EQ(vb.exceptions.size(), 1u);
      EXPECT_EQ(vb.exceptions[0].ifc_guid, "1BGpia0iv9cfH1lqT0_P80");
      ASSERT_EQ(vb.colours.size(), 2u);
      EXPECT_EQ(vb.colours[0].argb, 0xffff8000u);
      EXPECT_EQ(vb.colours[1].argb, 0x80112233u);
      ASSERT_EQ(vb.clipping_planes.size(), 2u);
      EXPECT_LE(glm::length(vb.clipping_planes[1].direction - glm::dvec3(0.6, 0.0, -0.8)), 1e-12);
      EXPECT_EQ(vb.snapshot_png, va.snapshot_png);
    }
  }
}

TEST(Bcf, TwoPointOneClampsTheFieldOfViewItAllowsAndSaysSo) {
  const fs::path dir = test::scratchDir();
  bcf::Archive archive = fullArchive();
  archive.topics[0].viewpoints[0].camera->field_of_view_deg = 90.0;
  std::vector<std::string> notes, warnings;
  bcf::writeArchive(dir / "wide.bcfzip", archive, bcf::Version::V2_1, notes);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("45 to 60"), std::string::npos) << notes[0];
  expectArchiveValidates(dir / "wide.bcfzip", "2.1", dir);
  bcf::writeArchive(dir / "wide3.bcfzip", archive, bcf::Version::V3_0, notes);
  const bcf::Archive back = bcf::readArchive(dir / "wide3.bcfzip", warnings);
  EXPECT_DOUBLE_EQ(back.topics[0].viewpoints[0].camera->field_of_view_deg, 90.0);
}

// --- through the package: bcf-architectural.ifc preprocessed once ---

fs::path architecturalPackage() {
  static const fs::path package = [] {
    const fs::path dir = test::processScratchDir("bcf-architectural");
    const fs::path p = dir / "arch.twk";
    const test::CommandResult r = test::runTerawalk(
        "-q preprocess " + (fs::path(TW_SHARED_DATA_DIR) / "bcf-architectural.ifc").string() +
        " -o " + p.string());
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return p;
  }();
  return package;
}

nlohmann::json listJson(const fs::path& archive) {
  const test::CommandResult r = test::runTerawalk("bcf list --json " + archive.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return nlohmann::json::parse(r.output.substr(r.output.find('{')));
}

std::set<std::string> guidsOf(const nlohmann::json& components) {
  std::set<std::string> out;
  for (const auto& c : components) out.insert(c.value("ifc_guid", c.value("authoring_tool_id", "")));
  return out;
}

TEST(Bcf, AViewpointExportedFromAReviewComesBackWithTheSamePicture) {
  const fs::path dir = test::scratchDir();
  const fs::path package = dir / "arch.twk";
  fs::copy_file(architecturalPackage(), package);
  const std::string walls = "'1E8YkwPMfB$h99jtn_uAjI,1BGpia0iv9cfH1lqT0_P80,2eKNhkT$f0P8WjqeWWO9d3'";
  const std::string state = " --eye 19.5,-28.25,13.75 --look-at 10,-13,7.5 --fov 55 --isolate-keys " +
                            walls + " --select '1BGpia0iv9cfH1lqT0_P80' --colour FF8000=" +
                            "'2eKNhkT$f0P8WjqeWWO9d3' --section 0,0,8.2,0,0,1 --size 320x200";
  for (const std::string version : {"2.1", "3.0"}) {
    const fs::path archive = dir / ("review" + version + ".bcfzip");
    const test::CommandResult e = test::runTerawalk(
        "-q bcf export " + package.string() + " -o " + archive.string() + " --version " + version +
        " --title 'Walls cut at 8.2 m' --comment 'Check the openings'" + state);
    ASSERT_EQ(e.exit_code, 0) << e.output;
    expectArchiveValidates(archive, version, dir);

    // What the archive says: the camera to 1e-9, the selection, visibility and clipping plane.
    const nlohmann::json list = listJson(archive);
    const nlohmann::json& topic = list["topics"].back();
    EXPECT_EQ(topic["title"], "Walls cut at 8.2 m");
    EXPECT_EQ(topic["comments"][0]["text"], "Check the openings");
    const nlohmann::json& v = topic["viewpoints"][0];
    const glm::dvec3 eye(19.5, -28.25, 13.75), dir_expected = glm::normalize(glm::dvec3(10, -13, 7.5) - eye);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(v["camera"]["position"][i].get<double>(), eye[i], 1e-9);
      EXPECT_NEAR(v["camera"]["direction"][i].get<double>(), dir_expected[i], 1e-9);
    }
    EXPECT_NEAR(v["camera"]["field_of_view_deg"].get<double>(), 55.0, 1e-9);
    EXPECT_EQ(guidsOf(v["selection"]), std::set<std::string>{"1BGpia0iv9cfH1lqT0_P80"});
    EXPECT_FALSE(v["default_visibility"].get<bool>()) << "three walls shown of many: the short list";
    EXPECT_EQ(guidsOf(v["exceptions"]),
              (std::set<std::string>{"1E8YkwPMfB$h99jtn_uAjI", "1BGpia0iv9cfH1lqT0_P80",
                                     "2eKNhkT$f0P8WjqeWWO9d3"}));
    ASSERT_EQ(v["colours"].size(), 1u);
    EXPECT_EQ(v["colours"][0]["argb"], "FFFF8000");
    ASSERT_EQ(v["clipping_planes"].size(), 1u);
    EXPECT_NEAR(v["clipping_planes"][0]["location"][2].get<double>(), 8.2, 1e-12);

    // Rendered from the imported viewpoint, the picture is the exported snapshot.
    const size_t number = topic["viewpoints"][0]["number"].get<size_t>();
    const test::CommandResult r = test::runTerawalk(
        "-q render " + package.string() + " --viewpoint " + archive.string() + "#" +
        std::to_string(number) + " --size 320x200 --png --out " + (dir / ("r" + version)).string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::vector<std::string> warnings;
    const bcf::Archive read = bcf::readArchive(archive, warnings);
    const fs::path snapshot = dir / "snapshot.png";
    std::ofstream(snapshot, std::ios::binary).write(
        reinterpret_cast<const char*>(read.topics.back().viewpoints[0].snapshot_png.data()),
        static_cast<std::streamsize>(read.topics.back().viewpoints[0].snapshot_png.size()));
    const RgbaImage exported = readPngRgba(snapshot);
    const RgbaImage rendered = readPngRgba(dir / ("r" + version) / "frame_00000.png");
    ASSERT_EQ(exported.rgba.size(), rendered.rgba.size());
    size_t differing = 0, coloured = 0, cap = 0;
    for (size_t p = 0; p < exported.rgba.size(); p += 4) {
      differing += std::memcmp(&exported.rgba[p], &rendered.rgba[p], 3) != 0;
      const uint8_t* px = &rendered.rgba[p];
      coloured += px[0] > 180 && px[1] > 70 && px[1] < 150 && px[2] < 60;  // the orange wall
      cap += px[0] == 199 && px[1] == 56 && px[2] == 46;                   // the section colour
    }
    EXPECT_EQ(differing, 0u) << "of " << exported.rgba.size() / 4 << " pixels";
    EXPECT_GT(coloured, 50u);
    EXPECT_GT(cap, 20u);
  }
}

TEST(Bcf, OfficialCasesImportAndTheirViewpointsRenderTheArchitecturalModel) {
  const fs::path dir = test::scratchDir();
  const fs::path package = dir / "arch.twk";
  fs::copy_file(architecturalPackage(), package);
  for (const char* name : kCaseNames) {
    const test::CommandResult r = test::runTerawalk("bcf import " + package.string() + " " +
                                                    (kCases / (std::string(name) + ".bcfzip")).string());
    EXPECT_EQ(r.exit_code, 0) << name << ": " << r.output;
    if (std::string(name) == "ComponentSelection") {
      // Its components belong to Estructura.ifc, not to this model: each is named and skipped.
      EXPECT_NE(r.output.find("IfcGuid 0AQJSsoeDDvwVqSNcwjy55: no object of the model has it; skipped"),
                std::string::npos) << r.output;
      EXPECT_NE(r.output.find("0 of 3 components found"), std::string::npos) << r.output;
    }
  }
  const nlohmann::json review = listJson(dir / "arch.review.bcfzip");
  EXPECT_EQ(review["topics"].size(), 7u);  // 1 + 1 + 1 + 3 + 1

  // Clipping plane: cut at z = 7.67 m, walls capped; Multiple topics: the building whole.
  auto render = [&](const std::string& name, int n) {
    const fs::path out = dir / (name + std::to_string(n));
    const test::CommandResult r = test::runTerawalk(
        "-q render " + package.string() + " --viewpoint " + (kCases / (name + ".bcfzip")).string() +
        "#" + std::to_string(n) + " --size 400x245 --png --out " + out.string());
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return readPngRgba(out / "ids_00000.png");
  };
  auto cover = [](const RgbaImage& ids) {
    size_t covered = 0;
    for (size_t p = 0; p < ids.rgba.size(); p += 4)
      covered += ids.rgba[p] | ids.rgba[p + 1] | ids.rgba[p + 2] | ids.rgba[p + 3];
    return double(covered) / (ids.rgba.size() / 4);
  };
  const RgbaImage clipped = render("Clippingplane", 1);
  EXPECT_GT(cover(clipped), 0.05);
  for (int n = 1; n <= 3; ++n) EXPECT_GT(cover(render("MultipleTopics", n)), 0.05) << n;
}

TEST(Bcf, BrokenArchivesGetClearErrorsAndTheReviewLosesNothing) {
  const fs::path dir = test::scratchDir();
  const fs::path package = dir / "arch.twk";
  fs::copy_file(architecturalPackage(), package);
  const fs::path store = dir / "arch.review.bcfzip";
  ASSERT_EQ(test::runTerawalk("-q bcf import " + package.string() + " " +
                              (kCases / "MultipleTopics.bcfzip").string()).exit_code, 0);
  std::ifstream in(store, std::ios::binary);
  const std::string before((std::istreambuf_iterator<char>(in)), {});
  ASSERT_FALSE(before.empty());

  // A truncated archive: an error naming it, the review untouched.
  std::ifstream whole(kCases / "MultipleTopics.bcfzip", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(whole)), {});
  std::ofstream(dir / "truncated.bcfzip", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  test::CommandResult r = test::runTerawalk("bcf import " + package.string() + " " +
                                            (dir / "truncated.bcfzip").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("truncated.bcfzip: not a readable BCF archive (zip)"), std::string::npos)
      << r.output;

  // One topic's markup does not parse: a warning naming the entry and line; the other topic is
  // read.
  const std::string good_guid = "11111111-2222-4333-8444-555555555555";
  const std::string good = "<?xml version=\"1.0\"?><Markup><Topic Guid=\"" + good_guid +
                           "\"><Title>Kept</Title><CreationDate>2026-01-01T00:00:00Z</CreationDate>"
                           "<CreationAuthor>a</CreationAuthor></Topic></Markup>";
  writeZip(dir / "half.bcfzip",
           {{"bcf.version", "<Version VersionId=\"2.1\"/>"},
            {good_guid + "/markup.bcf", good},
            {"99999999-2222-4333-8444-555555555555/markup.bcf", "<Markup>\n<Topic Guid=\"x\">\n<Title>"},
            {good_guid + "/viewpoint.bcfv", "<VisualizationInfo><PerspectiveCamera><CameraViewPoint>"
                                            "<X>nan</X><Y>0</Y><Z>0</Z></CameraViewPoint>"
                                            "</PerspectiveCamera></VisualizationInfo>"}});
  r = test::runTerawalk("bcf list " + (dir / "half.bcfzip").string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("99999999-2222-4333-8444-555555555555/markup.bcf:3: XML does not parse"),
            std::string::npos) << r.output;
  EXPECT_NE(r.output.find("topic skipped"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("viewpoint.bcfv:1: X 'nan' is not a finite number; viewpoint skipped"),
            std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Kept"), std::string::npos) << r.output;

  // Nothing readable at all: an error.
  writeZip(dir / "none.bcfzip", {{"a/markup.bcf", "not xml"}});
  r = test::runTerawalk("bcf import " + package.string() + " " + (dir / "none.bcfzip").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("none of its 1 topics could be read"), std::string::npos) << r.output;

  // A snapshot over the limit is skipped with a warning; the viewpoint stays.
  std::vector<std::string> warnings;
  bcf::ReadLimits limits;
  limits.max_snapshot_bytes = 1000;
  const bcf::Archive archive = bcf::readArchive(kCases / "Clippingplane.bcfzip", warnings, limits);
  ASSERT_EQ(archive.topics.size(), 1u);
  EXPECT_EQ(archive.topics[0].viewpoints.size(), 1u);
  EXPECT_TRUE(archive.topics[0].viewpoints[0].snapshot_png.empty());
  ASSERT_FALSE(warnings.empty());
  EXPECT_NE(warnings.back().find("snapshot.png: 51128 bytes, over the limit of 1000; snapshot skipped"),
            std::string::npos) << warnings.back();

  // The review's own archive damaged: import refuses and does not overwrite it.
  std::ofstream(store, std::ios::binary | std::ios::trunc) << before.substr(0, before.size() - 100);
  r = test::runTerawalk("bcf import " + package.string() + " " + (kCases / "Clippingplane.bcfzip").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("arch.review.bcfzip"), std::string::npos) << r.output;
  std::ifstream after_in(store, std::ios::binary);
  const std::string after((std::istreambuf_iterator<char>(after_in)), {});
  EXPECT_EQ(after.size(), before.size() - 100) << "the damaged review was overwritten";
}

// The way back for edits: a change set (a pump moved, with a comment) exported as BCF gives one
// topic for the pump, saying how it moved, with the comment and a viewpoint on the pump at its new
// place, selected; the archive validates.
TEST(Bcf, AChangeSetGoesToBcfAsATopicPerObjectWithItsViewpoint) {
  const fs::path dir = test::scratchDir();
  const fs::path package = dir / "plant.twk";
  fs::copy_file(test::generatedPlant().package, package);
  ChangeSet changes;
  Change move;
  move.kind = Change::Kind::Move;
  move.key = "P-1001-A";
  move.author = "ana";
  move.date = "2026-12-06T14:00:00Z";
  move.old_pivot = {10.0, 20.0, 3.0};
  move.new_pivot = move.old_pivot + glm::dvec3(0.4, 0.0, 0.0);
  move.transform = moveTransform(move.old_pivot, {0.4, 0.0, 0.0});
  changes.add(move);
  Change note = move;
  note.kind = Change::Kind::Comment;
  note.text = "clears the walkway now";
  changes.add(note);
  writeChangeSet(dir / "plant.changes.json", changes);
  for (const std::string version : {"2.1", "3.0"}) {
    const fs::path archive = dir / ("edits" + version + ".bcfzip");
    fs::remove(dir / "plant.review.bcfzip");
    const test::CommandResult r = test::runTerawalk(
        "-q bcf export " + package.string() + " --changes " + (dir / "plant.changes.json").string() +
        " -o " + archive.string() + " --version " + version + " --size 320x200");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    expectArchiveValidates(archive, version, dir);
    const nlohmann::json list = listJson(archive);
    ASSERT_EQ(list["topics"].size(), 1u) << list.dump();
    const nlohmann::json& t = list["topics"][0];
    EXPECT_EQ(t["title"], "Moved P-1001-A");
    EXPECT_NE(t["description"].get<std::string>().find("moved by (0.400, 0.000, 0.000) m"),
              std::string::npos) << t["description"];
    EXPECT_EQ(t["author"], "ana");
    ASSERT_EQ(t["comments"].size(), 1u);
    EXPECT_EQ(t["comments"][0]["text"], "clears the walkway now");
    ASSERT_EQ(t["viewpoints"].size(), 1u);
    EXPECT_EQ(guidsOf(t["viewpoints"][0]["selection"]), std::set<std::string>{"P-1001-A"});
    EXPECT_GT(t["viewpoints"][0]["snapshot_bytes"].get<size_t>(), 1000u);
  }
}

}  // namespace
}  // namespace tw
