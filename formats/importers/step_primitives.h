// Whole B-rep solids that are primitives of the scene model, recognized from their faces so a
// STEP part stays parametric: a capped cylinder (cylindrical faces of one axis and radius closed
// by two planar discs), a capped cone or frustum (conical faces of one axis closed by one or two
// discs), a sphere (spherical faces of one centre and radius covering the whole sphere), a torus
// segment (a pipe elbow: toroidal faces closed by two discs in planes through its axis, or a
// whole ring) and a box (six rectangles, pairwise opposite along three perpendicular axes).
//
// Why: a plant's pipes, vessels and structural members are such solids; kept as primitives they
// cost a hundred bytes each in the package instead of their triangles, are drawn at the
// resolution the distance needs, and stay measurable as what they are (an axis, a radius).
// Anything else (a cylinder with a hole, a chamfered rod, a stepped shaft) is not a primitive
// and is meshed; a recognizer that accepts a near miss would draw the wrong part.
#pragma once

#include <optional>

#include <TopoDS_Shape.hxx>

#include "scene.h"

namespace tw {

struct RecognizedPrimitive {
  Primitive primitive;
  Transform frame;  // the primitive's canonical frame in the shape's coordinates
};

// `solid` is one TopoDS_Solid (or a shape holding exactly one, with nothing else that has faces).
// `tolerance` is the largest distance, in the shape's units, by which the faces may miss the
// primitive (parameters compared within it). Returns nothing when it is not one of the above.
std::optional<RecognizedPrimitive> recognizePrimitive(const TopoDS_Shape& solid, double tolerance);

}  // namespace tw
