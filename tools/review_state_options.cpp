// The review-state options (review_state_options.h).
#include "review_state_options.h"

#include <cstdlib>
#include <stdexcept>

#include "object_queries.h"
#include "snapshot_camera.h"

namespace tw {

void addReviewStateOptions(CLI::App& cmd, ReviewStateArgs& args) {
  cmd.add_option("--hide-layer", args.hide_layers, "Hide the objects of this layer (repeatable)")
      ->allow_extra_args(false);
  cmd.add_option("--isolate-layer", args.isolate_layers,
                 "Show only the objects of this layer (repeatable; with --isolate-keys, both)")
      ->allow_extra_args(false);
  cmd.add_option("--isolate-keys", args.isolate_keys,
                 "Show only the objects with these database keys: FILE (one a line) or K1,K2,...");
  cmd.add_option("--select", args.select_keys,
                 "Select (tint and outline) the objects with these database keys: FILE or "
                 "K1,K2,...");
  cmd.add_option("--colour", args.colours,
                 "Colour the objects with these database keys: RRGGBB=FILE or RRGGBB=K1,K2,... "
                 "(repeatable)")
      ->allow_extra_args(false);
  cmd.add_option("--section", args.sections,
                 "Cut the model open with a plane X,Y,Z,NX,NY,NZ (world metres; the normal points "
                 "to the side removed; repeatable, at most 6)")
      ->allow_extra_args(false);
  cmd.add_option("--section-box", args.section_box,
                 "Keep only what lies inside the box MIN MAX (x,y,z each, world metres)")
      ->expected(2);
  cmd.add_flag("--xray-others", args.xray_others,
               "Draw the objects not isolated (or, with --select alone, not selected) ghosted "
               "instead of hiding them");
}

void validateReviewStateArgs(const ReviewStateArgs& args) {
  if (args.xray_others && args.isolate_layers.empty() && args.isolate_keys.empty() &&
      args.select_keys.empty())
    throw std::runtime_error("--xray-others needs --isolate-layer, --isolate-keys or --select");
}

namespace {

// "RRGGBB=KEYS" -> 0xAABBGGRR (opaque) and the keys.
uint32_t parseColour(const std::string& text, std::string& keys) {
  const size_t eq = text.find('=');
  const std::string hex = text.substr(0, eq);
  char* end = nullptr;
  const unsigned long rgb = std::strtoul(hex.c_str(), &end, 16);
  if (eq == std::string::npos || hex.size() != 6 || *end != '\0' || eq + 1 == text.size())
    throw std::invalid_argument("--colour '" + text + "': expected RRGGBB=KEYS");
  keys = text.substr(eq + 1);
  return 0xff000000u | ((rgb & 0xff) << 16) | (rgb & 0xff00) | ((rgb >> 16) & 0xff);
}

}  // namespace

void applyReviewState(const ReviewStateArgs& args, const PackageView& view, ObjectStates& states) {
  const uint32_t others = args.xray_others ? kObjectXray : kObjectHidden;
  if (!args.isolate_layers.empty() || !args.isolate_keys.empty()) {
    states.setAll(others, true);
    for (const std::string& name : args.isolate_layers)
      for (uint32_t o : objectsOfLayer(view, layerIndex(view, name))) states.set(o, others, false);
    if (!args.isolate_keys.empty())
      for (uint32_t o : objectsWithKeys(view, parseKeyList(args.isolate_keys)))
        states.set(o, others, false);
  } else if (args.xray_others) {
    states.setAll(kObjectXray, true);  // selected objects stay opaque (object_states.h)
  }
  for (const std::string& name : args.hide_layers)
    for (uint32_t o : objectsOfLayer(view, layerIndex(view, name))) states.set(o, kObjectHidden, true);
  if (!args.select_keys.empty())
    for (uint32_t o : objectsWithKeys(view, parseKeyList(args.select_keys)))
      states.set(o, kObjectSelected, true);
  for (const std::string& text : args.colours) {
    std::string keys;
    const uint32_t rgba = parseColour(text, keys);
    for (uint32_t o : objectsWithKeys(view, parseKeyList(keys))) states.setColor(o, rgba);
  }
}

std::vector<SectionPlane> reviewSectionPlanes(const ReviewStateArgs& args) {
  if (args.sections.size() > kMaxUserSectionPlanes)
    throw std::invalid_argument("--section: " + std::to_string(args.sections.size()) +
                                " planes, at most " + std::to_string(kMaxUserSectionPlanes));
  std::vector<SectionPlane> planes;
  for (const std::string& text : args.sections) planes.push_back(parseSectionPlane(text));
  if (!args.section_box.empty()) {
    const glm::dvec3 lo = parseVec3(args.section_box[0]), hi = parseVec3(args.section_box[1]);
    if (glm::any(glm::greaterThan(lo, hi)))
      throw std::invalid_argument("--section-box: MIN " + args.section_box[0] +
                                  " is not below MAX " + args.section_box[1] + " on every axis");
    for (const SectionPlane& plane : sectionBoxPlanes(lo, hi)) planes.push_back(plane);
  }
  return planes;
}

std::vector<SectionPlane> withReviewSectionPlanes(std::vector<SectionPlane> planes,
                                                  const ReviewStateArgs& args) {
  const std::vector<SectionPlane> own = reviewSectionPlanes(args);
  planes.insert(planes.end(), own.begin(), own.end());
  if (planes.size() > kMaxSectionPlanes)
    throw std::invalid_argument(std::to_string(planes.size()) + " section planes, at most " +
                                std::to_string(kMaxSectionPlanes));
  return planes;
}

}  // namespace tw
