// IFC's steel sections as polygons. See steel_profiles.h.
#include "steel_profiles.h"

#include <cmath>
#include <string>

namespace tw {
namespace {

bool positiveFinite(double v) { return std::isfinite(v) && v > 0.0; }

// Dimension `i`, which must be a positive length.
double required(const std::vector<double>& d, size_t i, const char* name) {
  if (i >= d.size() || !positiveFinite(d[i])) throw SteelSectionError(std::string("no positive ") + name);
  return d[i];
}

void require(bool holds, const char* what) {
  if (!holds) throw SteelSectionError(what);
}

// Points given from the bounding box's lower left corner, moved to centre it.
std::vector<glm::dvec2> centred(std::vector<glm::dvec2> pts, double width, double depth) {
  for (glm::dvec2& p : pts) p -= glm::dvec2(0.5 * width, 0.5 * depth);
  return pts;
}

std::vector<glm::dvec2> iSection(const std::vector<double>& d) {
  const double b = required(d, 0, "overall width"), h = required(d, 1, "overall depth");
  const double tw = required(d, 2, "web thickness"), tf = required(d, 3, "flange thickness");
  require(tw < b, "a web as wide as the flanges");
  require(2.0 * tf < h, "flanges that meet");
  const double w0 = 0.5 * (b - tw), w1 = 0.5 * (b + tw);
  return centred({{0, 0}, {b, 0}, {b, tf}, {w1, tf}, {w1, h - tf}, {b, h - tf}, {b, h}, {0, h},
                  {0, h - tf}, {w0, h - tf}, {w0, tf}, {0, tf}},
                 b, h);
}

std::vector<glm::dvec2> lSection(const std::vector<double>& d) {
  const double h = required(d, 0, "depth");
  const double b = d.size() > 1 && positiveFinite(d[1]) ? d[1] : h;
  const double t = required(d, 2, "thickness");
  require(t < b && t < h, "legs thinner than the thickness");
  return centred({{0, 0}, {b, 0}, {b, t}, {t, t}, {t, h}, {0, h}}, b, h);
}

std::vector<glm::dvec2> tSection(const std::vector<double>& d) {
  const double h = required(d, 0, "depth"), b = required(d, 1, "flange width");
  const double tw = required(d, 2, "web thickness"), tf = required(d, 3, "flange thickness");
  require(tw < b, "a web as wide as the flange");
  require(tf < h, "a flange as deep as the section");
  const double w0 = 0.5 * (b - tw), w1 = 0.5 * (b + tw);
  return centred({{w0, 0}, {w1, 0}, {w1, h - tf}, {b, h - tf}, {b, h}, {0, h}, {0, h - tf}, {w0, h - tf}}, b, h);
}

std::vector<glm::dvec2> uSection(const std::vector<double>& d) {
  const double h = required(d, 0, "depth"), b = required(d, 1, "flange width");
  const double tw = required(d, 2, "web thickness"), tf = required(d, 3, "flange thickness");
  require(tw < b, "a web as wide as the flanges");
  require(2.0 * tf < h, "flanges that meet");
  return centred({{0, 0}, {b, 0}, {b, tf}, {tw, tf}, {tw, h - tf}, {b, h - tf}, {b, h}, {0, h}}, b, h);
}

std::vector<glm::dvec2> cSection(const std::vector<double>& d) {
  const double h = required(d, 0, "depth"), b = required(d, 1, "width");
  const double t = required(d, 2, "wall thickness"), g = required(d, 3, "girth");
  require(2.0 * t < b, "walls that meet across the width");
  require(t < g && 2.0 * g < h, "lips that do not fit the depth");
  return centred({{0, 0}, {b, 0}, {b, g}, {b - t, g}, {b - t, t}, {t, t}, {t, h - t}, {b - t, h - t},
                  {b - t, h - g}, {b, h - g}, {b, h}, {0, h}},
                 b, h);
}

std::vector<glm::dvec2> zSection(const std::vector<double>& d) {
  const double h = required(d, 0, "depth"), b = required(d, 1, "flange width");
  const double tw = required(d, 2, "web thickness"), tf = required(d, 3, "flange thickness");
  require(tw < b, "a web as wide as the flanges");
  require(2.0 * tf < h, "flanges that meet");
  const double w = 2.0 * b - tw;  // the bottom flange to the left of the web, the top one right
  const double w0 = b - tw;
  return centred({{0, 0}, {b, 0}, {b, h - tf}, {w, h - tf}, {w, h}, {w0, h}, {w0, tf}, {0, tf}}, w, h);
}

}  // namespace

std::optional<SteelSection> steelSectionOf(std::string_view ifc_type) {
  if (ifc_type == "IFCISHAPEPROFILEDEF") return SteelSection::I;
  if (ifc_type == "IFCLSHAPEPROFILEDEF") return SteelSection::L;
  if (ifc_type == "IFCTSHAPEPROFILEDEF") return SteelSection::T;
  if (ifc_type == "IFCUSHAPEPROFILEDEF") return SteelSection::U;
  if (ifc_type == "IFCCSHAPEPROFILEDEF") return SteelSection::C;
  if (ifc_type == "IFCZSHAPEPROFILEDEF") return SteelSection::Z;
  return std::nullopt;
}

std::vector<glm::dvec2> steelSectionOutline(SteelSection section, const std::vector<double>& dimensions) {
  switch (section) {
    case SteelSection::I: return iSection(dimensions);
    case SteelSection::L: return lSection(dimensions);
    case SteelSection::T: return tSection(dimensions);
    case SteelSection::U: return uSection(dimensions);
    case SteelSection::C: return cSection(dimensions);
    case SteelSection::Z: return zSection(dimensions);
  }
  throw SteelSectionError("an unknown section");
}

}  // namespace tw
