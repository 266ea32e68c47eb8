// Exact-position keys for welding vertices that must be bit-identical (shared NURBS borders,
// watertightness checks). Hashing the float bits, not rounded values, keeps welding exact.
// Also integer grid cells, for searches of positions within a tolerance (cells of that size).
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>

#include <glm/glm.hpp>

namespace tw {

struct PositionKey {
  uint32_t x, y, z;
  bool operator==(const PositionKey&) const = default;
};

// +0.0f turns -0.0f into +0.0f, so the two zeros weld.
inline PositionKey positionKeyOf(const glm::vec3& p) {
  return {std::bit_cast<uint32_t>(p.x + 0.0f), std::bit_cast<uint32_t>(p.y + 0.0f),
          std::bit_cast<uint32_t>(p.z + 0.0f)};
}

struct PositionHash {
  size_t operator()(const PositionKey& k) const {
    uint64_t h = k.x * 0x9E3779B97F4A7C15ull;
    h ^= (h >> 29) + k.y * 0xBF58476D1CE4E5B9ull;
    h ^= (h >> 31) + k.z * 0x94D049BB133111EBull;
    return static_cast<size_t>(h ^ (h >> 32));
  }
};

// One cell of a uniform integer grid.
struct GridCellKey {
  int64_t x, y, z;
  bool operator==(const GridCellKey&) const = default;
};

struct GridCellHash {
  size_t operator()(const GridCellKey& k) const {
    uint64_t h = static_cast<uint64_t>(k.x) * 0x9E3779B97F4A7C15ull;
    h ^= (h >> 29) + static_cast<uint64_t>(k.y) * 0xBF58476D1CE4E5B9ull;
    h ^= (h >> 31) + static_cast<uint64_t>(k.z) * 0x94D049BB133111EBull;
    return static_cast<size_t>(h ^ (h >> 32));
  }
};

}  // namespace tw
