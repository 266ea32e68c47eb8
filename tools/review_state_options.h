// The options that set what a reviewer sees of a model, shared by the verbs that render it
// (render, bcf export): hidden, isolated, selected and X-rayed objects, and section planes.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "object_states.h"
#include "package_view.h"
#include "section_planes.h"

namespace tw {

struct ReviewStateArgs {
  std::vector<std::string> hide_layers;
  std::vector<std::string> isolate_layers;
  std::string isolate_keys;  // FILE or KEY,KEY,...
  std::string select_keys;
  bool xray_others = false;
  std::vector<std::string> colours;      // RRGGBB=KEYS each
  std::vector<std::string> sections;     // X,Y,Z,NX,NY,NZ each
  std::vector<std::string> section_box;  // MIN MAX, x,y,z each
};

void addReviewStateOptions(CLI::App& cmd, ReviewStateArgs& args);
// Throws std::runtime_error for combinations that mean nothing (--xray-others alone).
void validateReviewStateArgs(const ReviewStateArgs& args);

// Isolating hides every object but those named (layers and keys together), or X-rays them with
// --xray-others (which, with a selection alone, X-rays all but the selection); hiding then hides
// the layers named; --select selects; --colour recolours. Applied on top of what `states` holds.
// Throws std::invalid_argument for an unknown layer or a bad colour.
void applyReviewState(const ReviewStateArgs& args, const PackageView& view, ObjectStates& states);

// --section (each a plane) and --section-box (six planes facing out of the box), world metres.
std::vector<SectionPlane> reviewSectionPlanes(const ReviewStateArgs& args);
// `planes` (a viewpoint's) followed by the options' own; throws std::invalid_argument past
// kMaxSectionPlanes in all.
std::vector<SectionPlane> withReviewSectionPlanes(std::vector<SectionPlane> planes,
                                                  const ReviewStateArgs& args);

}  // namespace tw
