// IFC's parameterized steel sections (I, L, T, U, C and Z) as the polygons they outline.
//
// Plant and building models frame their structure in rolled steel; IFC writes each member as an
// extrusion of an IfcIShapeProfileDef, IfcLShapeProfileDef, ... given by its dimensions alone.
// The outline makes the member an Extrusion primitive, which the runtime keeps parametric. Root
// fillets and edge radii are left out (sharp corners): at a few millimetres on a section tens of
// centimetres deep they are below the scene's chordal tolerance for anything but a close look.
#pragma once

#include <optional>
#include <stdexcept>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

enum class SteelSection { I, L, T, U, C, Z };

// The section an IFC profile class names (IFCISHAPEPROFILEDEF ... IFCZSHAPEPROFILEDEF,
// IFCASYMMETRICISHAPEPROFILEDEF excepted), or none.
std::optional<SteelSection> steelSectionOf(std::string_view ifc_type);

class SteelSectionError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// The outline, counter-clockwise, centred on its bounding box as IFC places these profiles, from
// the dimensions in the order IFC lists them after Position (already in metres; later optional
// ones may be missing or NaN):
//   I: OverallWidth, OverallDepth, WebThickness, FlangeThickness
//   L: Depth, Width (Depth when missing), Thickness
//   T: Depth, FlangeWidth, WebThickness, FlangeThickness
//   U: Depth, FlangeWidth, WebThickness, FlangeThickness
//   C: Depth, Width, WallThickness, Girth
//   Z: Depth, FlangeWidth, WebThickness, FlangeThickness
// X is the width, Y the depth; U and C open towards +X, L's legs run along +X and +Y from its
// corner, Z's top flange points to +X. Throws SteelSectionError naming what does not fit (a web
// thicker than the flange is wide, a missing dimension).
std::vector<glm::dvec2> steelSectionOutline(SteelSection section, const std::vector<double>& dimensions);

}  // namespace tw
