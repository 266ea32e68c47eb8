// The GPU form of a mesh cluster's vertices: each vertex carries, in the word the package uses
// for its octahedral normal, the local index of a triangle of the vertex's own object.
//
// Why: the mesh fragment shader used to find a pixel's object (and from it the colour) by reading
// the per-triangle object table at gl_PrimitiveID, two table reads per fragment. On llvmpipe a
// table read indexed per pixel is a scalar loop over the vector's lanes, and it cost about a
// tenth of a decks frame (docs/runtime.md, "Objects per vertex"). With the tag the vertex shader
// reads the object once per vertex and hands object and colour to the fragments as flat inputs,
// taken from each triangle's provoking (last) vertex.
// How: a vertex used by triangles of one object is tagged with the first such triangle; a vertex
// that triangles of different objects share (rare: the preprocessor keeps objects' vertices
// apart, coarse levels merge a few) gets kSharedVertexTag. Each triangle is rotated, winding
// kept, so that its last vertex is one of its own where it has one; a triangle all of whose
// vertices are shared is left as it is, and its fragments read the table as before.
// The GPU never reads the normal word otherwise; CPU users of a cluster decode it themselves.
#pragma once

#include <cstdint>
#include <span>

#include "package_format.h"

namespace tw {

inline constexpr uint16_t kSharedVertexTag = 0xffff;  // never a triangle index (<= 65534)

// Tags `vertices` and rotates `indices` (3 per triangle, local to the cluster) in place;
// triangle_objects has one entry per triangle. Indices out of range are left alone (the decoder
// has rejected them already). Returns the triangles whose last vertex is still shared.
uint32_t tagVertexObjects(std::span<pkg::EncodedVertex> vertices, std::span<uint16_t> indices,
                          std::span<const uint32_t> triangle_objects);

// The tag stored in a vertex (for tests and tools).
uint16_t vertexObjectTag(const pkg::EncodedVertex& vertex);

}  // namespace tw
