// Far proxies through OpenVDB: unsigned distance field of the source (with its closest-triangle
// index grid), adaptive iso-surface at about one voxel, a predicted voxel size with at most one
// retry, canonical ordering for byte-identical output, and a two-sided error bound read from
// distance fields rather than from exact nearest-triangle searches. See far_proxy.h for the
// contract. The only translation unit that includes OpenVDB's mesh tools (about 12 s and 0.9 GB
// to compile).
#include "far_proxy.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <tuple>

#include "closest_on_triangle.h"

namespace tw {

namespace {

struct Soup {
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> tris;  // three per triangle
};

// OpenVDB's volumeToMesh already winds polygons facing away from the region below the iso value
// (the shell's inside). Checked by test_far_proxy (positive signed volume of a sphere's proxy).
constexpr bool kFlipVdbWinding = false;

// Narrow band of every distance field, in voxels: past the iso offset so the iso-surface is
// found everywhere, and wide enough that nearly every error sample finds its cell inside it.
float bandVoxels(const FarProxyOptions& o) { return o.iso_voxels + o.band_margin_voxels; }

// An unsigned distance field over positions relative to `center`: values are exact distances (in
// the input's units) at voxel centres (index coordinates times voxel), active within the band.
// With `nearest`, also the closest-triangle index of every active voxel: OpenVDB computes it
// with the distances and breaks ties by the lower index, so it is deterministic.
struct DistanceField {
  openvdb::FloatGrid::Ptr distance;
  openvdb::Int32Grid::Ptr nearest;
};

DistanceField distanceField(const Soup& soup, const glm::vec3& center, float voxel,
                            const FarProxyOptions& o, bool with_nearest) {
  auto transform = openvdb::math::Transform::createLinearTransform(double(voxel));
  // meshToVolume takes index-space points (as meshToUnsignedDistanceField converts them).
  std::vector<openvdb::Vec3s> points(soup.positions.size());
  for (size_t v = 0; v < points.size(); ++v) {
    const glm::vec3 p = soup.positions[v] - center;
    const openvdb::Vec3d world(openvdb::Vec3s(p.x, p.y, p.z));
    points[v] = openvdb::Vec3s(transform->worldToIndex(world));
  }
  std::vector<openvdb::Vec3I> triangles(soup.tris.size() / 3);
  for (size_t t = 0; t < triangles.size(); ++t)
    triangles[t] = openvdb::Vec3I(soup.tris[3 * t], soup.tris[3 * t + 1], soup.tris[3 * t + 2]);
  openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec3I> mesh(
      points.data(), points.size(), triangles.data(), triangles.size());
  DistanceField field;
  if (with_nearest) field.nearest = openvdb::Int32Grid::create(int32_t(openvdb::util::INVALID_IDX));
  const float band = bandVoxels(o);
  field.distance = openvdb::tools::meshToVolume<openvdb::FloatGrid>(
      mesh, *transform, band, band, openvdb::tools::UNSIGNED_DISTANCE_FIELD, field.nearest.get());
  return field;
}

// The iso-surface of a field at iso_voxels * voxel (positions relative to the field's center),
// quads split along their shorter diagonal.
Soup contour(const openvdb::FloatGrid& grid, float voxel, const FarProxyOptions& o) {
  std::vector<openvdb::Vec3s> out_points;
  std::vector<openvdb::Vec3I> out_triangles;
  std::vector<openvdb::Vec4I> out_quads;
  openvdb::tools::volumeToMesh(grid, out_points, out_triangles, out_quads,
                               double(o.iso_voxels) * double(voxel), double(o.adaptivity), true);
  Soup out;
  out.positions.resize(out_points.size());
  for (size_t v = 0; v < out_points.size(); ++v)
    out.positions[v] = glm::vec3(out_points[v].x(), out_points[v].y(), out_points[v].z());
  out.tris.reserve(3 * out_triangles.size() + 6 * out_quads.size());
  auto emit = [&](uint32_t a, uint32_t b, uint32_t c) {
    if (kFlipVdbWinding) std::swap(b, c);
    out.tris.insert(out.tris.end(), {a, b, c});
  };
  for (const openvdb::Vec3I& t : out_triangles) emit(t[0], t[1], t[2]);
  for (const openvdb::Vec4I& q : out_quads) {
    const glm::vec3 &a = out.positions[q[0]], &b = out.positions[q[1]], &c = out.positions[q[2]],
                    &d = out.positions[q[3]];
    if (glm::dot(a - c, a - c) <= glm::dot(b - d, b - d)) {
      emit(q[0], q[1], q[2]);
      emit(q[0], q[2], q[3]);
    } else {
      emit(q[0], q[1], q[3]);
      emit(q[1], q[2], q[3]);
    }
  }
  return out;
}

// Same triangles, canonical bytes: positions shifted back by `center`, welded and sorted, each
// triangle rotated to start at its lowest vertex (winding kept), triangles sorted, degenerate
// ones dropped, unused vertices removed.
Soup canonicalize(const Soup& raw, const glm::vec3& center) {
  using Key = std::tuple<float, float, float>;
  std::vector<std::pair<Key, uint32_t>> order(raw.positions.size());
  for (size_t v = 0; v < raw.positions.size(); ++v) {
    glm::vec3 p = raw.positions[v] + center;
    for (int k = 0; k < 3; ++k)
      if (p[k] == 0.0f) p[k] = 0.0f;  // -0 and +0 weld
    order[v] = {Key(p.x, p.y, p.z), uint32_t(v)};
  }
  std::sort(order.begin(), order.end());
  std::vector<uint32_t> remap(raw.positions.size());
  std::vector<glm::vec3> unique;
  for (size_t i = 0; i < order.size(); ++i) {
    if (i == 0 || order[i].first != order[i - 1].first) {
      const Key& k = order[i].first;
      unique.emplace_back(std::get<0>(k), std::get<1>(k), std::get<2>(k));
    }
    remap[order[i].second] = uint32_t(unique.size() - 1);
  }
  std::vector<std::array<uint32_t, 3>> tris;
  tris.reserve(raw.tris.size() / 3);
  for (size_t i = 0; i < raw.tris.size(); i += 3) {
    std::array<uint32_t, 3> t{remap[raw.tris[i]], remap[raw.tris[i + 1]], remap[raw.tris[i + 2]]};
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};
    tris.push_back(t);
  }
  std::sort(tris.begin(), tris.end());
  std::vector<uint32_t> used(unique.size(), std::numeric_limits<uint32_t>::max());
  for (const auto& t : tris)
    for (uint32_t v : t) used[v] = 0;
  Soup out;
  for (size_t v = 0; v < unique.size(); ++v)
    if (used[v] == 0) {
      used[v] = uint32_t(out.positions.size());
      out.positions.push_back(unique[v]);
    }
  out.tris.reserve(3 * tris.size());
  for (const auto& t : tris)
    for (uint32_t v : t) out.tris.push_back(used[v]);
  return out;
}


// Exact nearest-triangle queries over a soup: a dense grid of buckets (each triangle in every
// cell its box overlaps), searched ring by ring until no closer cell can remain.
class TriangleGrid {
 public:
  TriangleGrid(const Soup& soup, float cell_hint) : soup_(soup) {
    lo_ = glm::vec3(INFINITY);
    glm::vec3 hi(-INFINITY);
    for (const glm::vec3& p : soup.positions) {
      lo_ = glm::min(lo_, p);
      hi = glm::max(hi, p);
    }
    const glm::vec3 extent = glm::max(hi - lo_, glm::vec3(0.0f));
    // Cells: about cell_hint, at most 128 per axis and about two per triangle (a mostly empty
    // grid costs its clearing, per proxy, for nothing).
    cell_ = std::max({cell_hint, extent.x / 128.0f, extent.y / 128.0f, extent.z / 128.0f, 1e-30f});
    const double max_cells = std::max(4096.0, 2.0 * double(soup.tris.size() / 3));
    for (int attempt = 0; attempt < 8; ++attempt) {
      double cells = 1.0;
      for (int k = 0; k < 3; ++k) cells *= std::ceil(extent[k] / cell_) + 1.0;
      if (cells <= max_cells) break;
      cell_ *= float(std::cbrt(cells / max_cells));
    }
    for (int k = 0; k < 3; ++k) dims_[k] = std::max(1, int(std::ceil(extent[k] / cell_)) + 1);
    const size_t cells = size_t(dims_[0]) * size_t(dims_[1]) * size_t(dims_[2]);
    offsets_.assign(cells + 1, 0);
    const size_t count = soup.tris.size() / 3;
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<uint32_t> fill;
      if (pass == 1) {
        for (size_t i = 0; i < cells; ++i) offsets_[i + 1] += offsets_[i];
        items_.resize(offsets_[cells]);
        fill.assign(offsets_.begin(), offsets_.end() - 1);
      }
      for (size_t t = 0; t < count; ++t) {
        glm::ivec3 a(INT32_MAX), b(INT32_MIN);
        for (int k = 0; k < 3; ++k) {
          glm::ivec3 c = cellOf(soup.positions[soup.tris[3 * t + k]]);
          a = glm::min(a, c);
          b = glm::max(b, c);
        }
        for (int z = a.z; z <= b.z; ++z)
          for (int y = a.y; y <= b.y; ++y)
            for (int x = a.x; x <= b.x; ++x) {
              const size_t cell = index(x, y, z);
              if (pass == 0)
                ++offsets_[cell + 1];
              else
                items_[fill[cell]++] = uint32_t(t);
            }
      }
    }
    stamp_.assign(count, 0);
  }

  // The nearest triangle to p (ties: lower index) and its distance; {~0u, inf} for an empty soup.
  std::pair<uint32_t, float> nearest(const glm::vec3& p) {
    if (++epoch_ == 0) {
      std::fill(stamp_.begin(), stamp_.end(), 0);
      epoch_ = 1;
    }
    uint32_t best = std::numeric_limits<uint32_t>::max();
    float best_d2 = INFINITY;
    const glm::ivec3 c = cellOf(p);
    for (int r = 0;; ++r) {
      for (int z = std::max(c.z - r, 0); z <= std::min(c.z + r, dims_[2] - 1); ++z)
        for (int y = std::max(c.y - r, 0); y <= std::min(c.y + r, dims_[1] - 1); ++y)
          for (int x = std::max(c.x - r, 0); x <= std::min(c.x + r, dims_[0] - 1); ++x) {
            if (std::max({std::abs(x - c.x), std::abs(y - c.y), std::abs(z - c.z)}) != r) continue;
            // A cell farther than the best so far cannot hold a closer point (a triangle is in
            // every cell its box overlaps, so its closest point's cell is visited too).
            const glm::vec3 box_lo = lo_ + glm::vec3(float(x), float(y), float(z)) * cell_;
            const glm::vec3 gap = glm::max(glm::max(box_lo - p, p - (box_lo + cell_)), 0.0f);
            if (glm::dot(gap, gap) > best_d2) continue;
            const size_t cell = index(x, y, z);
            for (uint32_t i = offsets_[cell]; i < offsets_[cell + 1]; ++i) {
              const uint32_t t = items_[i];
              if (stamp_[t] == epoch_) continue;
              stamp_[t] = epoch_;
              const glm::vec3 q = closestOnTriangle(p, soup_.positions[soup_.tris[3 * t]],
                                                    soup_.positions[soup_.tris[3 * t + 1]],
                                                    soup_.positions[soup_.tris[3 * t + 2]]);
              const float d2 = glm::dot(p - q, p - q);
              if (d2 < best_d2 || (d2 == best_d2 && t < best)) {
                best_d2 = d2;
                best = t;
              }
            }
          }
      // Cells of ring r + 1 lie beyond one of the six slabs r + 1 cells from c; stop when the
      // nearest such slab is farther than the best, or when no cell of the grid is left.
      float next_ring = INFINITY;
      for (int k = 0; k < 3; ++k) {
        if (c[k] + r + 1 < dims_[k])
          next_ring = std::min(next_ring, lo_[k] + float(c[k] + r + 1) * cell_ - p[k]);
        if (c[k] - r - 1 >= 0)
          next_ring = std::min(next_ring, p[k] - (lo_[k] + float(c[k] - r) * cell_));
      }
      if (!std::isfinite(next_ring)) break;
      next_ring = std::max(next_ring, 0.0f);
      if (best_d2 < next_ring * next_ring) break;
    }
    return {best, std::sqrt(best_d2)};
  }

 private:
  glm::ivec3 cellOf(const glm::vec3& p) const {
    glm::ivec3 c;
    for (int k = 0; k < 3; ++k) {
      float f = std::floor((p[k] - lo_[k]) / cell_);
      c[k] = int(std::clamp(f, 0.0f, float(dims_[k] - 1)));
    }
    return c;
  }
  size_t index(int x, int y, int z) const {
    return (size_t(z) * size_t(dims_[1]) + size_t(y)) * size_t(dims_[0]) + size_t(x);
  }

  const Soup& soup_;
  glm::vec3 lo_{0.0f};
  float cell_ = 1.0f;
  int dims_[3] = {1, 1, 1};
  std::vector<uint32_t> offsets_;
  std::vector<uint32_t> items_;
  std::vector<uint32_t> stamp_;
  uint32_t epoch_ = 0;
};

// The nearest to p (world coordinates) of the closest triangles OpenVDB recorded at the voxels
// around it: the cell's eight corners widened by `ring` voxels on each side. Returns (triangle,
// exact distance), ties to the lower index; {~0u, inf} when none of those voxels is in the band.
// The distance to one triangle of a surface bounds the distance to the surface from above, and
// the triangle nearest p is nearly always among those nearest the voxels around it.
std::pair<uint32_t, float> nearestRecorded(const openvdb::Int32Grid::ConstAccessor& acc,
                                           const Soup& soup, const glm::vec3& p,
                                           const glm::vec3& center, float voxel, int ring) {
  const glm::vec3 base = glm::floor((p - center) / voxel);
  const int side = 2 + 2 * ring;
  const openvdb::Coord origin(int(base.x) - ring, int(base.y) - ring, int(base.z) - ring);
  const int32_t count = int32_t(soup.tris.size() / 3);
  std::array<int32_t, 64> seen;
  size_t seen_count = 0;
  uint32_t best = std::numeric_limits<uint32_t>::max();
  float best_d2 = INFINITY;
  for (int z = 0; z < side; ++z)
    for (int y = 0; y < side; ++y)
      for (int x = 0; x < side; ++x) {
        int32_t index = 0;
        if (!acc.probeValue(origin.offsetBy(x, y, z), index) || index < 0 || index >= count)
          continue;
        if (std::find(seen.begin(), seen.begin() + seen_count, index) != seen.begin() + seen_count)
          continue;
        if (seen_count < seen.size()) seen[seen_count++] = index;
        const uint32_t t = uint32_t(index);
        const glm::vec3 q = closestOnTriangle(p, soup.positions[soup.tris[3 * t]],
                                              soup.positions[soup.tris[3 * t + 1]],
                                              soup.positions[soup.tris[3 * t + 2]]);
        const float d2 = glm::dot(p - q, p - q);
        if (d2 < best_d2 || (d2 == best_d2 && t < best)) {
          best_d2 = d2;
          best = t;
        }
      }
  return {best, std::sqrt(best_d2)};
}

// Largest distance bound over points of `from` (every vertex, and a barycentric grid on every
// triangle with sub-edges at most `spacing` unless a huge triangle hits the sample cap), and the
// longest sub-edge used (the Lipschitz margin). With vertex_part, part_worst[part] gets the
// largest bound of each part's samples. bound(p, floor) bounds the distance from p to the other
// surface; it may return any value <= floor instead when the bound is <= floor (a sample that
// cannot raise a maximum need not be measured precisely), so the maxima are exact all the same.
template <typename Bound>
std::pair<float, float> sampledDistance(const Soup& from, float spacing, const Bound& bound,
                                        const std::vector<uint32_t>* vertex_part = nullptr,
                                        std::vector<float>* part_worst = nullptr) {
  float worst = 0.0f, margin = 0.0f;
  auto sample = [&](const glm::vec3& p, uint32_t vertex) {
    float* w = part_worst ? &(*part_worst)[(*vertex_part)[vertex]] : &worst;
    const float d = bound(p, *w);
    *w = std::max(*w, d);
    worst = std::max(worst, d);
  };
  std::vector<uint8_t> done(from.positions.size(), 0);
  for (uint32_t v : from.tris)
    if (!done[v]) {
      done[v] = 1;
      sample(from.positions[v], v);
    }
  for (size_t t = 0; t < from.tris.size(); t += 3) {
    const glm::vec3 &a = from.positions[from.tris[t]], &b = from.positions[from.tris[t + 1]],
                    &c = from.positions[from.tris[t + 2]];
    const float longest = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
    const int n = std::clamp(int(std::ceil(longest / spacing)), 1, 2048);
    margin = std::max(margin, longest / float(n));
    if (n == 1) continue;  // vertices already sampled
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        if ((i == 0 && j == 0) || i == n || j == n) continue;  // the three corners
        const float u = float(i) / float(n), w = float(j) / float(n);
        sample(a + (b - a) * u + (c - a) * w, from.tris[t]);
      }
  }
  return {worst, margin};
}

void initializeOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

}  // namespace

float predictFarProxyVoxel(double source_area, uint32_t target_triangles, float extent,
                           const FarProxyOptions& options) {
  // A shell of area S remeshed at voxel h has about c * S / h^2 triangles, and the shell around
  // thin or solid parts is about twice the source area. c = 12 (adaptivity 0.3): on the 10M
  // plant's proxy groups, the voxel sizes that met the target were 1.1x-2x sqrt(6 S / target).
  const double target = std::max<double>(target_triangles, 1.0);
  const float min_voxel = extent * std::max(options.min_voxel_fraction, 1e-6f);
  const float voxel = float(std::sqrt(12.0 * std::max(source_area, 0.0) / target));
  return std::clamp(voxel, min_voxel, std::max(extent, min_voxel));
}

// The input's valid triangles (no repeated corner, every coordinate finite) over its positions
// (unused ones are harmless), with their object ids, bounds and area.
struct FarProxySource {
  Soup soup;
  std::vector<uint32_t> ids;  // one per triangle of `soup`
  glm::vec3 lo{INFINITY}, hi{-INFINITY};
  double area = 0.0;
};

FarProxySource validSource(const FarProxyInput& input) {
  FarProxySource out;
  Soup& source = out.soup;
  std::vector<uint32_t>& source_ids = out.ids;
  glm::vec3& lo = out.lo;
  glm::vec3& hi = out.hi;
  double& area = out.area;
  source.positions.assign(input.positions.begin(), input.positions.end());
  for (size_t t = 0; t < input.triangle_object_ids.size(); ++t) {
    const uint32_t a = input.indices[3 * t], b = input.indices[3 * t + 1],
                   c = input.indices[3 * t + 2];
    bool finite = true;
    for (uint32_t v : {a, b, c})
      for (int k = 0; k < 3; ++k) finite = finite && std::isfinite(input.positions[v][k]);
    if (a == b || b == c || a == c || !finite) continue;
    source.tris.insert(source.tris.end(), {a, b, c});
    source_ids.push_back(input.triangle_object_ids[t]);
    for (uint32_t v : {a, b, c}) {
      lo = glm::min(lo, input.positions[v]);
      hi = glm::max(hi, input.positions[v]);
    }
    area += 0.5 * double(glm::length(glm::cross(input.positions[b] - input.positions[a],
                                                input.positions[c] - input.positions[a])));
  }
  return out;
}

// The remeshed shell the voxel-size search kept, with the distance field it came from.
struct Remesh {
  Soup raw;
  DistanceField field;
  float voxel = 0.0f;
};

// Voxel search: the predicted size first, then a rescale by the square root of the miss.
// Small parts become blobs whose count no longer falls with h, and counts jump where
// neighbouring shells merge, hence few tries (each costs a mesh -> volume -> mesh round trip).
Remesh searchVoxelSize(const FarProxySource& in, const glm::vec3& center, float extent,
                       const FarProxyOptions& options) {
  const Soup& source = in.soup;
  const double target = std::max<double>(options.target_triangles, 1.0);
  const float min_voxel = extent * std::max(options.min_voxel_fraction, 1e-6f);
  float voxel = predictFarProxyVoxel(in.area, options.target_triangles, extent, options);
  // Once one voxel size fits and a finer one does not, bisect between them (geometrically):
  // rescaling alone can oscillate across a jump.
  Remesh kept;
  Soup& best = kept.raw;
  DistanceField& best_field = kept.field;
  float& best_voxel = kept.voxel;
  bool best_fits = false;
  float finest_fit = INFINITY, coarsest_over = 0.0f;
  for (uint32_t attempt = 0; attempt < std::max(options.max_attempts, 1u); ++attempt) {
    DistanceField field = distanceField(source, center, voxel, options, true);
    Soup raw = contour(*field.distance, voxel, options);
    const double n = double(raw.tris.size() / 3);
    const bool fits = n <= target && n > 0;
    const double best_n = double(best.tris.size() / 3);
    if (fits)
      finest_fit = std::min(finest_fit, voxel);
    else if (n > target)
      coarsest_over = std::max(coarsest_over, voxel);
    if (best.tris.empty() || (fits && (!best_fits || n > best_n)) ||
        (!fits && !best_fits && n < best_n)) {
      best = std::move(raw);
      best_field = std::move(field);
      best_voxel = voxel;
      best_fits = fits;
    }
    if (fits && n >= double(options.min_fill) * target) break;  // each try costs a remesh
    // Refine by at most 0.7x a step: an attempt costs about its output, and counts can jump
    // tenfold where shells stop merging. Aim a little under the target: with one retry, a miss
    // above it is a wasted proxy.
    float next = n > 0 ? voxel * std::clamp(float(std::sqrt(n / (0.75 * target))), 0.7f, 3.0f)
                       : voxel * 0.7f;
    if (std::isfinite(finest_fit) && coarsest_over > 0.0f && coarsest_over < finest_fit)
      next = std::sqrt(finest_fit * coarsest_over);
    next = std::max(next, min_voxel);
    if (next == voxel) break;  // nothing else to try
    voxel = next;
  }
  return kept;
}

// Source parts (connected by shared vertices) and their boxes, for part_error.
struct SourceParts {
  std::vector<uint32_t> part;  // per position: its part's root
  std::vector<glm::vec3> part_lo, part_hi;
};

SourceParts sourceParts(const Soup& source) {
  SourceParts out;
  std::vector<uint32_t>& part = out.part;
  part.resize(source.positions.size());
  for (uint32_t v = 0; v < part.size(); ++v) part[v] = v;
  auto find = [&](uint32_t v) {
    while (part[v] != v) v = part[v] = part[part[v]];
    return v;
  };
  for (size_t i = 0; i < source.tris.size(); i += 3)
    for (int k = 1; k < 3; ++k) {
      const uint32_t a = find(source.tris[i]), b = find(source.tris[i + k]);
      if (a != b) part[std::max(a, b)] = std::min(a, b);
    }
  for (uint32_t v = 0; v < part.size(); ++v) part[v] = find(v);
  std::vector<glm::vec3>& part_lo = out.part_lo;
  std::vector<glm::vec3>& part_hi = out.part_hi;
  part_lo.assign(part.size(), glm::vec3(INFINITY));
  part_hi.assign(part.size(), glm::vec3(-INFINITY));
  for (uint32_t v : source.tris) {
    part_lo[part[v]] = glm::min(part_lo[part[v]], source.positions[v]);
    part_hi[part[v]] = glm::max(part_hi[part[v]], source.positions[v]);
  }
  return out;
}

// Exact nearest-triangle searches over a surface, built on first use.
class LazyTriangleGrid {
 public:
  LazyTriangleGrid(const Soup& surface, float cell) : surface_(surface), cell_(cell) {}
  TriangleGrid& get() {
    if (!grid_) grid_ = std::make_unique<TriangleGrid>(surface_, cell_);
    return *grid_;
  }

 private:
  const Soup& surface_;
  float cell_;
  std::unique_ptr<TriangleGrid> grid_;
};

// Object ids: the source triangle nearest each proxy triangle's centroid, found exactly (the
// closest triangles OpenVDB records away from the surface are approximate, and picked another
// part for about 3% of the triangles of a dense aggregate). One query per proxy triangle.
std::vector<uint32_t> proxyObjectIds(const Soup& mesh, const std::vector<uint32_t>& source_ids,
                                     LazyTriangleGrid& source_exact) {
  std::vector<uint32_t> ids(mesh.tris.size() / 3);
  for (size_t t = 0; t < ids.size(); ++t) {
    const glm::vec3 centroid =
        (mesh.positions[mesh.tris[3 * t]] + mesh.positions[mesh.tris[3 * t + 1]] +
         mesh.positions[mesh.tris[3 * t + 2]]) /
        3.0f;
    ids[t] = source_ids[source_exact.get().nearest(centroid).first];
  }
  return ids;
}

// Error: sampled two-sided distance bound plus the sample spacing (see far_proxy.h). Each
// sample's distance to the other surface is bounded by its exact distance to the triangles
// recorded as closest at the eight voxels around it: the source's index grid for proxy
// samples, the proxy's own (one more, smaller, voxelization) for source samples.
void measureFarProxyError(const FarProxySource& in, const Remesh& kept, const Soup& mesh,
                          const glm::vec3& center, const FarProxyOptions& options,
                          LazyTriangleGrid& source_exact, FarProxy& proxy) {
  const Soup& source = in.soup;
  const float h = kept.voxel;
  const openvdb::Int32Grid::ConstAccessor source_nearest = kept.field.nearest->getConstAccessor();

  const float spacing = 0.5f * h;
  // The eight corners' triangles first, then the 4x4x4 block's (tighter: the recorded triangles
  // are approximate away from the surface), then an exact search outside the band.
  auto boundFrom = [&](const openvdb::Int32Grid::ConstAccessor& nearest, const Soup& surface,
                       const glm::vec3& p, float floor, auto&& exact) {
    const float d = nearestRecorded(nearest, surface, p, center, h, 0).second;
    if (d <= floor) return d;
    const float wide = nearestRecorded(nearest, surface, p, center, h, 1).second;
    return std::isfinite(wide) ? wide : exact(p);
  };
  const auto [to_source, margin_p] =
      sampledDistance(mesh, spacing, [&](const glm::vec3& p, float floor) {
        return boundFrom(source_nearest, source, p, floor,
                         [&](const glm::vec3& q) { return source_exact.get().nearest(q).second; });
      });
  const DistanceField proxy_field = distanceField(mesh, center, h, options, true);
  const openvdb::Int32Grid::ConstAccessor proxy_nearest = proxy_field.nearest->getConstAccessor();
  const SourceParts parts = sourceParts(source);
  const std::vector<uint32_t>& part = parts.part;
  LazyTriangleGrid proxy_exact(mesh, h);
  std::vector<float> part_worst(part.size(), 0.0f);
  const auto [to_proxy, margin_s] = sampledDistance(
      source, spacing,
      [&](const glm::vec3& p, float floor) {
        // Hidden deep inside a merged shell: exact, against the (small) proxy.
        return boundFrom(proxy_nearest, mesh, p, floor, [&](const glm::vec3& q) {
          return proxy_exact.get().nearest(q).second;
        });
      },
      &part, &part_worst);
  proxy.error = std::max(to_source + margin_p, to_proxy + margin_s);
  proxy.part_error = to_source + margin_p;
  for (uint32_t root = 0; root < part.size(); ++root) {
    const glm::vec3 lo = parts.part_lo[root], hi = parts.part_hi[root];
    if (part[root] == root && lo.x <= hi.x)
      proxy.part_error =
          std::max(proxy.part_error, std::min(part_worst[root] + margin_s, glm::length(hi - lo)));
  }
  proxy.sample_spacing = std::max(margin_p, margin_s);
}

FarProxy buildFarProxy(const FarProxyInput& input, const FarProxyOptions& options) {
  if (input.indices.size() % 3 != 0)
    throw std::invalid_argument("buildFarProxy: index count is not a multiple of 3");
  if (input.triangle_object_ids.size() != input.indices.size() / 3)
    throw std::invalid_argument("buildFarProxy: need one object id per triangle");
  for (uint32_t v : input.indices)
    if (v >= input.positions.size())
      throw std::invalid_argument("buildFarProxy: index out of range");

  const FarProxySource source = validSource(input);
  FarProxy proxy;
  if (source.soup.tris.empty()) return proxy;
  const float extent = std::max({source.hi.x - source.lo.x, source.hi.y - source.lo.y,
                                 source.hi.z - source.lo.z});
  if (!(extent > 0.0f)) return proxy;
  initializeOpenVdb();

  const glm::vec3 center = 0.5f * (source.lo + source.hi);
  const Remesh kept = searchVoxelSize(source, center, extent, options);
  if (kept.raw.tris.empty()) return proxy;
  Soup mesh = canonicalize(kept.raw, center);
  LazyTriangleGrid source_exact(source.soup, kept.voxel);
  proxy.triangle_object_ids = proxyObjectIds(mesh, source.ids, source_exact);
  measureFarProxyError(source, kept, mesh, center, options, source_exact, proxy);
  proxy.voxel_size = kept.voxel;
  proxy.positions = std::move(mesh.positions);
  proxy.indices = std::move(mesh.tris);
  return proxy;
}

}  // namespace tw
