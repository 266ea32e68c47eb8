// Section planes and boxes. See section_planes.h.
#include "section_planes.h"

#include <charconv>
#include <cmath>
#include <stdexcept>

namespace tw {

std::array<SectionPlane, 6> sectionBoxPlanes(const glm::dvec3& min, const glm::dvec3& max) {
  return {SectionPlane{min, {-1.0, 0.0, 0.0}}, SectionPlane{max, {1.0, 0.0, 0.0}},
          SectionPlane{min, {0.0, -1.0, 0.0}}, SectionPlane{max, {0.0, 1.0, 0.0}},
          SectionPlane{min, {0.0, 0.0, -1.0}}, SectionPlane{max, {0.0, 0.0, 1.0}}};
}

SectionPlane parseSectionPlane(const std::string& text) {
  std::vector<double> values;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = text.find(',', start);
    const std::string part =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    double value = 0.0;
    const char* begin = part.data() + (part.starts_with('+') ? 1 : 0);
    const auto [end, error] = std::from_chars(begin, part.data() + part.size(), value);
    if (part.empty() || error != std::errc() || end != part.data() + part.size() || !std::isfinite(value))
      throw std::invalid_argument("section plane '" + text + "': '" + part +
                                  "' is not a finite number");
    values.push_back(value);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (values.size() != 6)
    throw std::invalid_argument("section plane '" + text +
                                "': expected X,Y,Z,NX,NY,NZ (six numbers), got " +
                                std::to_string(values.size()));
  const glm::dvec3 normal(values[3], values[4], values[5]);
  const double length = glm::length(normal);
  if (!(length > 0.0) || !std::isfinite(length))
    throw std::invalid_argument("section plane '" + text + "': the normal is zero");
  return SectionPlane{glm::dvec3(values[0], values[1], values[2]), normal / length};
}

}  // namespace tw
