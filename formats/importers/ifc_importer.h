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
//     circle is a torus segment (a bend); a revolved polyline is a revolution; a steel section
//     (I, L, T, U, C, Z: steel_profiles.h) is an extrusion of its outline; CSG blocks,
//     cylinders and spheres are boxes, cylinders and spheres; a swept disk along a polyline is a
//     cylinder per segment;
//   - an extrusion of a profile with voids, or along an oblique direction, is a closed mesh
//     prism (profile_prism.h) within the product's mesh;
//   - mapped items (IfcMappedItem) are expanded with their mapping;
// - name: the product's Name (else its class); database key: its GlobalId; layer: the
//   IfcPresentationLayerAssignment of its representation or items, else its IFC class;
//   colour: the IfcStyledItem surface colour of its first styled item.
// - openings (IfcRelVoidsElement) are cut from the product they void, and boolean differences
//   and intersections (IfcBooleanResult, IfcBooleanClippingResult, half-spaces included) are
//   computed by OpenCASCADE (solid_cut.h); the product is then one mesh; a cut that fails
//   keeps the first operand with a warning naming the #id;
// - faces with holes keep their holes.
// Not done: other profile types (ellipses, trapezia, derived and composite profiles) are skipped
// with a warning naming the #id.
// Property sets go to the project database (ifc_properties.h).
//
// Bad input: text that is not Part 21 is a FormatError naming the file and line; an item whose
// geometry fails (a missing reference, a degenerate profile) is skipped with a warning naming
// its #id and the product's class (ReadOptions::warn), and the rest imports. Placement chains
// and mapped items are followed to a bounded depth, so a loop cannot hang or overflow.
#pragma once

#include <filesystem>

#include "read_options.h"
#include "step21_file.h"
#include "scene_sink.h"

namespace tw {

void readIfc(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options = {});

// Whether `instance` is a product the importer draws: an IfcProduct (recognized by its
// attributes' layout) with a representation, not an opening, space, annotation, grid, virtual
// element or site. The property export (ifc_properties.h) keys the same products.
bool isDrawnIfcProduct(const Step21File& file, const Step21Instance& instance);

}  // namespace tw
