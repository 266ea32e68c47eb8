// `--viewpoint FILE.bcfzip[#N]`: a viewpoint of a BCF archive applied to a walkthrough's objects,
// for the verbs that render (render, bcf export). N counts viewpoints as `terawalk bcf list`
// numbers them, from 1.
#pragma once

#include <string>

#include "bcf_viewpoint.h"

namespace tw {

// Reads the archive (each item skipped is a warning on stderr), picks the viewpoint, applies it
// to `states` and prints each component skipped (the first ten, then a count). Throws
// std::runtime_error naming the archive when it has no viewpoint N, FormatError when it cannot be
// read.
ViewpointApplied applyViewpointOption(const std::string& text, const PackageView& view,
                                      ObjectStates& states, const Camera& base);

}  // namespace tw
