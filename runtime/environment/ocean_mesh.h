// The ocean's mesh for one eye position: a base square subdivided recursively, finer near the
// eye, with no T-vertex and no popping.
//
// Why this shape (ENVIRON's ocean, with Strugar's CDLOD geomorphing): the water reaches the
// horizon, so a uniform grid is either too coarse at the hull or too large to draw. A quadtree
// node splits while the eye is closer than range_factor times its side; neighbouring leaves
// differ by at most one level (the tree is balanced), and each leaf is a grid of
// cells_per_node^2 cells whose diagonals all run the same way. Where a leaf meets a coarser one,
// its odd border vertices are replaced by their even neighbours, so every edge is shared by two
// triangles or lies on the outer border.
//
// Geomorphing: a vertex that a coarser level will not have slides, as the eye moves away, onto
// the neighbour it collapses into (the one below it in x and y), reaching it exactly where its
// leaf merges into its parent (and on every border with a coarser leaf). So when leaves split or
// merge, the surface is already the coarser one, and heights change continuously with the eye.
// The slide of a vertex is a function of its position alone (its lattice point and the eye), so
// two leaves sharing it agree.
//
// Built on the CPU each frame (tens of thousands of vertices); the waves are added on the GPU.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

struct OceanGridOptions {
  glm::dvec2 center{0.0};        // world XY of the base square's centre
  double size_m = 32768.0;       // its side
  double waterline_m = 0.0;      // world Z of still water
  int cells_per_node = 8;        // a leaf is this many cells a side (even)
  double finest_node_m = 4.0;    // leaves are never smaller (the side is rounded to size / 2^n)
  double range_factor = 1.5;     // a node splits while the eye is closer than this times its side
  double morph_start = 0.6;      // share of the merge distance at which a vertex starts to slide
  bool geomorph = true;          // false: vertices never slide (for comparison: it pops)
};

// Each leaf has its own (cells + 1)^2 vertices; a lattice point shared by leaves is repeated at
// the same position, bit for bit, so the surface is closed and welding by position gives one
// mesh (what the T-vertex test does).
struct OceanMesh {
  std::vector<glm::dvec2> positions;  // still-water XY of each vertex, world, after sliding
  std::vector<uint32_t> indices;      // triangles, counter-clockwise seen from above
  uint32_t leaves = 0;                // drawn
  uint32_t culled_leaves = 0;         // outside the frustum
  uint32_t deepest_level = 0;         // of a leaf; 0 = the base square
};

// Throws std::invalid_argument naming the option when a size is not positive and finite, the
// cells per node not even and 2..64, the range factor below 1 or the morph start not in [0, 1).
void validateOceanGrid(const OceanGridOptions& options);

// What a frame sees, to leave out the leaves it cannot: projection * view rotation (the
// renderer's eye-relative frame, reversed Z), and how far the waves may move the water from its
// still place (sum of amplitudes, metres), which the leaves' boxes grow by.
struct OceanFrustum {
  glm::dmat4 view_projection{1.0};
  double wave_reach_m = 0.0;
};

// The mesh seen from `eye` (world). Call validateOceanGrid first. With `frustum`, leaves wholly
// outside it are left out (the tree, and so the stitching, stay those of the whole square). The
// second form refills `mesh`, keeping its vectors' memory (once a frame, without allocating).
OceanMesh buildOceanMesh(const OceanGridOptions& options, const glm::dvec3& eye);
void buildOceanMesh(const OceanGridOptions& options, const glm::dvec3& eye, OceanMesh& mesh,
                    const OceanFrustum* frustum = nullptr);

// The size of the mesh's cells at `distance_m` from the eye (smooth in the distance; what the
// waves fade by, gerstner_waves.h): the finest cell near the eye, growing linearly beyond.
double oceanCellSizeAt(const OceanGridOptions& options, double distance_m);

}  // namespace tw
