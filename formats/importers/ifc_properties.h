// What IFC knows of each product beside its geometry (class, name, storey, property sets and
// quantities), written to the project database so that a pick reads it: the review side of the
// IFC import (ifc_importer.h draws the products).
#pragma once

#include <cstdint>
#include <filesystem>

namespace tw {

class ProjectDatabase;

// Each drawn product (isDrawnIfcProduct) under its GlobalId: a record (type: the IFC class,
// description: its Name) and properties: set "IFC" (Class, Name, ObjectType, Storey), its
// property sets (IfcPropertySingleValue and enumerated values, with units) and quantities
// (IfcElementQuantity). Returns the number of products written. Throws FormatError as readIfc
// does.
uint64_t writeIfcProperties(const std::filesystem::path& path, ProjectDatabase& database);

}  // namespace tw
