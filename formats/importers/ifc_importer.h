// IFC (2x3 and 4) import over our own Part 21 reader (step21_file.h), keeping parametric
// geometry parametric.
//
// What comes out, per IfcProduct with a body representation (openings, spaces, annotations and
// grids are not drawn):
// - its mesh items (faceted B-reps, shell and face based surface models, polygonal and
//   triangulated face sets) as one mesh object placed by the product's placement chain; its
//   primitive items as objects of their own with the same name and database key:
//   - an extruded rectangle is a box; an extruded circle or hollow circle is a cylinder (a pipe,
//     drawn by its outer wall); an extruded polyline is an extrusion of that profile; a revolved
//     circle is a torus segment (a bend); a revolved polyline is a revolution; CSG blocks,
//     cylinders and spheres are boxes, cylinders and spheres; a swept disk along a polyline is a
//     cylinder per segment;
//   - mapped items (IfcMappedItem) are expanded with their mapping;
// - name: the product's Name (else its class); database key: its GlobalId; layer: the
//   IfcPresentationLayerAssignment of its representation or items, else its IFC class;
//   colour: the IfcStyledItem surface colour of its first styled item.
// Not done: openings are not cut from their walls (IfcRelVoidsElement) and boolean clippings
// keep their first operand (each counted in one warning), oblique extrusions, curved profile
// edges (arcs of composite curves) and the voids of profiles are skipped or ignored with a
// warning naming the #id, and property sets are not read.
//
// Bad input: text that is not Part 21 is a FormatError naming the file and line; an item whose
// geometry fails (a missing reference, a degenerate profile) is skipped with a warning naming
// its #id and the product's class (ReadOptions::warn), and the rest imports. Placement chains
// and mapped items are followed to a bounded depth, so a loop cannot hang or overflow.
#pragma once

#include <filesystem>

#include "read_options.h"
#include "scene_sink.h"

namespace tw {

void readIfc(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options = {});

class ProjectDatabase;

// What IFC knows of each drawn product, into the project database under its GlobalId: a record
// (type: the IFC class, description: its Name) and properties: set "IFC" (Class, Name, Storey,
// ObjectType), its property sets (IfcPropertySingleValue and enumerated values, with units) and
// quantities (IfcElementQuantity). Returns the number of products written. Throws FormatError as
// readIfc does.
uint64_t writeIfcProperties(const std::filesystem::path& path, ProjectDatabase& database);

}  // namespace tw
