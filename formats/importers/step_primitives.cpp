// Recognition of primitive solids from B-rep faces. See step_primitives.h.
//
// Each test reads as: the face kinds a primitive has, the shared axis or centre, the caps, and
// then the areas (exact surface integrals, not a tessellation) against the primitive's own, which
// rejects partial surfaces and extra holes that the kinds alone would let through.
#include "step_primitives.h"

#include <BRepAdaptor_Surface.hxx>
#include <BRepGProp.hxx>
#include <GProp_GProps.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <gp_Cone.hxx>
#include <gp_Cylinder.hxx>
#include <gp_Pln.hxx>
#include <gp_Sphere.hxx>
#include <gp_Torus.hxx>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace tw {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kAreaTolerance = 1e-4;    // relative
constexpr double kAngleTolerance = 1e-6;   // of a unit direction's components

struct Face {
  TopoDS_Face face;
  GeomAbs_SurfaceType type = GeomAbs_OtherSurface;
  BRepAdaptor_Surface surface;
  double area = 0.0;
  gp_Pnt centroid;
};

Face faceOf(const TopoDS_Face& face) {
  Face f;
  f.face = face;
  f.surface.Initialize(face);
  f.type = f.surface.GetType();
  GProp_GProps props;
  BRepGProp::SurfaceProperties(face, props);
  f.area = props.Mass();
  f.centroid = props.CentreOfMass();
  return f;
}

bool nearlyEqual(double a, double b, double relative) {
  return std::abs(a - b) <= relative * std::max(std::abs(a), std::abs(b));
}

bool parallel(const gp_Dir& a, const gp_Dir& b) {
  return std::abs(std::abs(a.Dot(b)) - 1.0) < kAngleTolerance;
}

// Distance from point p to the line through o along d.
double distanceToLine(const gp_Pnt& p, const gp_Pnt& o, const gp_Dir& d) {
  const gp_Vec v(o, p);
  return v.Crossed(gp_Vec(d)).Magnitude();
}

// A right-handed frame with its Z along `z` at `origin`.
Transform frameAlong(const gp_Pnt& origin, const gp_Dir& z) {
  gp_Dir helper = std::abs(z.X()) < 0.9 ? gp_Dir(1, 0, 0) : gp_Dir(0, 1, 0);
  const gp_Dir x = gp_Dir(helper.Crossed(z).Crossed(z).Reversed());
  const gp_Dir y = z.Crossed(x);
  Transform t;
  t.origin = glm::dvec3(origin.X(), origin.Y(), origin.Z());
  t.linear = glm::mat3(glm::vec3(float(x.X()), float(x.Y()), float(x.Z())),
                       glm::vec3(float(y.X()), float(y.Y()), float(y.Z())),
                       glm::vec3(float(z.X()), float(z.Y()), float(z.Z())));
  return t;
}

// The planar faces perpendicular to `axis`, as positions along it (from `origin`), each a disc of
// the radius `radiusAt(t)` gives there (checked by area). False when a plane is not.
template <typename RadiusAt>
bool discsAlong(const std::vector<const Face*>& planes, const gp_Pnt& origin, const gp_Dir& axis,
                double tolerance, RadiusAt radiusAt, std::vector<double>& positions) {
  for (const Face* f : planes) {
    const gp_Pln plane = f->surface.Plane();
    if (!parallel(plane.Axis().Direction(), axis)) return false;
    if (distanceToLine(f->centroid, origin, axis) > tolerance) return false;  // centred
    const double t = gp_Vec(origin, f->centroid).Dot(gp_Vec(axis));
    const double r = radiusAt(t);
    if (!(r > tolerance) || !nearlyEqual(f->area, kPi * r * r, kAreaTolerance)) return false;
    positions.push_back(t);
  }
  return true;
}

std::optional<RecognizedPrimitive> cylinder(const std::vector<Face>& faces, double tolerance) {
  std::vector<const Face*> sides, planes;
  for (const Face& f : faces) (f.type == GeomAbs_Cylinder ? sides : planes).push_back(&f);
  if (sides.empty() || planes.size() != 2) return std::nullopt;
  const gp_Cylinder first = sides[0]->surface.Cylinder();
  const gp_Pnt origin = first.Location();
  const gp_Dir axis = first.Axis().Direction();
  const double radius = first.Radius();
  double side_area = 0.0;
  for (const Face* f : sides) {
    const gp_Cylinder c = f->surface.Cylinder();
    if (!parallel(c.Axis().Direction(), axis) ||
        distanceToLine(c.Location(), origin, axis) > tolerance ||
        std::abs(c.Radius() - radius) > tolerance)
      return std::nullopt;
    side_area += f->area;
  }
  std::vector<double> at;
  if (!discsAlong(planes, origin, axis, tolerance, [&](double) { return radius; }, at))
    return std::nullopt;
  const double height = std::abs(at[1] - at[0]);
  if (!(height > tolerance) || !nearlyEqual(side_area, 2.0 * kPi * radius * height, kAreaTolerance))
    return std::nullopt;
  const gp_Pnt base = origin.Translated(gp_Vec(axis) * std::min(at[0], at[1]));
  return RecognizedPrimitive{Cylinder{float(radius), float(height), true}, frameAlong(base, axis)};
}

std::optional<RecognizedPrimitive> cone(const std::vector<Face>& faces, double tolerance) {
  std::vector<const Face*> sides, planes;
  for (const Face& f : faces) (f.type == GeomAbs_Cone ? sides : planes).push_back(&f);
  if (sides.empty() || planes.empty() || planes.size() > 2) return std::nullopt;
  const gp_Cone first = sides[0]->surface.Cone();
  const gp_Pnt origin = first.Location();
  const gp_Dir axis = first.Axis().Direction();
  const double ref_radius = first.RefRadius();
  const double slope = std::tan(first.SemiAngle());  // radius gained per unit along the axis
  double side_area = 0.0;
  for (const Face* f : sides) {
    const gp_Cone c = f->surface.Cone();
    if (!parallel(c.Axis().Direction(), axis) ||
        distanceToLine(c.Location(), origin, axis) > tolerance ||
        c.Apex().Distance(first.Apex()) > tolerance)
      return std::nullopt;
    side_area += f->area;
  }
  auto radiusAt = [&](double t) { return ref_radius + t * slope; };
  std::vector<double> at;
  if (!discsAlong(planes, origin, axis, tolerance, radiusAt, at)) return std::nullopt;
  // One disc: the other end is the apex.
  if (at.size() == 1) at.push_back(-ref_radius / slope);
  const double t0 = std::min(at[0], at[1]), t1 = std::max(at[0], at[1]);
  const double r0 = std::max(0.0, radiusAt(t0)), r1 = std::max(0.0, radiusAt(t1));
  const double height = t1 - t0;
  const double slant = std::hypot(height, r1 - r0);
  if (!(height > tolerance) || !nearlyEqual(side_area, kPi * (r0 + r1) * slant, kAreaTolerance))
    return std::nullopt;
  const gp_Pnt base = origin.Translated(gp_Vec(axis) * t0);
  return RecognizedPrimitive{Cone{float(r0), float(r1), float(height), true},
                             frameAlong(base, axis)};
}

std::optional<RecognizedPrimitive> sphere(const std::vector<Face>& faces, double tolerance) {
  const gp_Sphere first = faces[0].surface.Sphere();
  double area = 0.0;
  for (const Face& f : faces) {
    if (f.type != GeomAbs_Sphere) return std::nullopt;
    const gp_Sphere s = f.surface.Sphere();
    if (s.Location().Distance(first.Location()) > tolerance ||
        std::abs(s.Radius() - first.Radius()) > tolerance)
      return std::nullopt;
    area += f.area;
  }
  const double r = first.Radius();
  if (!nearlyEqual(area, 4.0 * kPi * r * r, kAreaTolerance)) return std::nullopt;
  return RecognizedPrimitive{Sphere{float(r)}, frameAlong(first.Location(), gp_Dir(0, 0, 1))};
}

// A torus segment (a pipe elbow): toroidal faces of one axis, centre and radii, closed by two
// discs of the tube's radius in planes through the axis (none for a whole ring). The frame's X
// points at the start disc's centre and the sweep turns counter-clockwise about Z through the
// tube to the end disc.
std::optional<RecognizedPrimitive> torus(const std::vector<Face>& faces, double tolerance) {
  std::vector<const Face*> sides, planes;
  for (const Face& f : faces) (f.type == GeomAbs_Torus ? sides : planes).push_back(&f);
  if (sides.empty() || (planes.size() != 0 && planes.size() != 2)) return std::nullopt;
  const gp_Torus first = sides[0]->surface.Torus();
  const gp_Pnt center = first.Location();
  const gp_Dir axis = first.Axis().Direction();
  const double major = first.MajorRadius(), minor = first.MinorRadius();
  if (!(minor > tolerance) || !(major > minor)) return std::nullopt;
  double side_area = 0.0;
  gp_XYZ side_centroid(0, 0, 0);
  for (const Face* f : sides) {
    const gp_Torus t = f->surface.Torus();
    if (!parallel(t.Axis().Direction(), axis) || t.Location().Distance(center) > tolerance ||
        std::abs(t.MajorRadius() - major) > tolerance ||
        std::abs(t.MinorRadius() - minor) > tolerance)
      return std::nullopt;
    side_area += f->area;
    side_centroid += f->centroid.XYZ() * f->area;
  }
  // Angles about the axis, measured from a reference direction in the torus plane.
  const gp_Dir reference = first.XAxis().Direction();
  const gp_Dir across = axis.Crossed(reference);
  auto angleOf = [&](const gp_Pnt& p) {
    const gp_Vec v(center, p);
    return std::atan2(v.Dot(gp_Vec(across)), v.Dot(gp_Vec(reference)));
  };
  double start = 0.0, sweep = 2.0 * kPi;
  if (planes.size() == 2) {
    double at[2];
    for (int i = 0; i < 2; ++i) {
      const Face* f = planes[size_t(i)];
      const gp_Pln plane = f->surface.Plane();
      // A plane through the axis: its normal is perpendicular to it and it holds the centre.
      if (std::abs(plane.Axis().Direction().Dot(axis)) > kAngleTolerance ||
          plane.Distance(center) > tolerance ||
          std::abs(gp_Vec(center, f->centroid).Dot(gp_Vec(axis))) > tolerance ||
          std::abs(center.Distance(f->centroid) - major) > tolerance ||
          !nearlyEqual(f->area, kPi * minor * minor, kAreaTolerance))
        return std::nullopt;
      at[i] = angleOf(f->centroid);
    }
    // The sweep from at[0] counter-clockwise to at[1], or the other way round: the one that
    // passes through the tube (its area-weighted centroid's angle lies inside the sweep).
    auto ccw = [](double from, double to) {
      double d = to - from;
      while (d <= 0.0) d += 2.0 * kPi;
      return d;
    };
    const double mid = angleOf(gp_Pnt(side_centroid / side_area));
    const bool forward = ccw(at[0], mid) < ccw(at[0], at[1]);
    start = forward ? at[0] : at[1];
    sweep = forward ? ccw(at[0], at[1]) : ccw(at[1], at[0]);
  }
  if (!nearlyEqual(side_area, 2.0 * kPi * major * minor * sweep, kAreaTolerance))
    return std::nullopt;
  const gp_Dir x = gp_Dir(gp_Vec(reference) * std::cos(start) + gp_Vec(across) * std::sin(start));
  const gp_Dir y = axis.Crossed(x);
  Transform t;
  t.origin = glm::dvec3(center.X(), center.Y(), center.Z());
  auto column = [](const gp_Dir& d) { return glm::vec3(float(d.X()), float(d.Y()), float(d.Z())); };
  t.linear = glm::mat3(column(x), column(y), column(axis));
  return RecognizedPrimitive{TorusSegment{float(major), float(minor), float(sweep)}, t};
}

std::optional<RecognizedPrimitive> box(const std::vector<Face>& faces, double tolerance) {
  if (faces.size() != 6) return std::nullopt;
  // Three directions, each with two planes: their offsets along it.
  std::vector<gp_Dir> axes;
  std::vector<std::vector<double>> offsets;
  for (const Face& f : faces) {
    if (f.type != GeomAbs_Plane) return std::nullopt;
    const gp_Pln plane = f.surface.Plane();
    const gp_Dir n = plane.Axis().Direction();
    size_t a = 0;
    while (a < axes.size() && !parallel(axes[a], n)) ++a;
    if (a == axes.size()) {
      axes.push_back(n);
      offsets.emplace_back();
    }
    offsets[a].push_back(gp_Vec(plane.Location().XYZ()).Dot(gp_Vec(axes[a])));
  }
  if (axes.size() != 3) return std::nullopt;
  for (int a = 0; a < 3; ++a)
    if (offsets[a].size() != 2 || !parallel(axes[a].Crossed(axes[(a + 1) % 3]), axes[(a + 2) % 3]))
      return std::nullopt;
  double extent[3];
  gp_XYZ center(0, 0, 0);
  for (int a = 0; a < 3; ++a) {
    extent[a] = std::abs(offsets[a][1] - offsets[a][0]);
    if (!(extent[a] > tolerance)) return std::nullopt;
    center += axes[a].XYZ() * (0.5 * (offsets[a][0] + offsets[a][1]));
  }
  // Each face a full rectangle: the two extents across it.
  for (const Face& f : faces) {
    const gp_Dir n = f.surface.Plane().Axis().Direction();
    int a = 0;
    while (!parallel(axes[size_t(a)], n)) ++a;
    if (!nearlyEqual(f.area, extent[(a + 1) % 3] * extent[(a + 2) % 3], kAreaTolerance))
      return std::nullopt;
  }
  gp_Dir z = axes[2];
  if (axes[0].Crossed(axes[1]).Dot(z) < 0.0) z.Reverse();  // right-handed
  Transform t;
  t.origin = glm::dvec3(center.X(), center.Y(), center.Z());
  auto column = [](const gp_Dir& d) { return glm::vec3(float(d.X()), float(d.Y()), float(d.Z())); };
  t.linear = glm::mat3(column(axes[0]), column(axes[1]), column(z));
  const glm::vec3 half(float(0.5 * extent[0]), float(0.5 * extent[1]), float(0.5 * extent[2]));
  return RecognizedPrimitive{Box{half}, t};
}

}  // namespace

std::optional<RecognizedPrimitive> recognizePrimitive(const TopoDS_Shape& shape, double tolerance) {
  int solids = 0;
  for (TopExp_Explorer e(shape, TopAbs_SOLID); e.More(); e.Next()) ++solids;
  if (solids != 1) return std::nullopt;
  // Faces outside the solid (a loose sheet in the same part) would be lost.
  int faces_outside = 0;
  for (TopExp_Explorer e(shape, TopAbs_FACE, TopAbs_SOLID); e.More(); e.Next()) ++faces_outside;
  if (faces_outside > 0) return std::nullopt;

  std::vector<Face> faces;
  bool planes = false, cylinders = false, cones = false, spheres = false, tori = false;
  for (TopExp_Explorer e(shape, TopAbs_FACE); e.More(); e.Next()) {
    Face f = faceOf(TopoDS::Face(e.Current()));
    switch (f.type) {
      case GeomAbs_Plane: planes = true; break;
      case GeomAbs_Cylinder: cylinders = true; break;
      case GeomAbs_Cone: cones = true; break;
      case GeomAbs_Sphere: spheres = true; break;
      case GeomAbs_Torus: tori = true; break;
      default: return std::nullopt;
    }
    faces.push_back(std::move(f));
  }
  if (faces.empty()) return std::nullopt;
  const int kinds = int(cylinders) + int(cones) + int(spheres) + int(tori);
  if (kinds > 1) return std::nullopt;
  if (tori) return torus(faces, tolerance);
  if (cylinders) return cylinder(faces, tolerance);
  if (cones) return cone(faces, tolerance);
  if (spheres) return planes ? std::nullopt : sphere(faces, tolerance);
  return box(faces, tolerance);
}

}  // namespace tw
