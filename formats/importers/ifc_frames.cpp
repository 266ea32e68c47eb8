// An IFC file's units and placements (ifc_frames.h).
#include "ifc_frames.h"

#include <cmath>
#include <map>
#include <string>

namespace tw {
namespace {

using part21::arg;
using part21::numberOf;
using part21::textOf;

double siPrefix(const std::string& p) {
  static const std::map<std::string, double> prefixes = {
      {"EXA", 1e18}, {"PETA", 1e15}, {"TERA", 1e12}, {"GIGA", 1e9}, {"MEGA", 1e6},
      {"KILO", 1e3}, {"HECTO", 1e2}, {"DECA", 1e1}, {"DECI", 1e-1}, {"CENTI", 1e-2},
      {"MILLI", 1e-3}, {"MICRO", 1e-6}, {"NANO", 1e-9}};
  auto it = prefixes.find(p);
  return it == prefixes.end() ? 1.0 : it->second;
}

}  // namespace

IfcFrames::IfcFrames(const Step21File& file) : f_(file) {
  for (uint64_t id : f_.idsOfType("IFCUNITASSIGNMENT")) {
    for (const Step21Value& u : arg(f_.find(id), 0).items) {
      const Step21Instance* unit = f_.deref(u);
      if (!unit) continue;
      const std::string type = textOf(arg(unit, 1));  // UnitType, in both kinds of unit
      const double scale = unitScale(unit, 0);
      if (scale <= 0.0) continue;
      if (type == "LENGTHUNIT") length_ = scale;
      if (type == "PLANEANGLEUNIT") angle_ = scale;
    }
    break;
  }
}

// Metres (or radians) per unit of an IfcSIUnit or IfcConversionBasedUnit, 0 if unknown.
double IfcFrames::unitScale(const Step21Instance* unit, int depth) const {
  if (!unit || depth > 4) return 0.0;
  if (unit->type == "IFCSIUNIT") return siPrefix(textOf(arg(unit, 2)));
  if (unit->type == "IFCCONVERSIONBASEDUNIT" || unit->type == "IFCCONVERSIONBASEDUNITWITHOFFSET") {
    const Step21Instance* measure = f_.deref(arg(unit, 3));
    if (!measure) return 0.0;
    const double value = numberOf(arg(measure, 0), 0.0);
    const double base = unitScale(f_.deref(arg(measure, 1)), depth + 1);
    return value * (base > 0.0 ? base : 1.0);
  }
  return 0.0;
}

glm::dvec3 IfcFrames::point(const Step21Instance* p) const {
  glm::dvec3 out(0.0);
  if (!p || p->type != "IFCCARTESIANPOINT") return out;
  const auto& c = arg(p, 0).items;
  for (size_t i = 0; i < 3 && i < c.size(); ++i) out[int(i)] = numberOf(c[i], 0.0) * length_;
  return out;
}

std::optional<glm::dvec3> IfcFrames::direction(const Step21Instance* d) const {
  if (!d || d->type != "IFCDIRECTION") return std::nullopt;
  glm::dvec3 out(0.0);
  const auto& c = arg(d, 0).items;
  for (size_t i = 0; i < 3 && i < c.size(); ++i) out[int(i)] = numberOf(c[i], 0.0);
  const double n = glm::length(out);
  if (!(n > 1e-12)) return std::nullopt;
  return out / n;
}

glm::dmat4 IfcFrames::frame(const glm::dvec3& origin, glm::dvec3 z, glm::dvec3 x) {
  z = glm::normalize(z);
  x = x - glm::dot(x, z) * z;
  if (glm::length(x) < 1e-9) {
    const glm::dvec3 helper = std::abs(z.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
    x = helper - glm::dot(helper, z) * z;
  }
  x = glm::normalize(x);
  const glm::dvec3 y = glm::cross(z, x);
  glm::dmat4 m(1.0);
  m[0] = glm::dvec4(x, 0.0);
  m[1] = glm::dvec4(y, 0.0);
  m[2] = glm::dvec4(z, 0.0);
  m[3] = glm::dvec4(origin, 1.0);
  return m;
}

glm::dmat4 IfcFrames::axisPlacement(const Step21Instance* a) const {
  if (!a) return glm::dmat4(1.0);
  const glm::dvec3 origin = point(f_.deref(arg(a, 0)));
  if (a->type == "IFCAXIS2PLACEMENT2D") {
    const glm::dvec3 x = direction(f_.deref(arg(a, 1))).value_or(glm::dvec3(1, 0, 0));
    return frame(origin, glm::dvec3(0, 0, 1), glm::dvec3(x.x, x.y, 0.0));
  }
  if (a->type != "IFCAXIS2PLACEMENT3D") return glm::dmat4(1.0);
  const glm::dvec3 z = direction(f_.deref(arg(a, 1))).value_or(glm::dvec3(0, 0, 1));
  const glm::dvec3 x = direction(f_.deref(arg(a, 2))).value_or(glm::dvec3(1, 0, 0));
  return frame(origin, z, x);
}

glm::dmat4 IfcFrames::placement(const Step21Instance* p, int depth) const {
  if (!p || depth > kMaxDepth || p->type != "IFCLOCALPLACEMENT") return glm::dmat4(1.0);
  return placement(f_.deref(arg(p, 0)), depth + 1) * axisPlacement(f_.deref(arg(p, 1)));
}

}  // namespace tw
