// Minimum distances between objects of a package. See object_distance.h.
#include "object_distance.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "format_error.h"
#include "instance_primitive.h"
#include "page_codec.h"
#include "tessellate.h"

namespace tw {
namespace {

struct Box {
  glm::dvec3 lo{INFINITY}, hi{-INFINITY};
  void add(const glm::dvec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
};

Box boxOf(const Triangle3d& t) {
  Box b;
  for (const glm::dvec3& p : t) b.add(p);
  return b;
}

// The distance between two boxes (0 where they overlap): a lower bound for anything inside.
double boxDistance(const Box& a, const Box& b) {
  const glm::dvec3 gap = glm::max(glm::max(a.lo - b.hi, b.lo - a.hi), glm::dvec3(0.0));
  return glm::length(gap);
}

// A bounding volume hierarchy over triangles: median splits on the longest axis of the
// centroids, leaves of up to 8 triangles.
class TriangleTree {
 public:
  explicit TriangleTree(const std::vector<Triangle3d>& triangles) : triangles_(triangles) {
    order_.resize(triangles.size());
    for (uint32_t i = 0; i < order_.size(); ++i) order_[i] = i;
    if (order_.empty()) return;
    nodes_.resize(1);
    build(0, 0, uint32_t(order_.size()));
  }

  // Lowers `best` to the closest pair between `t` and the tree's triangles, if closer.
  void closest(const Triangle3d& t, PointPair& best) const {
    if (nodes_.empty()) return;
    const Box box = boxOf(t);
    uint32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& node = nodes_[stack[--top]];
      if (boxDistance(box, node.box) >= best.distance) continue;
      if (node.count > 0) {
        for (uint32_t i = node.first; i < node.first + node.count; ++i) {
          const PointPair p = closestBetweenTriangles(t, triangles_[order_[i]]);
          if (p.distance < best.distance) best = p;
        }
        continue;
      }
      // The nearer child last, so it is searched first.
      const double dl = boxDistance(box, nodes_[node.left].box);
      const double dr = boxDistance(box, nodes_[node.left + 1].box);
      stack[top++] = dl < dr ? node.left + 1 : node.left;
      stack[top++] = dl < dr ? node.left : node.left + 1;
    }
  }

 private:
  struct Node {
    Box box;
    uint32_t first = 0, count = 0;  // a leaf's triangles in order_ (count 0: inner node)
    uint32_t left = 0;              // an inner node's children: left and left + 1
  };

  // Fills node `index` with triangles [first, first + count) of order_, splitting it further
  // into two children allocated side by side.
  void build(uint32_t index, uint32_t first, uint32_t count) {
    Box box, centres;
    for (uint32_t i = first; i < first + count; ++i) {
      const Triangle3d& t = triangles_[order_[i]];
      for (const glm::dvec3& p : t) box.add(p);
      centres.add((t[0] + t[1] + t[2]) / 3.0);
    }
    nodes_[index].box = box;
    // Median splits halve every node, so the depth stays far below the traversal stack's 64.
    if (count <= 8) {
      nodes_[index].first = first;
      nodes_[index].count = count;
      return;
    }
    const glm::dvec3 extent = centres.hi - centres.lo;
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
    const uint32_t half = count / 2;
    std::nth_element(order_.begin() + first, order_.begin() + first + half,
                     order_.begin() + first + count, [&](uint32_t a, uint32_t b) {
                       const Triangle3d &ta = triangles_[a], &tb = triangles_[b];
                       return ta[0][axis] + ta[1][axis] + ta[2][axis] <
                              tb[0][axis] + tb[1][axis] + tb[2][axis];
                     });
    const uint32_t left = uint32_t(nodes_.size());
    nodes_.resize(nodes_.size() + 2);
    nodes_[index].left = left;
    build(left, first, half);
    build(left + 1, first + half, count - half);
  }

  const std::vector<Triangle3d>& triangles_;
  std::vector<uint32_t> order_;
  std::vector<Node> nodes_;
};

// A cylinder instance as its axis and radius, when its placement keeps it round (orthogonal
// columns of one length): the closed form applies only to a true circular cylinder.
std::optional<CylinderAxis> roundCylinder(const pkg::InstanceRecord& in) {
  if (in.type != uint32_t(pkg::PrimitiveType::Cylinder)) return std::nullopt;
  const glm::dmat3 m(instanceLinear(in));
  const double sx = glm::length(m[0]), sy = glm::length(m[1]);
  const double tolerance = 1e-6 * std::max(sx, sy);
  if (std::abs(sx - sy) > tolerance || std::abs(glm::dot(m[0], m[1])) > tolerance * sx ||
      std::abs(glm::dot(m[0], m[2])) > tolerance * glm::length(m[2]) * sx ||
      std::abs(glm::dot(m[1], m[2])) > tolerance * glm::length(m[2]) * sy)
    return std::nullopt;
  const glm::dvec3 base(in.origin[0], in.origin[1], in.origin[2]);
  return CylinderAxis{base, base + m * glm::dvec3(0.0, 0.0, in.params[1]), in.params[0] * sx};
}

std::vector<uint8_t> objectMask(const PackageView& view, std::span<const uint32_t> objects) {
  std::vector<uint8_t> mask(view.objects().size(), 0);
  for (uint32_t o : objects)
    if (o < mask.size()) mask[o] = 1;
  return mask;
}

// The level-0 mesh triangles of the masked objects, page by page.
void appendMeshTriangles(const PackageView& view, const std::vector<uint8_t>& mask,
                         std::vector<Triangle3d>& out) {
  std::vector<uint32_t> clusters;
  for (uint32_t c = 0; c < view.clusters().size(); ++c) {
    const pkg::ClusterRecord& r = view.clusters()[c];
    if (r.level != 0 || r.kind != uint8_t(pkg::ClusterKind::Mesh)) continue;
    for (uint32_t o = r.object_min; o <= r.object_max && o < mask.size(); ++o)
      if (mask[o]) {
        clusters.push_back(c);
        break;
      }
  }
  std::sort(clusters.begin(), clusters.end(), [&](uint32_t a, uint32_t b) {
    return view.clusters()[a].page < view.clusters()[b].page;
  });
  std::vector<uint8_t> scratch;
  std::span<const uint8_t> raw;
  uint32_t loaded = pkg::kNone;
  DecodedCluster decoded;
  for (uint32_t c : clusters) {
    const pkg::ClusterRecord& r = view.clusters()[c];
    if (r.page != loaded) {
      raw = view.loadPage(r.page, scratch);
      loaded = r.page;
    }
    const DecodeStatus status =
        decodeCluster(raw.subspan(r.page_offset, r.encoded_bytes), view.positionStepM(),
                      uint32_t(view.objects().size()), decoded);
    if (!status.ok())
      throw FormatError(view.fileName(), "cluster " + std::to_string(c) + " of page " +
                                             std::to_string(r.page) + " does not decode: " +
                                             status.error);
    for (size_t t = 0; t < decoded.triangle_objects.size(); ++t) {
      if (!mask[decoded.triangle_objects[t]]) continue;
      Triangle3d tri;
      for (int k = 0; k < 3; ++k) tri[k] = glm::dvec3(decoded.positions[decoded.indices[3 * t + k]]);
      out.push_back(tri);
    }
  }
}

glm::dvec3 world(const PackageView& view, const glm::dvec3& p) { return view.origin() + p; }

}  // namespace

MeasureShape measureShape(const PackageView& view, std::span<const uint32_t> objects,
                          double chordal_tolerance_m) {
  const std::vector<uint8_t> mask = objectMask(view, objects);
  MeasureShape shape;
  appendMeshTriangles(view, mask, shape.triangles);
  TriangleMesh mesh;
  for (const pkg::InstanceRecord& in : view.instances()) {
    if (in.object >= mask.size() || !mask[in.object]) continue;
    ++shape.parametric_instances;
    if (auto cylinder = roundCylinder(in)) shape.cylinders.push_back(*cylinder);
    mesh = TriangleMesh{};
    tessellatePrimitive(primitiveOf(in, view.profilePoints()), float(chordal_tolerance_m), mesh);
    const glm::dmat3 linear(instanceLinear(in));
    const glm::dvec3 origin(in.origin[0], in.origin[1], in.origin[2]);
    for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
      Triangle3d tri;
      for (int k = 0; k < 3; ++k)
        tri[k] = origin + linear * glm::dvec3(mesh.positions[mesh.indices[i + k]]);
      shape.triangles.push_back(tri);
    }
    shape.tessellation_error_m = chordal_tolerance_m;
  }
  return shape;
}

MeasuredDistance minimumDistance(const PackageView& view, const MeasureShape& a,
                                 const MeasureShape& b) {
  if (a.triangles.empty() || b.triangles.empty())
    throw std::invalid_argument("nothing to measure: an object has no geometry");
  MeasuredDistance result;
  result.points.distance = INFINITY;
  // Triangles: every one of the smaller set against a tree of the larger.
  const bool a_smaller = a.triangles.size() <= b.triangles.size();
  const std::vector<Triangle3d>& queries = a_smaller ? a.triangles : b.triangles;
  const TriangleTree tree(a_smaller ? b.triangles : a.triangles);
  for (const Triangle3d& t : queries) tree.closest(t, result.points);
  if (!a_smaller) std::swap(result.points.a, result.points.b);
  result.method = "triangles";
  result.error_bound_m = a.tessellation_error_m + b.tessellation_error_m;
  // Cylinders in closed form: exact, and never farther than their (inscribed) tessellations.
  for (const CylinderAxis& ca : a.cylinders)
    for (const CylinderAxis& cb : b.cylinders)
      if (auto p = closestBetweenCylinders(ca, cb); p && p->distance <= result.points.distance) {
        result.points = *p;
        result.method = "cylinders (closed form)";
        result.error_bound_m = 0.0;
      }
  result.points.a = world(view, result.points.a);
  result.points.b = world(view, result.points.b);
  return result;
}

MeasuredDistance centreLineDistance(const PackageView& view, const MeasureShape& a,
                                    const MeasureShape& b) {
  if (a.cylinders.empty() || b.cylinders.empty())
    throw std::invalid_argument("centre lines: an object has no cylinder");
  MeasuredDistance result;
  result.points.distance = INFINITY;
  for (const CylinderAxis& ca : a.cylinders)
    for (const CylinderAxis& cb : b.cylinders) {
      const SegmentClosest s = closestOnSegments(ca.base, ca.top, cb.base, cb.top);
      if (s.points.distance < result.points.distance) result.points = s.points;
    }
  result.points.a = world(view, result.points.a);
  result.points.b = world(view, result.points.b);
  result.method = "centre lines";
  return result;
}

}  // namespace tw
