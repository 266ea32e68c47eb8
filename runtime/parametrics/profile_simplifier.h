// Ramer-Douglas-Peucker simplification of the 2D profiles that extrusions and revolutions are
// swept from, to a tolerance.
//
// Why: a profile's detail below the frame's tolerance costs long, thin side strips that touch a
// row of llvmpipe's 4x4 blocks each along the whole beam or vessel, and shows nothing. Revolutions
// swept per instance (parametric_instance_meshes.h) simplify their open profile every frame;
// extrusions' cluster meshes (parametric_meshes.h) simplify their closed one per tolerance bucket.
// The scratch is kept between calls: it runs for every instance drawn.
#pragma once

#include <cstddef>
#include <span>
#include <utility>
#include <vector>

#include <glm/vec2.hpp>

namespace tw {

class ProfileSimplifier {
 public:
  // The open polyline `profile` without the points that lie within `tolerance` of the line
  // between their kept neighbours: first and last always stay; consecutive duplicates go.
  void simplify(std::span<const glm::vec2> profile, float tolerance, std::vector<glm::vec2>& kept);

  // The closed polygon `profile` (its last point joins its first) simplified the same way, its
  // first point and the point farthest from it kept. Every dropped point lies within `tolerance`
  // of the kept outline; the kept points are a subset, in order. Fewer than three points in: a
  // copy out.
  void simplifyClosed(std::span<const glm::vec2> profile, float tolerance,
                      std::vector<glm::vec2>& kept);

 private:
  void mark(std::span<const glm::vec2> profile, size_t first, size_t last, float tolerance);
  void collect(std::span<const glm::vec2> profile, std::vector<glm::vec2>& kept) const;

  std::vector<unsigned char> keep_;
  std::vector<std::pair<size_t, size_t>> spans_;
};

}  // namespace tw
