// `terawalk changes apply SCENE CHANGES.json -o NEW.tws`: a review's change set carried back into
// the scene (docs/review.md, "Change sets"). Each object whose database key (else name) a move
// names gets the move composed into its placement, exactly (the transform's origin in double,
// its linear part in the scene's float); a colour change becomes its colour. Hiding and comments
// have no place in a scene file and are counted, not written.
#include <cctype>
#include <cstdio>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>

#include "change_set.h"
#include "command.h"
#include "ifc_placement_writer.h"
#include "scene_io.h"
#include "tws_writer.h"
#include "up_axis.h"

namespace tw {
namespace {

struct ApplyArgs {
  std::string scene, changes, out;
  std::string up = "auto";
};

// Passes the scene through to the writer, placing and colouring the objects the changes name.
class ChangeApplier : public SceneSink {
 public:
  ChangeApplier(const ChangeSet& changes, SceneSink& out) : out_(out) {
    for (const std::string& key : changes.movedKeys()) moves_[key] = {changes.placement(key), 0};
    for (const Change& c : changes.changes())
      if (c.kind == Change::Kind::Colour) colours_[c.key] = {c.rgba, 0};
  }
  void onLayer(uint32_t index, const Layer& layer) override { out_.onLayer(index, layer); }
  void onObject(const SceneObject& object) override {
    const std::string& key = object.info.db_key.empty() ? object.info.name : object.info.db_key;
    const auto move = moves_.find(key);
    const auto colour = colours_.find(key);
    if (move == moves_.end() && colour == colours_.end()) {
      out_.onObject(object);
      return;
    }
    SceneObject changed = object;
    if (move != moves_.end()) {
      const glm::dmat4& m = move->second.first;
      Transform& t = changed.info.transform;
      t.origin = glm::dvec3(m * glm::dvec4(t.origin, 1.0));
      t.linear = glm::mat3(glm::dmat3(m) * glm::dmat3(t.linear));
      ++move->second.second;
    }
    if (colour != colours_.end()) {
      changed.info.color_rgba = colour->second.first;
      ++colour->second.second;
    }
    out_.onObject(changed);
  }
  // Keys that named no object of the scene.
  std::vector<std::string> unmatched() const {
    std::vector<std::string> keys;
    for (const auto& [key, m] : moves_)
      if (m.second == 0) keys.push_back(key);
    for (const auto& [key, c] : colours_)
      if (c.second == 0) keys.push_back(key);
    return keys;
  }
  size_t movedObjects() const {
    size_t n = 0;
    for (const auto& [key, m] : moves_) n += m.second;
    return n;
  }

 private:
  SceneSink& out_;
  std::map<std::string, std::pair<glm::dmat4, size_t>> moves_;
  std::map<std::string, std::pair<uint32_t, size_t>> colours_;
};

bool hasExtension(const std::string& path, const char* extension) {
  std::string e = std::filesystem::path(path).extension().string();
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e == extension;
}

// An IFC scene written back as IFC: the moved products placed anew (ifc_placement_writer.h).
void applyToIfc(const ApplyArgs& args, const ChangeSet& changes) {
  std::vector<std::pair<std::string, glm::dmat4>> moves;
  for (const std::string& key : changes.movedKeys()) moves.emplace_back(key, changes.placement(key));
  const IfcMoveReport report = writeMovedIfc(args.scene, args.out, moves);
  if (!report.missing.empty()) {
    std::filesystem::remove(args.out);
    throw std::runtime_error(args.changes + ": no product of " + args.scene + " has the GlobalId '" +
                             report.missing.front() + "'; nothing written");
  }
  size_t other = 0;
  for (const Change& c : changes.changes()) other += c.kind != Change::Kind::Move;
  std::printf("%s: %zu products placed anew (new absolute IfcLocalPlacements); %zu hide, colour "
              "and comment changes are review state, not written to the IFC\n",
              args.out.c_str(), report.moved, other);
}

void runApply(const ApplyArgs& args) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(args.out) && fs::equivalent(args.scene, args.out, ec))
    throw std::runtime_error("-o " + args.out + " is the scene being read; write to another file");
  const ChangeSet changes = readChangeSet(args.changes);
  if (changes.empty()) throw std::runtime_error(args.changes + ": no changes (or no such file)");
  if (hasExtension(args.scene, ".ifc") && hasExtension(args.out, ".ifc")) return applyToIfc(args, changes);
  TwsWriter writer(args.out);
  ChangeApplier applier(changes, writer);
  ReadOptions options;
  options.up = parseUpAxis(args.up);
  readScene(args.scene, applier, options);
  const std::vector<std::string> unmatched = applier.unmatched();
  if (!unmatched.empty())
    throw std::runtime_error(args.changes + ": no object of " + args.scene + " has the key '" +
                             unmatched.front() + "'" +
                             (unmatched.size() > 1 ? " (and " + std::to_string(unmatched.size() - 1) +
                                                         " more)" : "") + "; nothing written");
  writer.finish();
  size_t hides = 0, comments = 0;
  for (const Change& c : changes.changes()) {
    hides += c.kind == Change::Kind::Hide;
    comments += c.kind == Change::Kind::Comment;
  }
  std::printf("%s: %zu objects moved; colours applied; %zu hide and %zu comment changes are "
              "review state, not written to the scene\n",
              args.out.c_str(), applier.movedObjects(), hides, comments);
}

}  // namespace

void registerChangesCommand(CLI::App& app, const GlobalOptions&) {
  CLI::App* changes = app.add_subcommand("changes", "Carry a review's change set back to the scene");
  changes->require_subcommand(1);
  auto args = std::make_shared<ApplyArgs>();
  CLI::App* apply = changes->add_subcommand(
      "apply", "Write a copy of the scene with the change set's moves and colours applied (.tws); "
               "an IFC scene to an .ifc gets its moved products placed anew");
  apply->add_option("scene", args->scene, "Scene file the package was made from")
      ->required()->check(CLI::ExistingFile);
  apply->add_option("changes", args->changes, "Change set (model.changes.json)")
      ->required()->check(CLI::ExistingFile);
  apply->add_option("-o,--out", args->out, "New scene (.tws; .ifc for an IFC scene)")->required();
  apply->add_option("--up", args->up, "The scene file's up axis, as for preprocess")
      ->check(CLI::IsMember({"auto", "y", "z"}));
  apply->callback([args] { runApply(*args); });
}

}  // namespace tw
