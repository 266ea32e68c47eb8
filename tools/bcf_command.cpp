// `terawalk bcf list|import|export`: BCF topics between a review and CAD tools (docs/review.md,
// "BCF"). list prints an archive's topics and numbers its viewpoints (as render --viewpoint takes
// them); import merges an archive into the review's own topics (model.review.bcfzip) and says
// which components the model has; export adds a topic made from a camera and review state (with
// a snapshot rendered headless) and writes the review's topics as BCF 2.1 or 3.0.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bcf_archive.h"
#include "bcf_ids.h"
#include "bcf_viewpoint.h"
#include "bcf_viewpoint_option.h"
#include "change_set_view.h"
#include "command.h"
#include "command_args.h"
#include "egl_context.h"
#include "frame_loop.h"
#include "image_compare.h"
#include "review_archive.h"
#include "review_state_options.h"
#include "snapshot_camera.h"

namespace tw {
namespace {

constexpr size_t kMostWarningsPrinted = 10;

void printWarnings(const std::vector<std::string>& warnings, bool quiet = false) {
  if (quiet) return;
  for (size_t i = 0; i < warnings.size() && i < kMostWarningsPrinted; ++i)
    std::fprintf(stderr, "terawalk: warning: %s\n", warnings[i].c_str());
  if (warnings.size() > kMostWarningsPrinted)
    std::fprintf(stderr, "terawalk: warning: ... and %zu more\n",
                 warnings.size() - kMostWarningsPrinted);
}

nlohmann::json vec(const glm::dvec3& v) { return {v.x, v.y, v.z}; }

nlohmann::json componentsJson(const std::vector<bcf::Component>& list) {
  nlohmann::json out = nlohmann::json::array();
  for (const bcf::Component& c : list)
    out.push_back(c.ifc_guid.empty() ? nlohmann::json{{"authoring_tool_id", c.authoring_tool_id}}
                                     : nlohmann::json{{"ifc_guid", c.ifc_guid}});
  return out;
}

nlohmann::json viewpointJson(const bcf::Viewpoint& v, size_t number) {
  nlohmann::json j = {{"number", number},
                      {"guid", v.guid},
                      {"selection", componentsJson(v.selection)},
                      {"default_visibility", v.default_visibility},
                      {"exceptions", componentsJson(v.exceptions)},
                      {"snapshot_bytes", v.snapshot_png.size()}};
  if (v.camera) {
    const bcf::Camera& c = *v.camera;
    j["camera"] = {{"kind", c.orthogonal ? "orthogonal" : "perspective"},
                   {"position", vec(c.position)},
                   {"direction", vec(c.direction)},
                   {"up", vec(c.up)}};
    if (c.orthogonal) j["camera"]["view_to_world_scale"] = c.view_to_world_scale;
    else j["camera"]["field_of_view_deg"] = c.field_of_view_deg;
  }
  nlohmann::json colours = nlohmann::json::array();
  for (const bcf::ColourGroup& g : v.colours) {
    char argb[9];
    std::snprintf(argb, sizeof argb, "%08X", g.argb);
    colours.push_back({{"argb", argb}, {"components", componentsJson(g.components)}});
  }
  j["colours"] = colours;
  nlohmann::json planes = nlohmann::json::array();
  for (const bcf::ClippingPlane& p : v.clipping_planes)
    planes.push_back({{"location", vec(p.location)}, {"direction", vec(p.direction)}});
  j["clipping_planes"] = planes;
  return j;
}

nlohmann::json archiveJson(const bcf::Archive& archive) {
  nlohmann::json topics = nlohmann::json::array();
  size_t number = 0;
  const std::vector<bcf::ViewpointRef> order = bcf::viewpointsInOrder(archive);
  for (const bcf::Topic& t : archive.topics) {
    nlohmann::json comments = nlohmann::json::array();
    for (const bcf::Comment& c : t.comments)
      comments.push_back({{"guid", c.guid}, {"author", c.author}, {"date", c.date}, {"text", c.text},
                          {"viewpoint", c.viewpoint_guid}});
    nlohmann::json views = nlohmann::json::array();
    for (const bcf::ViewpointRef& r : order)
      if (r.topic == &t) views.push_back(viewpointJson(*r.viewpoint, ++number));
    topics.push_back({{"guid", t.guid}, {"title", t.title}, {"status", t.status}, {"type", t.type},
                      {"author", t.creation_author}, {"date", t.creation_date},
                      {"description", t.description}, {"comments", comments},
                      {"viewpoints", views}});
  }
  return {{"version", archive.version_id}, {"topics", topics}};
}

// --- list ---

struct ListArgs {
  std::string file;
  bool json = false;
};

void runList(const ListArgs& args) {
  std::vector<std::string> warnings;
  const bcf::Archive archive = bcf::readArchive(args.file, warnings);
  printWarnings(warnings);
  const nlohmann::json j = archiveJson(archive);
  if (args.json) {
    std::printf("%s\n", j.dump(1).c_str());
    return;
  }
  std::printf("%s: BCF %s, %zu topics\n", args.file.c_str(),
              archive.version_id.empty() ? "(no version)" : archive.version_id.c_str(),
              archive.topics.size());
  for (const auto& t : j["topics"]) {
    std::printf("\n%s [%s] by %s, %s\n  %s\n", t["title"].get<std::string>().c_str(),
                t["status"].get<std::string>().c_str(), t["author"].get<std::string>().c_str(),
                t["date"].get<std::string>().c_str(), t["guid"].get<std::string>().c_str());
    for (const auto& c : t["comments"])
      std::printf("  comment by %s: %s\n", c["author"].get<std::string>().c_str(),
                  c["text"].get<std::string>().c_str());
    for (const auto& v : t["viewpoints"]) {
      std::string camera = "no camera";
      if (v.contains("camera")) {
        const auto& c = v["camera"];
        const auto& p = c["position"];
        char text[160];
        std::snprintf(text, sizeof text, "%s camera at (%.3f, %.3f, %.3f)",
                      c["kind"].get<std::string>().c_str(), p[0].get<double>(), p[1].get<double>(),
                      p[2].get<double>());
        camera = text;
      }
      std::printf("  #%zu %s; %zu selected, %s with %zu exceptions, %zu colours, %zu clipping "
                  "planes, snapshot %zu bytes\n",
                  v["number"].get<size_t>(), camera.c_str(), v["selection"].size(),
                  v["default_visibility"].get<bool>() ? "all visible" : "all hidden",
                  v["exceptions"].size(), v["colours"].size(), v["clipping_planes"].size(),
                  v["snapshot_bytes"].get<size_t>());
    }
  }
}

// The review's archive, or an empty one when there is none yet. An archive that cannot be read
// stops the command: it is never overwritten.
bcf::Archive readReviewArchive(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) return {};
  std::vector<std::string> warnings;
  bcf::Archive archive = bcf::readArchive(path, warnings);
  if (!warnings.empty())
    throw std::runtime_error(path.string() + ": the review's own topics do not read cleanly (" +
                             warnings.front() + "); move it away or mend it, it is not overwritten");
  return archive;
}

void writeReviewArchive(const std::filesystem::path& path, const bcf::Archive& archive) {
  std::vector<std::string> notes;
  bcf::writeArchive(path, archive, bcf::Version::V3_0, notes);
}

// --- import ---

struct ImportArgs {
  std::string package;
  std::string file;
  bool json = false;
};

void runImport(const ImportArgs& args, const GlobalOptions& global) {
  std::vector<std::string> warnings;
  const bcf::Archive incoming = bcf::readArchive(args.file, warnings);
  printWarnings(warnings);
  const PackageView view = PackageView::open(args.package);
  const ComponentIndex index(view);
  // Each viewpoint applied to a scratch state: which components the model has.
  nlohmann::json report = nlohmann::json::array();
  size_t number = 0;
  for (const bcf::ViewpointRef& r : bcf::viewpointsInOrder(incoming)) {
    ObjectStates states(view.objects().size());
    const ViewpointApplied applied = applyViewpoint(*r.viewpoint, index, states, Camera{});
    ++number;
    std::vector<std::string> prefixed;
    for (const std::string& w : applied.warnings)
      prefixed.push_back(args.file + "#" + std::to_string(number) + ": " + w);
    printWarnings(prefixed, global.quiet);
    report.push_back({{"number", number}, {"topic", r.topic->title}, {"components", applied.components},
                      {"components_unknown", applied.components_unknown},
                      {"objects_selected", applied.selected}, {"objects_hidden", applied.hidden},
                      {"objects_coloured", applied.coloured},
                      {"clipping_planes", applied.sections.size()}, {"camera", applied.has_camera}});
  }
  const std::filesystem::path store = reviewArchivePathFor(args.package);
  bcf::Archive review = readReviewArchive(store);
  const MergeCount merged = mergeTopics(review, incoming);
  writeReviewArchive(store, review);
  nlohmann::json out = {{"review", store.string()}, {"topics", review.topics.size()},
                        {"new_topics", merged.new_topics}, {"updated_topics", merged.updated_topics},
                        {"viewpoints", report}};
  if (args.json) {
    std::printf("%s\n", out.dump(1).c_str());
    return;
  }
  for (const auto& v : report)
    std::printf("#%zu %s: %zu of %zu components found; %u objects selected, %u hidden, %u "
                "coloured, %zu clipping planes%s\n",
                v["number"].get<size_t>(), v["topic"].get<std::string>().c_str(),
                v["components"].get<size_t>() - v["components_unknown"].get<size_t>(),
                v["components"].get<size_t>(), v["objects_selected"].get<unsigned>(),
                v["objects_hidden"].get<unsigned>(), v["objects_coloured"].get<unsigned>(),
                v["clipping_planes"].get<size_t>(), v["camera"].get<bool>() ? "" : ", no camera");
  std::printf("%s: %zu topics (%zu new, %zu updated)\n", store.string().c_str(),
              review.topics.size(), merged.new_topics, merged.updated_topics);
}

// --- export ---

struct ExportArgs {
  std::string package;
  std::string out;
  std::string version = "3.0";
  std::string title, status = "Open", type = "Issue", author, description;
  std::vector<std::string> comments;
  std::string eye, look_at;
  double fov_deg = 60.0;
  std::string viewpoint;  // FILE.bcfzip[#N]
  std::string size = "1280x720";
  std::string changes;  // a change set: one topic per object it names
  ReviewStateArgs state;
};

std::string defaultAuthor() {
  const char* user = std::getenv("USER");
  return user && *user ? user : "terawalk";
}

// The package opened headless at the snapshot size (--size).
struct HeadlessWalk {
  static WalkthroughOptions options(const ExportArgs& args) {
    WalkthroughOptions o;
    parseImageSize(args.size, "--size", o.width, o.height);
    return o;
  }
  explicit HeadlessWalk(const ExportArgs& args) : walk(args.package, options(args)) {}
  EglContext context;  // first: the walkthrough needs it current
  Walkthrough walk;
};

// The viewpoint of what `camera` sees now (states and `sections` as set on `walk`), the view
// rendered until the cut settles as its snapshot.
bcf::Viewpoint snapshotViewpoint(Walkthrough& walk, const Camera& camera,
                                 std::span<const SectionPlane> sections) {
  walk.renderSettled(camera);
  const GlRenderer& r = walk.renderer();
  std::vector<uint8_t> rgba;
  r.readColor(rgba, true);
  bcf::Viewpoint v = captureViewpoint(camera, double(r.width()) / r.height(), walk.objectStates(),
                                      ComponentIndex(walk.package()), sections);
  v.snapshot_png = encodePngRgba(r.width(), r.height(), rgba);
  return v;
}

// The new topic's viewpoint and snapshot: the package opened headless, the viewpoint and state
// options applied, the camera's view rendered until the cut settles.
bcf::Viewpoint renderViewpoint(const ExportArgs& args) {
  HeadlessWalk headless(args);
  Walkthrough& walk = headless.walk;
  const glm::dvec3 lo = walk.worldMin(), hi = walk.worldMax();
  Camera camera;
  camera.far_m = std::max(100.0, 10.0 * glm::length(hi - lo));
  std::vector<SectionPlane> sections;
  if (!args.viewpoint.empty()) {
    const ViewpointApplied applied =
        applyViewpointOption(args.viewpoint, walk.package(), walk.objectStates(), camera);
    camera = applied.camera;
    sections = applied.sections;
  }
  if (!args.eye.empty()) {
    camera.position = parseVec3(args.eye);
    camera.fov_y_rad = args.fov_deg * std::numbers::pi / 180.0;
    camera.lookAt(args.look_at.empty() ? 0.5 * (lo + hi) : parseVec3(args.look_at));
  }
  applyReviewState(args.state, walk.package(), walk.objectStates());
  sections = withReviewSectionPlanes(std::move(sections), args.state);
  walk.setSections(sections);
  return snapshotViewpoint(walk, camera, sections);
}

// One topic per object a change set names, in the order first named: what changed (moves with
// their translation, hiding, colour), its comments, and a viewpoint on the object at its new
// place, selected, with a snapshot drawn with the changes applied.
std::vector<bcf::Topic> changeTopics(const ExportArgs& args, const ChangeSet& changes) {
  HeadlessWalk headless(args);
  Walkthrough& walk = headless.walk;
  const PackageView& view = walk.package();
  applyChangeStates(changes, view, walk.objectStates());
  walk.setMovedObjects(movedMeshes(changes, view));
  std::vector<std::string> keys;
  for (const Change& c : changes.changes())
    if (std::find(keys.begin(), keys.end(), c.key) == keys.end()) keys.push_back(c.key);
  std::vector<bcf::Topic> topics;
  for (const std::string& key : keys) {
    bcf::Topic topic;
    topic.guid = bcf::newGuid();
    topic.type = "Change";
    topic.status = "Open";
    std::string what;
    for (const Change& c : changes.changes()) {
      if (c.key != key) continue;
      if (topic.creation_date.empty()) {
        topic.creation_date = c.date.empty() ? bcf::utcNow() : c.date;
        topic.creation_author = c.author.empty() ? defaultAuthor() : c.author;
      }
      char line[256];
      if (c.kind == Change::Kind::Move) {
        const glm::dvec3 t = c.new_pivot - c.old_pivot;
        std::snprintf(line, sizeof line, "moved by (%.3f, %.3f, %.3f) m, centre (%.3f, %.3f, %.3f) to (%.3f, %.3f, %.3f)",
                      t.x, t.y, t.z, c.old_pivot.x, c.old_pivot.y, c.old_pivot.z, c.new_pivot.x,
                      c.new_pivot.y, c.new_pivot.z);
        what += std::string(what.empty() ? "" : "; ") + line;
      } else if (c.kind == Change::Kind::Hide) {
        what += std::string(what.empty() ? "" : "; ") + (c.hidden ? "hidden" : "shown");
      } else if (c.kind == Change::Kind::Colour) {
        std::snprintf(line, sizeof line, "recoloured %08X (ABGR)", c.rgba);
        what += std::string(what.empty() ? "" : "; ") + line;
      } else {
        topic.comments.push_back({bcf::newGuid(), c.date.empty() ? bcf::utcNow() : c.date,
                                  c.author.empty() ? defaultAuthor() : c.author, c.text, "", "", ""});
      }
    }
    topic.title = (what.rfind("moved", 0) == 0 ? "Moved " : "Changed ") + key;
    topic.description = what.empty() ? "comments on " + key : key + ": " + what;

    // The camera frames the object where it stands now, from the south-west and above.
    const std::vector<uint32_t> objects = objectsOfChangeKey(view, key);
    glm::dvec3 lo, hi;
    Camera camera;
    if (!movedBounds(view, objects, changes.placement(key), lo, hi))
      throw std::runtime_error(args.changes + ": '" + key + "' has no geometry to look at");
    const glm::dvec3 centre = 0.5 * (lo + hi);
    const double radius = std::max(0.5 * glm::length(hi - lo), 0.1);
    camera.position = centre + glm::normalize(glm::dvec3(-1.0, -1.0, 0.7)) *
                                   (1.6 * radius / std::tan(0.5 * camera.fov_y_rad));
    camera.far_m = std::max(100.0, 10.0 * glm::length(walk.worldMax() - walk.worldMin()));
    camera.lookAt(centre);
    ObjectStates& states = walk.objectStates();
    states.setAll(kObjectSelected, false);
    for (uint32_t o : objects) states.set(o, kObjectSelected, true);
    bcf::Viewpoint v = snapshotViewpoint(walk, camera, {});
    for (bcf::Comment& c : topic.comments) c.viewpoint_guid = v.guid;
    topic.viewpoints.push_back(std::move(v));
    topics.push_back(std::move(topic));
  }
  return topics;
}

void runExport(const ExportArgs& args) {
  const bcf::Version version = args.version == "2.1" ? bcf::Version::V2_1 : bcf::Version::V3_0;
  if (args.title.empty() && (!args.comments.empty() || !args.eye.empty() || !args.viewpoint.empty()))
    throw std::runtime_error("a new topic needs --title");
  if (!args.title.empty() && args.eye.empty() && args.viewpoint.empty())
    throw std::runtime_error("a new topic needs a camera: --eye X,Y,Z [--look-at X,Y,Z] or --viewpoint FILE.bcfzip[#N]");
  validateReviewStateArgs(args.state);
  const std::filesystem::path store = reviewArchivePathFor(args.package);
  bcf::Archive review = readReviewArchive(store);  // before any work: an unreadable one stops us
  if (!args.title.empty()) {
    bcf::Topic topic;
    topic.guid = bcf::newGuid();
    topic.title = args.title;
    topic.status = args.status;
    topic.type = args.type;
    topic.creation_author = args.author.empty() ? defaultAuthor() : args.author;
    topic.creation_date = bcf::utcNow();
    topic.description = args.description;
    topic.files.push_back({std::filesystem::path(args.package).filename().string(), "", "", ""});
    topic.viewpoints.push_back(renderViewpoint(args));
    for (const std::string& text : args.comments)
      topic.comments.push_back({bcf::newGuid(), topic.creation_date, topic.creation_author, text,
                                topic.viewpoints.front().guid, "", ""});
    review.topics.push_back(std::move(topic));
    writeReviewArchive(store, review);
  }
  if (!args.changes.empty()) {
    const ChangeSet changes = readChangeSet(args.changes);
    if (changes.empty()) throw std::runtime_error(args.changes + ": no changes (or no such file)");
    for (bcf::Topic& topic : changeTopics(args, changes)) review.topics.push_back(std::move(topic));
    writeReviewArchive(store, review);
  }
  if (review.topics.empty())
    throw std::runtime_error(store.string() + ": the review has no topics yet; give --title to make one");
  std::vector<std::string> notes;
  bcf::writeArchive(args.out, review, version, notes);
  printWarnings(notes);
  std::printf("%s: BCF %s, %zu topics\n", args.out.c_str(), args.version.c_str(), review.topics.size());
}

}  // namespace

void registerBcfCommand(CLI::App& app, const GlobalOptions& global) {
  CLI::App* bcf = app.add_subcommand("bcf", "BCF topics: list an archive, import one into the "
                                            "review, export the review's topics");
  bcf->require_subcommand(1);

  auto list = std::make_shared<ListArgs>();
  CLI::App* l = bcf->add_subcommand("list", "Print an archive's topics, comments and numbered viewpoints");
  l->add_option("file", list->file, "BCF archive (.bcfzip)")->required()->check(CLI::ExistingFile);
  l->add_flag("--json", list->json, "Print JSON");
  l->callback([list] { runList(*list); });

  auto import = std::make_shared<ImportArgs>();
  CLI::App* i = bcf->add_subcommand(
      "import", "Merge an archive's topics into the review's (model.review.bcfzip), saying which "
                "of its components the model has");
  i->add_option("package", import->package, "Package (.twk)")->required()->check(CLI::ExistingFile);
  i->add_option("file", import->file, "BCF archive (.bcfzip)")->required()->check(CLI::ExistingFile);
  i->add_flag("--json", import->json, "Print JSON");
  i->callback([import, &global] { runImport(*import, global); });

  auto ex = std::make_shared<ExportArgs>();
  CLI::App* e = bcf->add_subcommand(
      "export", "Write the review's topics as BCF; with --title, first add a topic from a camera "
                "and review state, with a snapshot rendered headless");
  e->add_option("package", ex->package, "Package (.twk)")->required()->check(CLI::ExistingFile);
  e->add_option("-o,--out", ex->out, "BCF archive to write (.bcfzip)")->required();
  e->add_option("--version", ex->version, "BCF version")->check(CLI::IsMember({"2.1", "3.0"}))
      ->capture_default_str();
  e->add_option("--title", ex->title, "Add a topic with this title");
  e->add_option("--status", ex->status, "The new topic's status")->capture_default_str();
  e->add_option("--type", ex->type, "The new topic's type")->capture_default_str();
  e->add_option("--author", ex->author, "The new topic's author (default: $USER)");
  e->add_option("--description", ex->description, "The new topic's description");
  e->add_option("--comment", ex->comments, "A comment on the new topic (repeatable)")
      ->allow_extra_args(false);
  e->add_option("--eye", ex->eye, "Camera position X,Y,Z (world metres)");
  e->add_option("--look-at", ex->look_at, "Point the camera looks at X,Y,Z (default: the model's centre)");
  e->add_option("--fov", ex->fov_deg, "Vertical field of view, degrees")->check(CLI::Range(1.0, 170.0));
  e->add_option("--viewpoint", ex->viewpoint,
                "Start from a BCF viewpoint (FILE.bcfzip[#N]): camera, selection, visibility, "
                "colours, clipping planes");
  e->add_option("--size", ex->size, "Snapshot size WIDTHxHEIGHT")->capture_default_str();
  e->add_option("--changes", ex->changes,
                "Add a topic per object a change set (model.changes.json) names: what changed, "
                "its comments, a viewpoint on it at its new place")
      ->check(CLI::ExistingFile);
  addReviewStateOptions(*e, ex->state);
  e->callback([ex] { runExport(*ex); });
}

}  // namespace tw
