// The ocean's quadtree mesh (ocean_mesh.h).
#include "ocean_mesh.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_set>

namespace tw {
namespace {

// Node keys: depth in the top 8 bits, then x and y in 28 bits each.
constexpr int kMaxDepth = 24;
uint64_t nodeKey(int depth, int64_t x, int64_t y) {
  return uint64_t(depth) << 56 | uint64_t(x) << 28 | uint64_t(y);
}

struct Node {
  int depth;
  int64_t x, y;
};

// The grid everything is placed on: integer lattice points, one per finest cell corner.
struct Lattice {
  glm::dvec2 corner{0.0};  // world XY of lattice point (0, 0)
  double cell_m = 1.0;     // finest cell
  int depth = 0;           // of the finest leaves
  int cells = 8;           // per leaf side
  int64_t size = 8;        // lattice points per side - 1 (cells << depth)
  int top_level = 0;       // level of the base square's cells: log2(size / cells)

  glm::dvec2 point(int64_t i, int64_t j) const { return corner + glm::dvec2(double(i), double(j)) * cell_m; }
  double nodeSide(int node_depth) const { return cell_m * double(cells) * double(int64_t(1) << (depth - node_depth)); }
};

Lattice makeLattice(const OceanGridOptions& o) {
  Lattice l;
  l.cells = o.cells_per_node;
  l.depth = std::clamp(int(std::lround(std::log2(o.size_m / o.finest_node_m))), 0, kMaxDepth);
  l.size = int64_t(l.cells) << l.depth;
  l.cell_m = o.size_m / double(l.size);
  l.corner = o.center - glm::dvec2(0.5 * o.size_m);
  l.top_level = l.depth;  // cells of a depth-0 leaf are 2^depth lattice steps
  return l;
}

double distanceToSquare(const glm::dvec3& eye, const glm::dvec2& lo, double side, double z) {
  const glm::dvec2 e(eye);
  const glm::dvec2 nearest = glm::clamp(e, lo, lo + glm::dvec2(side));
  return glm::length(glm::dvec3(nearest - e, z - eye.z));
}

// The quadtree: every node that exists (split or leaf), split by distance, then balanced.
class OceanTree {
 public:
  OceanTree(const OceanGridOptions& o, const Lattice& l, const glm::dvec3& eye) : o_(o), l_(l) {
    splitByDistance({0, 0, 0}, eye);
    balance();
  }

  bool exists(int depth, int64_t x, int64_t y) const { return nodes_.count(nodeKey(depth, x, y)) > 0; }
  bool isLeaf(const Node& n) const { return n.depth == l_.depth || !exists(n.depth + 1, 2 * n.x, 2 * n.y); }
  std::vector<Node> leaves() const {
    std::vector<Node> out;
    for (const Node& n : list_)
      if (isLeaf(n)) out.push_back(n);
    return out;
  }
  // Whether the leaf's neighbour across an edge (dx, dy) is coarser than the leaf.
  bool coarserAcross(const Node& n, int dx, int dy) const {
    const int64_t count = int64_t(1) << n.depth;
    const int64_t nx = n.x + dx, ny = n.y + dy;
    if (n.depth == 0 || nx < 0 || ny < 0 || nx >= count || ny >= count) return false;
    return !exists(n.depth, nx, ny);
  }

 private:
  void add(const Node& n) {
    if (nodes_.insert(nodeKey(n.depth, n.x, n.y)).second) list_.push_back(n);
  }
  void splitByDistance(const Node& n, const glm::dvec3& eye) {
    add(n);
    if (n.depth == l_.depth) return;
    const double side = l_.nodeSide(n.depth);
    const glm::dvec2 lo = l_.corner + glm::dvec2(double(n.x), double(n.y)) * side;
    if (distanceToSquare(eye, lo, side, o_.waterline_m) >= o_.range_factor * side) return;
    for (int c = 0; c < 4; ++c) splitByDistance({n.depth + 1, 2 * n.x + (c & 1), 2 * n.y + (c >> 1)}, eye);
  }
  // Splits leaves until no leaf has a neighbour more than one level coarser.
  void balance() {
    for (bool changed = true; changed;) {
      changed = false;
      for (size_t i = 0; i < list_.size(); ++i) {
        const Node n = list_[i];
        if (n.depth < 2 || !isLeaf(n)) continue;
        const int64_t count = int64_t(1) << n.depth;
        for (const auto& [dx, dy] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
          const int64_t nx = n.x + dx, ny = n.y + dy;
          if (nx < 0 || ny < 0 || nx >= count || ny >= count) continue;
          // The node one level up that holds the neighbour must exist; else split down to it.
          Node up{n.depth - 1, nx >> 1, ny >> 1};
          if (exists(up.depth, up.x, up.y)) continue;
          Node leaf = up;
          while (!exists(leaf.depth, leaf.x, leaf.y)) leaf = {leaf.depth - 1, leaf.x >> 1, leaf.y >> 1};
          for (int c = 0; c < 4; ++c) add({leaf.depth + 1, 2 * leaf.x + (c & 1), 2 * leaf.y + (c >> 1)});
          changed = true;
        }
      }
    }
  }

  const OceanGridOptions& o_;
  const Lattice& l_;
  std::unordered_set<uint64_t> nodes_;
  std::vector<Node> list_;
};

// Where each lattice point lies after sliding: a function of the point and the eye alone, so
// every leaf that holds the point computes the same position, bit for bit.
class OceanSlide {
 public:
  OceanSlide(const OceanGridOptions& o, const Lattice& l, const glm::dvec3& eye) : o_(o), l_(l), eye_(eye) {}

  // The point slides towards its parent, which may itself slide towards its own: walk up the
  // chain while each link slides, then fold the positions back down.
  glm::dvec2 position(int64_t i, int64_t j) const {
    struct Link {
      glm::dvec2 at;
      double k;
    };
    Link chain[64];
    int links = 0;
    for (;;) {
      const glm::dvec2 at = l_.point(i, j);
      const int level = nativeLevel(i, j);
      const double k = level < l_.top_level ? slide(level, at) : 0.0;
      chain[links++] = {at, k};
      if (k == 0.0) break;
      const int64_t step = int64_t(1) << level;
      if ((i >> level) & 1) i -= step;
      if ((j >> level) & 1) j -= step;
    }
    glm::dvec2 p = chain[links - 1].at;
    for (int c = links - 2; c >= 0; --c) p = chain[c].at + chain[c].k * (p - chain[c].at);
    return p;
  }

 private:
  // The level at which the point first appears: its cells are 2^level lattice steps. Each
  // parent's level is higher, so a chain has at most top_level + 1 links.
  int nativeLevel(int64_t i, int64_t j) const {
    const int level = std::min(i == 0 ? 63 : std::countr_zero(uint64_t(i)),
                               j == 0 ? 63 : std::countr_zero(uint64_t(j)));
    return std::min(level, l_.top_level);
  }
  // How far the point has slid towards its parent: 0 near, 1 from where its leaves merge.
  double slide(int level, const glm::dvec2& at) const {
    if (!o_.geomorph) return 0.0;
    const double leaf_side = l_.cell_m * double(l_.cells) * double(int64_t(1) << level);
    const double merge_distance = 2.0 * o_.range_factor * leaf_side;
    const double d = glm::length(glm::dvec3(at - glm::dvec2(eye_), o_.waterline_m - eye_.z));
    return std::clamp((d / merge_distance - o_.morph_start) / (1.0 - o_.morph_start), 0.0, 1.0);
  }

  const OceanGridOptions& o_;
  const Lattice& l_;
  glm::dvec3 eye_;
};

// A leaf's vertices and triangles: its grid, diagonals from (a, b) to (a+1, b+1), with the odd
// vertices of a border shared with a coarser leaf replaced by the even ones below them. Border
// vertices are repeated in each leaf that holds them, at the same position.
void appendLeaf(const OceanTree& tree, const Node& n, const Lattice& l, const OceanSlide& slide,
                OceanMesh& mesh) {
  const int cells = l.cells, side = cells + 1;
  const int64_t step = int64_t(1) << (l.depth - n.depth);
  const int64_t i0 = n.x * cells * step, j0 = n.y * cells * step;
  const uint32_t first = uint32_t(mesh.positions.size());
  for (int b = 0; b <= cells; ++b)
    for (int a = 0; a <= cells; ++a) mesh.positions.push_back(slide.position(i0 + a * step, j0 + b * step));
  const bool west = tree.coarserAcross(n, -1, 0), east = tree.coarserAcross(n, 1, 0);
  const bool south = tree.coarserAcross(n, 0, -1), north = tree.coarserAcross(n, 0, 1);
  auto vertex = [&](int a, int b) {
    if (((a == 0 && west) || (a == cells && east)) && (b & 1)) --b;
    if (((b == 0 && south) || (b == cells && north)) && (a & 1)) --a;
    return first + uint32_t(b * side + a);
  };
  auto triangle = [&](uint32_t p, uint32_t q, uint32_t r) {
    if (p == q || q == r || r == p) return;  // collapsed by the stitching
    mesh.indices.insert(mesh.indices.end(), {p, q, r});
  };
  for (int b = 0; b < cells; ++b)
    for (int a = 0; a < cells; ++a) {
      const uint32_t v00 = vertex(a, b), v10 = vertex(a + 1, b);
      const uint32_t v01 = vertex(a, b + 1), v11 = vertex(a + 1, b + 1);
      triangle(v00, v10, v11);
      triangle(v00, v11, v01);
    }
}

// Whether the leaf's box (its square, grown by the waves' reach, from the waterline down and up
// by it), eye-relative, lies wholly outside one of the frustum's side planes or behind the near
// plane: every corner fails the same clip test (reversed Z: 0 <= z <= w, x and y within +-w).
bool outsideFrustum(const OceanFrustum& f, const Node& n, const Lattice& l, double waterline,
                    const glm::dvec3& eye) {
  const double side = l.nodeSide(n.depth), reach = f.wave_reach_m;
  const glm::dvec2 lo = l.corner + glm::dvec2(double(n.x), double(n.y)) * side - glm::dvec2(reach) - glm::dvec2(eye);
  const glm::dvec2 hi = lo + glm::dvec2(side + 2.0 * reach);
  const double z0 = waterline - reach - eye.z, z1 = waterline + reach - eye.z;
  int outside[5] = {0, 0, 0, 0, 0};
  for (int c = 0; c < 8; ++c) {
    const glm::dvec4 p = f.view_projection * glm::dvec4(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? z1 : z0, 1.0);
    outside[0] += p.x < -p.w;
    outside[1] += p.x > p.w;
    outside[2] += p.y < -p.w;
    outside[3] += p.y > p.w;
    outside[4] += p.z > p.w;  // in front of the near plane (reversed Z: depth 1 there)
  }
  for (int plane : outside)
    if (plane == 8) return true;
  return false;
}

}  // namespace

void validateOceanGrid(const OceanGridOptions& o) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("ocean: " + what); };
  if (!(std::isfinite(o.size_m) && o.size_m > 0.0 && o.size_m <= 1e7)) fail("the size must be above 0 and at most 1e7 m");
  if (!(std::isfinite(o.finest_node_m) && o.finest_node_m > 0.0)) fail("the finest node must be above 0 m");
  if (!std::isfinite(o.center.x) || !std::isfinite(o.center.y) || !std::isfinite(o.waterline_m))
    fail("the centre and the waterline must be numbers");
  if (o.cells_per_node < 2 || o.cells_per_node > 64 || o.cells_per_node % 2 != 0)
    fail("cells per node must be even, 2 to 64");
  if (!(o.range_factor >= 1.0 && o.range_factor <= 16.0)) fail("the range factor must be 1 to 16");
  if (!(o.morph_start >= 0.0 && o.morph_start < 1.0)) fail("the morph start must be in [0, 1)");
}

OceanMesh buildOceanMesh(const OceanGridOptions& options, const glm::dvec3& eye) {
  OceanMesh mesh;
  buildOceanMesh(options, eye, mesh);
  return mesh;
}

void buildOceanMesh(const OceanGridOptions& options, const glm::dvec3& eye, OceanMesh& mesh,
                    const OceanFrustum* frustum) {
  const Lattice lattice = makeLattice(options);
  const OceanTree tree(options, lattice, eye);
  const OceanSlide slide(options, lattice, eye);
  mesh.positions.clear();
  mesh.indices.clear();
  mesh.leaves = 0;
  mesh.culled_leaves = 0;
  mesh.deepest_level = 0;
  for (const Node& leaf : tree.leaves()) {
    if (frustum && outsideFrustum(*frustum, leaf, lattice, options.waterline_m, eye)) {
      ++mesh.culled_leaves;
      continue;
    }
    appendLeaf(tree, leaf, lattice, slide, mesh);
    ++mesh.leaves;
    mesh.deepest_level = std::max(mesh.deepest_level, uint32_t(leaf.depth));
  }
}

double oceanCellSizeAt(const OceanGridOptions& options, double distance_m) {
  const Lattice lattice = makeLattice(options);
  return std::max(lattice.cell_m, distance_m / (options.range_factor * options.cells_per_node));
}

}  // namespace tw
