// IFC colours: styled items and materials. See ifc_colours.h.
#include "ifc_colours.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace tw {
namespace {

using Kind = Step21Value::Kind;
using part21::arg;
using part21::numberOf;

}  // namespace

IfcColours::IfcColours(const Step21File& file) : f_(file) {
  readStyledItems();
  readMaterials();
}

// The colour of an IfcPresentationStyleAssignment or IfcSurfaceStyle: its first shading's.
std::optional<uint32_t> IfcColours::surfaceColour(const Step21Instance* style, int depth) const {
  if (!style || depth > 4) return std::nullopt;
  if (style->type == "IFCPRESENTATIONSTYLEASSIGNMENT") {
    for (const Step21Value& s : arg(style, 0).items)
      if (auto c = surfaceColour(f_.deref(s), depth + 1)) return c;
    return std::nullopt;
  }
  if (style->type != "IFCSURFACESTYLE") return std::nullopt;
  for (const Step21Value& s : arg(style, 2).items) {
    const Step21Instance* shading = f_.deref(s);
    if (!shading || (shading->type != "IFCSURFACESTYLERENDERING" &&
                     shading->type != "IFCSURFACESTYLESHADING"))
      continue;
    const Step21Instance* rgb = f_.deref(arg(shading, 0));
    if (!rgb || rgb->type != "IFCCOLOURRGB") continue;
    auto channel = [&](size_t i) {
      return uint32_t(std::lround(std::clamp(numberOf(arg(rgb, i), 0.7), 0.0, 1.0) * 255.0));
    };
    const double transparency = std::clamp(numberOf(arg(shading, 1), 0.0), 0.0, 1.0);
    const uint32_t alpha = uint32_t(std::lround((1.0 - transparency) * 255.0));
    return channel(1) | (channel(2) << 8) | (channel(3) << 16) | (std::max(alpha, 1u) << 24);
  }
  return std::nullopt;
}

void IfcColours::readStyledItems() {
  for (uint64_t id : f_.idsOfType("IFCSTYLEDITEM")) {
    const Step21Instance* styled = f_.find(id);
    const Step21Value& item = arg(styled, 0);
    if (item.kind != Kind::Ref) continue;
    for (const Step21Value& s : arg(styled, 1).items)
      if (auto c = surfaceColour(f_.deref(s), 0)) {
        item_.emplace(item.ref, *c);
        break;
      }
  }
}

// Materials' colours from their styled representations, then the objects associated with each
// material, the objects of each coloured type, and the representation maps of each coloured type.
void IfcColours::readMaterials() {
  Colours of_material;
  for (uint64_t id : f_.idsOfType("IFCMATERIALDEFINITIONREPRESENTATION")) {
    const Step21Instance* definition = f_.find(id);
    const Step21Value& material = arg(definition, 3);
    if (material.kind != Kind::Ref || of_material.count(material.ref)) continue;
    if (auto c = styledRepresentationsColour(arg(definition, 2)))
      of_material.emplace(material.ref, *c);
  }
  if (of_material.empty()) return;
  for (uint64_t id : f_.idsOfType("IFCRELASSOCIATESMATERIAL")) {
    const Step21Instance* rel = f_.find(id);
    const auto c = materialColour(arg(rel, 5), of_material, 0);
    if (!c) continue;
    for (const Step21Value& object : arg(rel, 4).items)
      if (object.kind == Kind::Ref) material_.emplace(object.ref, *c);
  }
  // A product without a material of its own takes its type's (IfcRelDefinesByType).
  for (uint64_t id : f_.idsOfType("IFCRELDEFINESBYTYPE")) {
    const Step21Instance* rel = f_.find(id);
    const Step21Value& type = arg(rel, 5);
    auto it = material_.find(type.ref);
    if (type.kind != Kind::Ref || it == material_.end()) continue;
    const uint32_t c = it->second;
    for (const Step21Value& object : arg(rel, 4).items)
      if (object.kind == Kind::Ref) material_.emplace(object.ref, c);
  }
  // A type's representation maps (IfcTypeProduct's seventh attribute) drawn through mapped
  // items carry the type's material, whichever product maps them.
  for (const auto& [type, c] : material_) {
    const Step21Instance* t = f_.find(type);
    if (!t || t->type.size() < 4 || t->type.compare(t->type.size() - 4, 4, "TYPE") != 0) continue;
    for (const Step21Value& map : arg(t, 6).items)
      if (map.kind == Kind::Ref) map_.emplace(map.ref, c);
  }
}

// The first surface colour of a list of IfcStyledRepresentations' styled items.
std::optional<uint32_t> IfcColours::styledRepresentationsColour(
  const Step21Value& representations) const {
  for (const Step21Value& r : representations.items) {
    const Step21Instance* rep = f_.deref(r);
    if (!rep) continue;
    for (const Step21Value& i : arg(rep, 3).items) {
      const Step21Instance* styled = f_.deref(i);
      if (!styled || styled->type != "IFCSTYLEDITEM") continue;
      for (const Step21Value& s : arg(styled, 1).items)
        if (auto c = surfaceColour(f_.deref(s), 0)) return c;
    }
  }
  return std::nullopt;
}

// The colour of an IfcMaterialSelect (a reference): a material's own, else the first of its
// parts' that has one (a wall's layers from the first, the side a viewer usually sees).
std::optional<uint32_t> IfcColours::materialColour(const Step21Value& select,
                                                 const Colours& of_material, int depth) const {
  const Step21Instance* m = f_.deref(select);
  if (!m || depth > 6) return std::nullopt;
  const std::string& t = m->type;
  if (t == "IFCMATERIAL") {
    auto it = of_material.find(select.ref);
    return it == of_material.end() ? std::nullopt : std::optional<uint32_t>(it->second);
  }
  auto one = [&](const Step21Value& part) { return materialColour(part, of_material, depth + 1); };
  auto first = [&](const Step21Value& list) -> std::optional<uint32_t> {
    for (const Step21Value& part : list.items)
      if (auto c = one(part)) return c;
    return std::nullopt;
  };
  if (t == "IFCMATERIALLAYERSETUSAGE" || t == "IFCMATERIALPROFILESETUSAGE" ||
      t == "IFCMATERIALPROFILESETUSAGETAPERING" || t == "IFCMATERIALLAYER" ||
      t == "IFCMATERIALLAYERWITHOFFSETS")
    return one(arg(m, 0));
  if (t == "IFCMATERIALLAYERSET" || t == "IFCMATERIALLIST") return first(arg(m, 0));
  if (t == "IFCMATERIALPROFILE" || t == "IFCMATERIALPROFILEWITHOFFSETS" ||
      t == "IFCMATERIALCONSTITUENT")
    return one(arg(m, 2));
  if (t == "IFCMATERIALPROFILESET" || t == "IFCMATERIALCONSTITUENTSET") return first(arg(m, 2));
  return std::nullopt;
}

}  // namespace tw
