// Parametric clusters: type, then Morton order, then runs. See parametric_clusters.h.
#include "parametric_clusters.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <variant>

#include "bounds.h"

namespace tw {

namespace {

uint64_t spread21(uint64_t x) {
  x &= 0x1fffff;
  x = (x | (x << 32)) & 0x1f00000000ffffull;
  x = (x | (x << 16)) & 0x1f0000ff0000ffull;
  x = (x | (x << 8)) & 0x100f00f00f00f00full;
  x = (x | (x << 4)) & 0x10c30c30c30c30c3ull;
  x = (x | (x << 2)) & 0x1249249249249249ull;
  return x;
}

}  // namespace

float parametricShowWidth(const Primitive& primitive, const Transform& transform) {
  const glm::vec3 scale(glm::length(transform.linear[0]), glm::length(transform.linear[1]),
                        glm::length(transform.linear[2]));
  float width = 0.0f;
  if (const auto* torus = std::get_if<TorusSegment>(&primitive)) {
    width = 2.0f * torus->minor_radius * std::max({scale.x, scale.y, scale.z});  // the tube
  } else {
    const LocalBox box = primitiveBounds(primitive);
    const glm::vec3 size = (box.max - box.min) * scale;
    // The second largest of the three (a tube's, a sphere's or a revolution's diameter).
    width = std::max(std::min(size.x, size.y), std::min(std::max(size.x, size.y), size.z));
  }
  return std::isfinite(width) ? width : 0.0f;  // a strict order for the sort; no profile: 0
}

uint64_t parametricMortonCode(const glm::vec3& unit) {
  auto q = [](float f) { return uint64_t(std::clamp(f, 0.0f, 1.0f) * 2097151.0f); };
  return spread21(q(unit.x)) | (spread21(q(unit.y)) << 1) | (spread21(q(unit.z)) << 2);
}

ParametricClustering clusterPrimitives(std::span<const ParametricItem> items,
                                       glm::dvec3 package_origin, uint32_t max_per_cluster) {
  if (max_per_cluster == 0)
    throw std::invalid_argument("clusterPrimitives: max_per_cluster must be > 0");
  if (items.size() >= std::numeric_limits<uint32_t>::max())
    throw std::invalid_argument("clusterPrimitives: too many items");

  // Box centres through the package's own instance conversion, so the clustering sees exactly
  // the bounds the package will store (and bad parameters fail here, before anything is added).
  std::vector<glm::vec3> centers(items.size());
  std::vector<float> width(items.size());  // the order within a cluster, widest first
  {
    PackageStorage scratch;
    scratch.origin = package_origin;
    for (size_t i = 0; i < items.size(); ++i) {
      scratch.addInstance(items[i].primitive, items[i].transform, items[i].object);
      glm::vec3 box_lo, box_hi;
      instanceBounds(scratch.instances.back(), scratch.profile_points, box_lo, box_hi);
      centers[i] = 0.5f * (box_lo + box_hi);
      width[i] = parametricShowWidth(items[i].primitive, items[i].transform);
      scratch.instances.clear();  // bounds are taken; keep the scratch small
      scratch.profile_points.clear();
    }
  }
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (const glm::vec3& c : centers) {
    lo = glm::min(lo, c);
    hi = glm::max(hi, c);
  }
  // One scale for all axes (a cube), so a flat site is not cut into slabs along its thin axis.
  const glm::vec3 extent(std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z, 1e-30f}));

  struct Key {
    uint32_t type;
    uint64_t morton;
    uint32_t item;
  };
  std::vector<Key> keys(items.size());
  for (size_t i = 0; i < items.size(); ++i)
    keys[i] = {uint32_t(items[i].primitive.index()), parametricMortonCode((centers[i] - lo) / extent),
               uint32_t(i)};
  std::sort(keys.begin(), keys.end(), [](const Key& a, const Key& b) {
    if (a.type != b.type) return a.type < b.type;
    if (a.morton != b.morton) return a.morton < b.morton;
    return a.item < b.item;
  });

  ParametricClustering out;
  out.order.reserve(items.size());
  for (const Key& k : keys) out.order.push_back(k.item);
  for (size_t begin = 0; begin < keys.size();) {
    size_t end = begin;
    while (end < keys.size() && keys[end].type == keys[begin].type) ++end;
    // ceil(n / max) runs whose sizes differ by at most one.
    const size_t n = end - begin;
    const size_t runs = (n + max_per_cluster - 1) / max_per_cluster;
    for (size_t r = 0; r < runs; ++r) {
      out.offsets.push_back(uint32_t(begin + n * r / runs));
      out.types.push_back(static_cast<pkg::PrimitiveType>(keys[begin].type));
    }
    begin = end;
  }
  out.offsets.push_back(uint32_t(keys.size()));
  if (out.types.empty()) out.offsets.clear();
  // Within each cluster, widest first (stable: ties keep Morton order).
  for (size_t c = 0; c + 1 < out.offsets.size(); ++c)
    std::stable_sort(out.order.begin() + out.offsets[c], out.order.begin() + out.offsets[c + 1],
                     [&](uint32_t a, uint32_t b) { return width[a] > width[b]; });
  return out;
}

std::vector<uint32_t> addParametricClusters(std::span<const ParametricItem> items,
                                            const ParametricClustering& clustering,
                                            PackageStorage& storage,
                                            std::span<const uint16_t> role_flags) {
  const size_t count = clustering.clusterCount();
  if (!role_flags.empty() && role_flags.size() != items.size())
    throw std::invalid_argument("addParametricClusters: role flags do not match the items");
  if (clustering.order.size() != items.size() ||
      (count == 0 ? !clustering.offsets.empty() : clustering.offsets.size() != count + 1))
    throw std::invalid_argument("addParametricClusters: clustering does not match the items");
  for (uint32_t item : clustering.order)
    if (item >= items.size())
      throw std::invalid_argument("addParametricClusters: clustering does not match the items");
  std::vector<uint32_t> cluster_ids;
  cluster_ids.reserve(count);
  for (size_t c = 0; c < count; ++c) {
    const uint32_t begin = clustering.offsets[c], end = clustering.offsets[c + 1];
    if (begin >= end || end > clustering.order.size())
      throw std::invalid_argument("addParametricClusters: clustering has a bad cluster range");
    const uint32_t first = storage.instanceCount();
    for (uint32_t i = begin; i < end; ++i) {
      const uint32_t index = clustering.order[i];
      const ParametricItem& item = items[index];
      storage.addInstance(item.primitive, item.transform, item.object,
                          role_flags.empty() ? 0u : role_flags[index]);
    }
    // Level-0 root: error 0, parent_error +inf, lod spheres = its bounds (radius 0 selects them).
    ClusterLod lod;
    cluster_ids.push_back(storage.addParametricCluster(first, end - begin, lod));
  }
  return cluster_ids;
}

}  // namespace tw
