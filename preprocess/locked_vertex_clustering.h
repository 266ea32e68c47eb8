// Topology-free simplification with chosen vertices held in place: vertex clustering on a uniform
// grid, each cell's vertices merged onto the one of them that its summed quadric prefers, the grid
// size searched so the result lands just under a target triangle count.
//
// Why it exists: meshopt_simplifySloppy (meshoptimizer 0.18, what Debian ships) cannot lock
// vertices, so the DAG builder could use it only on components touching no other group. CAD
// groups are mostly made of small parts that touch their neighbours' groups, so those groups
// stalled and whole levels fell back to one far proxy. Here the group's border vertices stay
// where they are (each in a cell of its own), and every other vertex may merge with any vertex
// of its cell, which joins and removes small parts as the grid coarsens.
//
// Guarantees: locked vertices never move and no other vertex merges onto them, so a triangle
// on a locked edge keeps that edge. The directed edges of the result balance wherever those of
// the input did (a degenerate triangle is dropped and a pair of opposite triangles, one of them
// moved, cancels). Vertices of unbalanced input edges (open or odd non-manifold edges: the rims
// of uncapped pipes, sheets), marked by markRimVertices, merge only with each other, so every
// edge the result uses once joins two rim vertices: a part's own hole may change its outline,
// but no hole opens inside a surface and nothing moves where the group meets the others.
//
// Error: the largest distance a vertex moved to its cell's representative, object space.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

struct VertexClusteringResult {
  std::vector<uint32_t> tris;             // three per triangle, into the input positions
  std::vector<uint32_t> source_triangle;  // per output triangle: the input triangle it came from
  float error = 0.0f;                     // largest vertex displacement
  double grid_cells = 0.0;                // cells along the longest axis of the chosen grid
};

// Per vertex, bit flags: kRimVertex (on an unbalanced edge: merges only with other rim vertices),
// kLockedVertex (never moves, nothing merges onto it). 0: free.
enum VertexRole : uint8_t { kFreeVertex = 0, kRimVertex = 1, kLockedVertex = 2 };

// Simplifies `tris` (indices into positions) to the count nearest target_triangles that does not
// pass most_triangles (< target_triangles: taken as target_triangles) where the locked vertices
// allow, else to the fewest the coarsest grid gives. roles: one per position.
VertexClusteringResult simplifyByLockedVertexClustering(std::span<const glm::vec3> positions,
                                                        std::span<const uint32_t> tris,
                                                        std::span<const uint8_t> roles,
                                                        size_t target_triangles,
                                                        size_t most_triangles = 0);

// Adds kRimVertex to both vertices of every edge whose uses in one direction do not match its
// uses in the other (open edges, odd non-manifold edges, the group's own border).
void markRimVertices(std::span<const uint32_t> tris, std::vector<uint8_t>& roles);

}  // namespace tw
