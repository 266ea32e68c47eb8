// The colours an IFC file gives its products, read once per file: the surface colour of each
// styled representation item (IfcStyledItem), and for products whose items carry none, their
// material's (IfcRelAssociatesMaterial, through layer, profile and constituent sets and lists,
// coloured by IfcMaterialDefinitionRepresentation), their type's (IfcRelDefinesByType), or that
// of the type whose representation map they draw. Authoring tools often colour walls and slabs
// through materials only. Colours are 0xAABBGGRR (sRGB), alpha from the style's transparency.
#pragma once

#include <cstdint>
#include <optional>
#include <unordered_map>

#include "step21_file.h"

namespace tw {

class IfcColours {
 public:
  explicit IfcColours(const Step21File& file);

  // The surface colour of representation item `item`, when an IfcStyledItem gives it one.
  std::optional<uint32_t> ofItem(uint64_t item) const { return find(item_, item); }
  // The colour product (or type) `object` takes from its material, or from its type's material.
  std::optional<uint32_t> ofMaterial(uint64_t object) const { return find(material_, object); }
  // The material colour of the type that owns representation map `map`.
  std::optional<uint32_t> ofRepresentationMap(uint64_t map) const { return find(map_, map); }

 private:
  using Colours = std::unordered_map<uint64_t, uint32_t>;
  static std::optional<uint32_t> find(const Colours& colours, uint64_t id) {
    auto it = colours.find(id);
    return it == colours.end() ? std::nullopt : std::optional<uint32_t>(it->second);
  }
  void readStyledItems();
  void readMaterials();
  std::optional<uint32_t> surfaceColour(const Step21Instance* style, int depth) const;
  std::optional<uint32_t> styledRepresentationsColour(const Step21Value& representations) const;
  std::optional<uint32_t> materialColour(const Step21Value& select, const Colours& of_material,
                                         int depth) const;

  const Step21File& f_;
  Colours item_;      // styled item -> colour
  Colours material_;  // product or type -> its material's colour
  Colours map_;       // representation map -> its type's material's colour
};

}  // namespace tw
