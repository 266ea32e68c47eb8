// Exact repeats of a triangle: the same three vertices (by position) in the same cyclic order as
// an earlier triangle of the same mesh.
//
// Why: CAD exports write some solids twice (a third of duplex-mep's 335,822 triangles repeat
// another). A copy adds nothing to the image, but it makes each of its edges non-manifold, which
// stops edge collapse there, confuses the winding pass (it may turn one copy, leaving a two-sided
// pair) and costs memory and drawing at every level. The preprocessor drops repeats before the
// winding pass; the DAG builder drops those left in its welded input. A triangle and its reversed
// twin (a sheet drawn from both sides) are both kept.
#pragma once

#include <cstdint>
#include <vector>

#include "scene.h"

namespace tw {

// Triangles (index t for mesh.indices[3t..3t+2]) that repeat an earlier one, increasing.
std::vector<uint32_t> repeatedTriangles(const TriangleMesh& mesh);

// The same on welded triangles (three vertex indices each, one object id each): removes the
// repeats in place, keeping the first copy with its id; returns how many were removed.
uint64_t dropRepeatedTriangles(std::vector<uint32_t>& tris, std::vector<uint32_t>& ids);

// A copy of `mesh` without the listed triangles (increasing), vertices unchanged.
TriangleMesh withoutTriangles(const TriangleMesh& mesh, const std::vector<uint32_t>& triangles);

}  // namespace tw
