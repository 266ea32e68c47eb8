// `--viewpoint FILE.bcfzip[#N]` (bcf_viewpoint_option.h).
#include "bcf_viewpoint_option.h"

#include <cstdio>
#include <stdexcept>

#include "bcf_archive.h"

namespace tw {
namespace {

constexpr size_t kMostWarningsPrinted = 10;

void printWarnings(const std::vector<std::string>& warnings) {
  for (size_t i = 0; i < warnings.size() && i < kMostWarningsPrinted; ++i)
    std::fprintf(stderr, "terawalk: warning: %s\n", warnings[i].c_str());
  if (warnings.size() > kMostWarningsPrinted)
    std::fprintf(stderr, "terawalk: warning: ... and %zu more\n", warnings.size() - kMostWarningsPrinted);
}

}  // namespace

ViewpointApplied applyViewpointOption(const std::string& text, const PackageView& view,
                                      ObjectStates& states, const Camera& base) {
  std::string file = text;
  size_t number = 1;
  const size_t hash = text.rfind('#');
  if (hash != std::string::npos && hash + 1 < text.size() &&
      text.find_first_not_of("0123456789", hash + 1) == std::string::npos) {
    file = text.substr(0, hash);
    number = std::stoul(text.substr(hash + 1));
  }
  std::vector<std::string> warnings;
  const bcf::Archive archive = bcf::readArchive(file, warnings);
  printWarnings(warnings);
  const std::vector<bcf::ViewpointRef> views = bcf::viewpointsInOrder(archive);
  if (number == 0 || number > views.size())
    throw std::runtime_error(file + ": no viewpoint " + std::to_string(number) + " (it has " +
                             std::to_string(views.size()) + ")");
  const ViewpointApplied applied = applyViewpoint(*views[number - 1].viewpoint, ComponentIndex(view), states, base);
  std::vector<std::string> prefixed;
  for (const std::string& w : applied.warnings) prefixed.push_back(file + "#" + std::to_string(number) + ": " + w);
  printWarnings(prefixed);
  return applied;
}

}  // namespace tw
