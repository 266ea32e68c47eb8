// An IFC file's units and placements: metres and radians per file unit (its IfcUnitAssignment),
// and points, directions, axis placements and the chains of IfcLocalPlacement in metres. What the
// importer places products with, and what writing moved products back into a copy of the file
// (ifc_placement_writer.h) reads their old placements with, so both agree.
#pragma once

#include <optional>

#include <glm/glm.hpp>

#include "step21_file.h"

namespace tw {

class IfcFrames {
 public:
  static constexpr int kMaxDepth = 32;  // placement chains

  explicit IfcFrames(const Step21File& file);  // reads the units

  double metresPerUnit() const { return length_; }
  double radiansPerUnit() const { return angle_; }

  // An IfcCartesianPoint in metres (the origin for anything else).
  glm::dvec3 point(const Step21Instance* p) const;
  // A unit IfcDirection; nullopt for anything else or a zero vector.
  std::optional<glm::dvec3> direction(const Step21Instance* d) const;
  // A frame from an origin, a Z and an approximate X (IFC's Axis2Placement rule).
  static glm::dmat4 frame(const glm::dvec3& origin, glm::dvec3 z, glm::dvec3 x);
  // An IfcAxis2Placement2D or 3D (identity for anything else).
  glm::dmat4 axisPlacement(const Step21Instance* a) const;
  // An IfcLocalPlacement in the world: its chain of PlacementRelTo composed (identity for
  // anything else, and past kMaxDepth).
  glm::dmat4 placement(const Step21Instance* p, int depth = 0) const;

 private:
  double unitScale(const Step21Instance* unit, int depth) const;

  const Step21File& f_;
  double length_ = 1.0;
  double angle_ = 1.0;
};

}  // namespace tw
