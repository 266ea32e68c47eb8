// A change set shown on a package (change_set_view.h).
#include "change_set_view.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <glm/gtc/matrix_transform.hpp>

#include "object_distance.h"
#include "object_queries.h"

namespace tw {
namespace {

std::vector<uint32_t> requireObjects(const PackageView& view, const std::string& key) {
  std::vector<uint32_t> objects = objectsOfChangeKey(view, key);
  if (objects.empty())
    throw std::runtime_error(view.fileName() + ": the change set names '" + key +
                             "', which no object has as database key or name");
  return objects;
}

}  // namespace

std::vector<uint32_t> objectsOfChangeKey(const PackageView& view, const std::string& key) {
  std::vector<uint32_t> objects = objectsWithKeys(view, {key});
  if (objects.empty())
    for (uint32_t o = 0; o < view.objects().size(); ++o)
      if (view.objectName(o) == key) objects.push_back(o);
  return objects;
}

std::vector<MovedMesh> objectMeshes(const PackageView& view, const std::vector<uint32_t>& objects) {
  std::vector<MovedMesh> meshes;
  for (uint32_t object : objects) {
    glm::dvec3 lo, hi;
    const uint32_t one[] = {object};
    const double size = objectsBounds(view, one, lo, hi) ? glm::length(hi - lo) : 1.0;
    const MeasureShape shape = measureShape(view, one, std::max(1e-3, 1e-3 * size));
    MovedMesh mesh;
    mesh.object = object;
    if (!shape.triangles.empty()) mesh.anchor = shape.triangles.front()[0];
    for (const Triangle3d& t : shape.triangles)
      for (const glm::dvec3& p : t) mesh.triangles.push_back(glm::vec3(p - mesh.anchor));
    meshes.push_back(std::move(mesh));
  }
  return meshes;
}

glm::dmat4 packageMove(const PackageView& view, const glm::dmat4& world) {
  // p_pkg -> world(p_pkg + origin) - origin.
  const glm::dvec3 origin = view.origin();
  return glm::translate(glm::dmat4(1.0), -origin) * world * glm::translate(glm::dmat4(1.0), origin);
}

std::vector<MovedMesh> movedMeshes(const ChangeSet& changes, const PackageView& view) {
  std::vector<MovedMesh> meshes;
  for (const std::string& key : changes.movedKeys()) {
    const glm::dmat4 move = packageMove(view, changes.placement(key));
    for (MovedMesh& mesh : objectMeshes(view, requireObjects(view, key))) {
      mesh.move = move;
      meshes.push_back(std::move(mesh));
    }
  }
  return meshes;
}

void applyChangeStates(const ChangeSet& changes, const PackageView& view, ObjectStates& states) {
  for (const Change& c : changes.changes()) {
    if (c.kind == Change::Kind::Hide)
      for (uint32_t o : requireObjects(view, c.key)) states.set(o, kObjectHidden, c.hidden);
    else if (c.kind == Change::Kind::Colour)
      for (uint32_t o : requireObjects(view, c.key)) states.setColor(o, c.rgba);
  }
}

MeasureShape movedShape(const PackageView& view, const MeasureShape& shape, const glm::dmat4& world) {
  if (world == glm::dmat4(1.0)) return shape;
  const glm::dmat4 m = packageMove(view, world);
  auto at = [&](const glm::dvec3& p) { return glm::dvec3(m * glm::dvec4(p, 1.0)); };
  MeasureShape out = shape;
  for (Triangle3d& t : out.triangles)
    for (glm::dvec3& p : t) p = at(p);
  // A cylinder stays one under a rigid move and a uniform scale (its radius scaled with it).
  const double scale = std::cbrt(std::abs(glm::determinant(glm::dmat3(m))));
  for (CylinderAxis& c : out.cylinders) {
    c.base = at(c.base);
    c.top = at(c.top);
    c.radius *= scale;
  }
  return out;
}

bool movedBounds(const PackageView& view, const std::vector<uint32_t>& objects,
                 const glm::dmat4& move, glm::dvec3& lo, glm::dvec3& hi) {
  glm::dvec3 a, b;
  if (!objectsBounds(view, objects, a, b)) return false;
  lo = glm::dvec3(1e300);
  hi = glm::dvec3(-1e300);
  for (int corner = 0; corner < 8; ++corner) {
    const glm::dvec3 p((corner & 1) ? b.x : a.x, (corner & 2) ? b.y : a.y, (corner & 4) ? b.z : a.z);
    const glm::dvec3 q = glm::dvec3(move * glm::dvec4(p, 1.0));
    lo = glm::min(lo, q);
    hi = glm::max(hi, q);
  }
  return true;
}

}  // namespace tw
