// Covered box faces: face centres on a sorted cell index, pairs checked from the instance records.
// See covered_box_faces.h.
#include "covered_box_faces.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <unordered_map>
#include <cmath>
#include <limits>

#include <glm/glm.hpp>
#include <xxhash.h>

namespace tw {
namespace {

// Normals this close to opposite count as such: 0.045 degrees.
constexpr double kOppositeCos = -(1.0 - 3e-7);
// Cells of the index, metres: a few tolerances, so a centre's reach spans at most two a side.
constexpr double kCellM = 4.0 * kFaceToleranceM;

// One face of a box instance, as the pairing needs it (recomputed from the record: the index
// keeps only the keys).
struct FaceGeometry {
  glm::dvec3 centre, normal, edge_a, edge_b;
};

// The box's columns (linear map), when they are perpendicular, non-zero and finite, with its
// half sizes; false otherwise.
bool boxFrame(const pkg::InstanceRecord& in, glm::dmat3& columns, glm::dvec3& half) {
  if (in.type != uint32_t(pkg::PrimitiveType::Box)) return false;
  const float* l = in.linear;
  columns = glm::dmat3(l[0], l[1], l[2], l[3], l[4], l[5], l[6], l[7], l[8]);
  double length[3];
  for (int k = 0; k < 3; ++k) {
    length[k] = glm::length(columns[k]);
    half[k] = in.params[k];
    if (!(length[k] > 0.0) || !std::isfinite(length[k]) || !(half[k] > 0.0) ||
        !std::isfinite(half[k]))
      return false;
  }
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b)
      if (std::abs(glm::dot(columns[a], columns[b])) > 1e-5 * length[a] * length[b]) return false;
  return std::isfinite(in.origin[0]) && std::isfinite(in.origin[1]) && std::isfinite(in.origin[2]);
}

// Face f (-X, +X, -Y, +Y, -Z, +Z) of a box with those columns and half sizes.
FaceGeometry faceOf(const pkg::InstanceRecord& in, const glm::dmat3& columns,
                    const glm::dvec3& half, int f) {
  const int axis = f / 2;
  const double side = (f & 1) ? 1.0 : -1.0;
  const int a = (axis + 1) % 3, b = (axis + 2) % 3;
  FaceGeometry g;
  g.centre = glm::dvec3(in.origin[0], in.origin[1], in.origin[2]) + side * half[axis] * columns[axis];
  g.normal = side * glm::normalize(columns[axis]);
  g.edge_a = half[a] * columns[a];
  g.edge_b = half[b] * columns[b];
  return g;
}

bool sameUpToSign(const glm::dvec3& u, const glm::dvec3& v) {
  return glm::length(u - v) <= kFaceToleranceM || glm::length(u + v) <= kFaceToleranceM;
}

// Two faces that are the same rectangle, facing each other.
bool pair(const FaceGeometry& f, const FaceGeometry& g) {
  if (glm::dot(f.normal, g.normal) > kOppositeCos) return false;
  if (glm::length(f.centre - g.centre) > kFaceToleranceM) return false;
  return (sameUpToSign(f.edge_a, g.edge_a) && sameUpToSign(f.edge_b, g.edge_b)) ||
         (sameUpToSign(f.edge_a, g.edge_b) && sameUpToSign(f.edge_b, g.edge_a));
}

constexpr uint32_t kNoCopy = 0xffffffffu;

struct Entry {
  int32_t x, y, z;    // the centre's cell
  uint32_t instance;
  uint8_t face;
};

bool cellLess(const Entry& p, const Entry& q) {
  if (p.x != q.x) return p.x < q.x;
  if (p.y != q.y) return p.y < q.y;
  return p.z < q.z;
}

// The cell of coordinate `v`, or false when it is beyond the index's range.
bool cellOf(double v, int32_t& cell) {
  const double c = std::floor(v / kCellM);
  if (!(std::abs(c) < double(std::numeric_limits<int32_t>::max() - 1))) return false;
  cell = int32_t(c);
  return true;
}


// What decides a box's faces and what they may pair with: its placement, sizes and layer. Boxes
// equal in all of these (coincident copies) have equal faces and so equal covered masks.
struct BoxKey {
  float origin[3], linear[9], half[3];
  uint32_t layer;
  bool operator==(const BoxKey& o) const { return std::memcmp(this, &o, sizeof(BoxKey)) == 0; }
};
struct BoxKeyHash {
  size_t operator()(const BoxKey& k) const { return size_t(XXH3_64bits(&k, sizeof(BoxKey))); }
};

}  // namespace

std::vector<uint8_t> findCoveredBoxFaces(std::span<const pkg::InstanceRecord> instances,
                                         std::span<const uint32_t> object_layers,
                                         CoveredFaceStats* stats) {
  std::vector<uint8_t> covered(instances.size(), 0);
  CoveredFaceStats local;
  std::vector<Entry> entries;
  // Coincident copies are indexed once, by the first of them (their faces can only pair with
  // other boxes' faces, never with each other's, which face the same way): without it n
  // coincident boxes cost n^2 comparisons (20,000 took 69 s).
  std::unordered_map<BoxKey, uint32_t, BoxKeyHash> first_copy;
  std::vector<uint32_t> copy_of(instances.size(), kNoCopy);
  for (uint32_t i = 0; i < instances.size(); ++i) {
    const pkg::InstanceRecord& in = instances[i];
    glm::dmat3 columns;
    glm::dvec3 half;
    if (in.object >= object_layers.size() || !boxFrame(in, columns, half)) continue;
    ++local.boxes;
    BoxKey key;
    std::memset(&key, 0, sizeof key);
    std::memcpy(key.origin, in.origin, sizeof key.origin);
    std::memcpy(key.linear, in.linear, sizeof key.linear);
    std::memcpy(key.half, in.params, sizeof key.half);
    key.layer = object_layers[in.object];
    const auto [it, fresh] = first_copy.emplace(key, i);
    if (!fresh) {
      copy_of[i] = it->second;
      continue;
    }
    for (int f = 0; f < 6; ++f) {
      const glm::dvec3 c = faceOf(in, columns, half, f).centre;
      Entry e{0, 0, 0, i, uint8_t(f)};
      if (cellOf(c.x, e.x) && cellOf(c.y, e.y) && cellOf(c.z, e.z)) entries.push_back(e);
    }
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& p, const Entry& q) {
    if (cellLess(p, q) || cellLess(q, p)) return cellLess(p, q);
    return p.instance != q.instance ? p.instance < q.instance : p.face < q.face;
  });

  for (const Entry& e : entries) {
    const pkg::InstanceRecord& in = instances[e.instance];
    glm::dmat3 columns;
    glm::dvec3 half;
    boxFrame(in, columns, half);
    const FaceGeometry f = faceOf(in, columns, half, e.face);
    const uint32_t layer = object_layers[in.object];
    // The cells the centre's tolerance reaches: at most two along each axis.
    int32_t lo[3], hi[3];
    for (int k = 0; k < 3; ++k)
      if (!cellOf(f.centre[k] - kFaceToleranceM, lo[k]) || !cellOf(f.centre[k] + kFaceToleranceM, hi[k]))
        lo[k] = hi[k] = k == 0 ? e.x : (k == 1 ? e.y : e.z);
    bool found = false;
    for (int32_t x = lo[0]; x <= hi[0] && !found; ++x)
      for (int32_t y = lo[1]; y <= hi[1] && !found; ++y)
        for (int32_t z = lo[2]; z <= hi[2] && !found; ++z) {
          const Entry probe{x, y, z, 0, 0};
          auto it = std::lower_bound(entries.begin(), entries.end(), probe, cellLess);
          for (; it != entries.end() && !cellLess(probe, *it) && !found; ++it) {
            if (it->instance == e.instance) continue;
            const pkg::InstanceRecord& other = instances[it->instance];
            if (object_layers[other.object] != layer) continue;
            glm::dmat3 other_columns;
            glm::dvec3 other_half;
            boxFrame(other, other_columns, other_half);
            found = pair(f, faceOf(other, other_columns, other_half, it->face));
          }
        }
    if (found) covered[e.instance] |= uint8_t(1u << e.face);
  }
  for (uint32_t i = 0; i < instances.size(); ++i) {
    if (copy_of[i] != kNoCopy) covered[i] = covered[copy_of[i]];
    if (covered[i] == 0) continue;
    ++local.boxes_with_covered_faces;
    local.covered_faces += uint64_t(std::popcount(unsigned(covered[i])));
  }
  if (stats) *stats = local;
  return covered;
}

}  // namespace tw
