// IFC products to scene objects, parametric where IFC is. See ifc_importer.h.
#include "ifc_importer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "format_error.h"
#include "ifc_colours.h"
#include "ifc_frames.h"
#include "plane_arcs.h"
#include "profile_prism.h"
#include "solid_cut.h"
#include "steel_profiles.h"
#include "step21_file.h"
#include "tessellate.h"

namespace tw {
namespace {

using Kind = Step21Value::Kind;
constexpr int kMaxDepth = 32;  // placement chains, mapped items, boolean trees

using part21::arg;
using part21::numberOf;
using part21::textOf;

// A geometry failure of one item: skipped with a warning, the rest imports.
struct ItemError {
  std::string reason;
};

class IfcImporter {
 public:
  IfcImporter(const Step21File& file, SceneSink& sink, const ReadOptions& options)
      : f_(file), sink_(sink), options_(options), frames_(file), length_(frames_.metresPerUnit()),
        angle_(frames_.radiansPerUnit()), colours_(file) {}

  void run() {
    readLayers();
    readOpenings();
    std::vector<uint64_t> ids;
    for (const auto& [id, instance] : f_.instances()) ids.push_back(id);
    std::sort(ids.begin(), ids.end());
    for (uint64_t id : ids) {
      const Step21Instance& in = *f_.find(id);
      if (!isDrawnIfcProduct(f_, in)) continue;
      ++products_;
      importProduct(id, in);
    }
    if (uncut_ > 0)
      warn(std::to_string(uncut_) + " openings or boolean differences could not be cut and were drawn whole");
    if (skipped_warnings_ > kMaxWarnings)
      warn(std::to_string(skipped_warnings_ - kMaxWarnings) + " more items skipped");
  }

  uint32_t objects() const { return next_id_; }
  uint32_t products() const { return products_; }

 private:
  static constexpr int kMaxWarnings = 20;

  void warn(const std::string& message) { readWarning(options_, f_.fileName() + ": " + message); }
  void skipped(uint64_t item, const std::string& product_type, const std::string& reason) {
    if (++skipped_warnings_ <= kMaxWarnings) warn(itemMessage(item, product_type, reason, "skipped"));
  }
  void notCut(uint64_t item, const std::string& what, const std::string& reason) {
    ++uncut_;
    if (++skipped_warnings_ <= kMaxWarnings)
      warn(itemMessage(item, product_type_, what + " not cut: " + reason, "drawn whole"));
  }
  // "#id (in an IFCWALL): reason; outcome", appended piece by piece (GCC 12 warns, wrongly,
  // about overlapping copies in a chain of operator+).
  static std::string itemMessage(uint64_t item, const std::string& product_type,
                                 const std::string& reason, const char* outcome) {
    std::string m = "#";
    m += std::to_string(item);
    m += " (in an ";
    m += product_type;
    m += "): ";
    m += reason;
    m += "; ";
    m += outcome;
    return m;
  }

  // --- Layers --------------------------------------------------------------------------------
  void readLayers() {
    for (const char* type : {"IFCPRESENTATIONLAYERASSIGNMENT", "IFCPRESENTATIONLAYERWITHSTYLE"})
      for (uint64_t id : f_.idsOfType(type)) {
        const Step21Instance* layer = f_.find(id);
        const std::string name = textOf(arg(layer, 0));
        if (name.empty()) continue;
        for (const Step21Value& item : arg(layer, 2).items)
          if (item.kind == Kind::Ref) layer_of_.emplace(item.ref, name);
      }
  }

  uint32_t layerIndex(const std::string& name) {
    auto [it, inserted] = layers_.emplace(name, uint32_t(layers_.size()));
    if (inserted) sink_.onLayer(it->second, Layer{name});
    return it->second;
  }

  // --- Products ------------------------------------------------------------------------------
  // Points, directions and placements in metres (ifc_frames.h).
  glm::dvec3 point(const Step21Instance* p) const { return frames_.point(p); }
  std::optional<glm::dvec3> direction(const Step21Instance* d) const { return frames_.direction(d); }
  static glm::dmat4 frame(const glm::dvec3& origin, glm::dvec3 z, glm::dvec3 x) {
    return IfcFrames::frame(origin, z, x);
  }
  glm::dmat4 axisPlacement(const Step21Instance* a) const { return frames_.axisPlacement(a); }
  glm::dmat4 placement(const Step21Instance* p, int depth) const { return frames_.placement(p, depth); }

  void importProduct(uint64_t product_id, const Step21Instance& product) {
    ObjectInfo info;
    info.name = textOf(product.args[2]);
    if (info.name.empty()) info.name = product.type;
    info.db_key = product.args[0].text;
    product_type_ = product.type;
    const glm::dmat4 world = placement(f_.deref(product.args[5]), 0);
    const Step21Instance* shape = f_.deref(product.args[6]);
    const std::vector<const Step21Instance*> bodies = bodyRepresentations(product);

    std::string layer;
    for (const Step21Value& r : arg(shape, 2).items)
      if (auto it = layer_of_.find(r.ref); r.kind == Kind::Ref && it != layer_of_.end()) {
        layer = it->second;
        break;
      }
    mesh_ = TriangleMesh{};
    primitives_.clear();
    colour_ = 0;
    map_colour_found_.reset();
    for (const Step21Instance* rep : bodies)
      for (const Step21Value& item : arg(rep, 3).items) {
        if (layer.empty())
          if (auto it = layer_of_.find(item.ref); item.kind == Kind::Ref && it != layer_of_.end())
            layer = it->second;
        if (item.kind == Kind::Ref) importItem(item.ref, glm::dmat4(1.0), 0);
      }
    cutOpenings(product_id, world);
    if (colour_ == 0)
      colour_ = colours_.ofMaterial(product_id).value_or(map_colour_found_.value_or(0));
    if (!options_.cad.primitives) meshPrimitives();
    if (mesh_.indices.empty() && primitives_.empty()) return;

    info.layer = layerIndex(layer.empty() ? product.type : layer);
    info.color_rgba = colour_;
    if (!mesh_.indices.empty()) {
      ObjectInfo mesh_info = info;
      mesh_info.id = next_id_++;
      mesh_info.transform = toTransform(world);
      sink_.onObject(SceneObject{mesh_info, mesh_});
    }
    for (auto& [local, primitive] : primitives_) {
      ObjectInfo p = info;
      p.id = next_id_++;
      p.transform = toTransform(world * local);
      sink_.onObject(SceneObject{p, primitive});
    }
  }

  // A product's body representations: 'Body' by identifier, else any with solid or surface
  // items.
  std::vector<const Step21Instance*> bodyRepresentations(const Step21Instance& product) const {
    std::vector<const Step21Instance*> bodies, others;
    const Step21Instance* shape = f_.deref(product.args[6]);
    for (const Step21Value& r : arg(shape, 2).items) {
      const Step21Instance* rep = f_.deref(r);
      if (!rep) continue;
      const std::string identifier = textOf(arg(rep, 1));
      if (identifier == "Body") bodies.push_back(rep);
      else if (identifier.empty() || identifier == "Facetation" || identifier == "Mesh")
        others.push_back(rep);
    }
    return bodies.empty() ? others : bodies;
  }

  // --- Cuts ----------------------------------------------------------------------------------
  // IfcRelVoidsElement: RelatingBuildingElement (4) is voided by RelatedOpeningElement (5).
  void readOpenings() {
    for (uint64_t id : f_.idsOfType("IFCRELVOIDSELEMENT")) {
      const Step21Instance* rel = f_.find(id);
      const Step21Value& host = arg(rel, 4);
      const Step21Value& opening = arg(rel, 5);
      if (host.kind == Kind::Ref && opening.kind == Kind::Ref) openings_of_[host.ref].push_back(opening.ref);
    }
  }

  // What `import` adds to the product's geometry, taken apart from it.
  template <typename Import>
  SolidSet collectSolids(Import&& import) {
    TriangleMesh saved_mesh = std::move(mesh_);
    auto saved_primitives = std::move(primitives_);
    const uint32_t saved_colour = colour_;
    mesh_ = TriangleMesh{};
    primitives_.clear();
    import();
    SolidSet out{std::move(mesh_), std::move(primitives_)};
    mesh_ = std::move(saved_mesh);
    primitives_ = std::move(saved_primitives);
    colour_ = saved_colour;
    return out;
  }

  // Adds `set` to the product's geometry as it is.
  void keep(SolidSet set) {
    appendMesh(set.mesh, glm::dmat4(1.0));
    for (auto& placed : set.primitives) primitives_.push_back(std::move(placed));
  }
  void appendMesh(const TriangleMesh& part, const glm::dmat4& at) {
    const uint32_t base = uint32_t(mesh_.positions.size());
    for (const glm::vec3& p : part.positions) mesh_.positions.push_back(glm::vec3(at * glm::dvec4(glm::dvec3(p), 1.0)));
    for (uint32_t i : part.indices) mesh_.indices.push_back(base + i);
  }

  // `first` less `tools` and `half_spaces` (or what it has in common with them), added to the
  // product's geometry; `first` whole, with a warning naming `item`, when the cut fails.
  void combineInto(SolidSet first, const SolidSet& tools, const std::vector<HalfSpace>& half_spaces,
                    uint64_t item, const std::string& what, bool intersect = false) {
    try {
      const TriangleMesh result =
          intersect ? intersectSolids(first, tools, half_spaces, kDefaultChordalTolerance)
                    : subtractSolids(first, tools, half_spaces, kDefaultChordalTolerance);
      appendMesh(result, glm::dmat4(1.0));
    } catch (const SolidCutError& e) {
      notCut(item, what, e.what());
      keep(std::move(first));
    }
  }

  // The openings that void `product` (windows, doors, recesses), cut from all of its geometry.
  void cutOpenings(uint64_t product_id, const glm::dmat4& world) {
    const auto it = openings_of_.find(product_id);
    if (it == openings_of_.end() || (mesh_.indices.empty() && primitives_.empty())) return;
    const glm::dmat4 to_product = glm::inverse(world);
    SolidSet openings = collectSolids([&] {
      for (uint64_t id : it->second) {
        const Step21Instance* opening = f_.find(id);
        if (!opening || opening->args.size() < 7) continue;
        const glm::dmat4 at = to_product * placement(f_.deref(opening->args[5]), 0);
        for (const Step21Instance* rep : bodyRepresentations(*opening))
          for (const Step21Value& item : arg(rep, 3).items)
            if (item.kind == Kind::Ref) importItem(item.ref, at, 0);
      }
    });
    if (openings.empty()) return;
    SolidSet host{std::move(mesh_), std::move(primitives_)};
    mesh_ = TriangleMesh{};
    primitives_.clear();
    combineInto(std::move(host), openings, {}, product_id,
                 std::to_string(it->second.size()) + (it->second.size() == 1 ? " opening" : " openings") +
                     " (IfcRelVoidsElement)");
  }

  // IfcHalfSpaceSolid, IfcBoxedHalfSpace (its enclosure only speeds up a cut: ignored) and
  // IfcPolygonalBoundedHalfSpace, placed by `local`.
  std::optional<HalfSpace> halfSpace(const Step21Instance& in, const glm::dmat4& local) const {
    if (in.type != "IFCHALFSPACESOLID" && in.type != "IFCBOXEDHALFSPACE" &&
        in.type != "IFCPOLYGONALBOUNDEDHALFSPACE")
      return std::nullopt;
    const Step21Instance* surface = f_.deref(arg(&in, 0));
    if (!surface || surface->type != "IFCPLANE") throw ItemError{"a half-space not bounded by a plane"};
    HalfSpace h;
    h.plane = local * axisPlacement(f_.deref(arg(surface, 0)));
    // AgreementFlag true: the plane's normal points away from the material.
    h.material_below = textOf(arg(&in, 1)) != "F";
    if (in.type == "IFCPOLYGONALBOUNDEDHALFSPACE") {
      h.boundary_frame = local * axisPlacement(f_.deref(arg(&in, 2)));
      h.boundary = curvePoints(f_.deref(arg(&in, 3)));
    }
    return h;
  }

  // CadOptions::primitives off: the primitives become triangles of the product's mesh, at
  // the scene's default chordal tolerance (what the preprocessor would tessellate them at).
  void meshPrimitives() {
    for (const auto& [local, primitive] : primitives_) {
      TriangleMesh part;
      tessellatePrimitive(primitive, kDefaultChordalTolerance, part);
      appendMesh(part, local);
    }
    primitives_.clear();
  }

  static Transform toTransform(const glm::dmat4& m) {
    Transform t;
    t.origin = glm::dvec3(m[3]);
    t.linear = glm::mat3(glm::dmat3(m));
    return t;
  }

  // --- Items ---------------------------------------------------------------------------------
  void importItem(uint64_t id, const glm::dmat4& local, int depth) {
    const Step21Instance* item = f_.find(id);
    if (!item) return skipped(id, product_type_, "the item is missing");
    if (depth > kMaxDepth) return skipped(id, product_type_, "mapped items nested too deep");
    if (colour_ == 0)
      if (auto c = colours_.ofItem(id)) colour_ = *c;
    try {
      const std::string& t = item->type;
      if (t == "IFCEXTRUDEDAREASOLID") extruded(*item, local);
      else if (t == "IFCREVOLVEDAREASOLID") revolved(*item, local);
      else if (t == "IFCFACETEDBREP" || t == "IFCFACETEDBREPWITHVOIDS") shell(f_.deref(arg(item, 0)), local);
      else if (t == "IFCSHELLBASEDSURFACEMODEL" || t == "IFCFACEBASEDSURFACEMODEL")
        for (const Step21Value& s : arg(item, 0).items) shell(f_.deref(s), local);
      else if (t == "IFCPOLYGONALFACESET") polygonalFaceSet(*item, local);
      else if (t == "IFCTRIANGULATEDFACESET") triangulatedFaceSet(*item, local);
      else if (t == "IFCMAPPEDITEM") mapped(*item, local, depth);
      else if (t == "IFCBOOLEANCLIPPINGRESULT" || t == "IFCBOOLEANRESULT") boolean(id, *item, local, depth);
      else if (t == "IFCCSGSOLID") csgPrimitive(id, f_.deref(arg(item, 0)), local, depth);
      else if (t == "IFCBLOCK" || t == "IFCRIGHTCIRCULARCYLINDER" || t == "IFCSPHERE")
        csgPrimitive(id, item, local, depth);
      else if (t == "IFCSWEPTDISKSOLID") sweptDisk(*item, local);
      else throw ItemError{"geometry " + t + " is not read"};
    } catch (const ItemError& e) {
      skipped(id, product_type_, e.reason);
    }
  }

  void mapped(const Step21Instance& item, const glm::dmat4& local, int depth) {
    const Step21Instance* source = f_.deref(arg(&item, 0));
    const Step21Instance* op = f_.deref(arg(&item, 1));
    if (!source || source->type != "IFCREPRESENTATIONMAP") throw ItemError{"no representation map"};
    if (!map_colour_found_) map_colour_found_ = colours_.ofRepresentationMap(arg(&item, 0).ref);
    glm::dmat4 target(1.0);
    if (op && op->type.rfind("IFCCARTESIANTRANSFORMATIONOPERATOR3D", 0) == 0) {
      const glm::dvec3 origin = point(f_.deref(arg(op, 2)));
      const glm::dvec3 x = direction(f_.deref(arg(op, 0))).value_or(glm::dvec3(1, 0, 0));
      const glm::dvec3 z = op->args.size() > 4 ? direction(f_.deref(arg(op, 4))).value_or(glm::dvec3(0, 0, 1))
                                               : glm::dvec3(0, 0, 1);
      // Scale, and for the non-uniform operator Scale2 and Scale3 (each defaulting to Scale).
      const double s = numberOf(arg(op, 3), 1.0);
      glm::dvec3 scale(s);
      if (op->type == "IFCCARTESIANTRANSFORMATIONOPERATOR3DNONUNIFORM")
        scale = glm::dvec3(s, numberOf(arg(op, 5), s), numberOf(arg(op, 6), s));
      target = frame(origin, z, x) * glm::scale(glm::dmat4(1.0), scale);
    }
    const glm::dmat4 to = local * target * axisPlacement(f_.deref(arg(source, 0)));
    const Step21Instance* rep = f_.deref(arg(source, 1));
    for (const Step21Value& sub : arg(rep, 3).items)
      if (sub.kind == Kind::Ref) importItem(sub.ref, to, depth + 1);
  }

  // UNION: both operands; DIFFERENCE (IfcBooleanClippingResult is one): the second cut from the
  // first; INTERSECTION: what the two have in common.
  void boolean(uint64_t id, const Step21Instance& item, const glm::dmat4& local, int depth) {
    const std::string op = textOf(arg(&item, 0));
    auto operand = [&](size_t i) {
      const Step21Value& v = arg(&item, i);
      if (v.kind == Kind::Ref) importItem(v.ref, local, depth + 1);
    };
    if (op == "UNION") {
      operand(1);
      operand(2);
      return;
    }
    if (op != "DIFFERENCE" && op != "INTERSECTION") throw ItemError{"a boolean operator ." + op + "."};
    const bool intersect = op == "INTERSECTION";
    const std::string what = intersect ? "a boolean intersection" : "a boolean difference";
    SolidSet first = collectSolids([&] { operand(1); });
    if (first.empty()) return;
    std::vector<HalfSpace> half_spaces;
    SolidSet tools;
    try {
      const Step21Instance* second = f_.deref(arg(&item, 2));
      if (!second) throw ItemError{what + " without a second operand"};
      if (auto h = halfSpace(*second, local)) half_spaces.push_back(*h);
      else tools = collectSolids([&] { operand(2); });
    } catch (const ItemError& e) {
      notCut(id, what, e.reason);
      keep(std::move(first));
      return;
    }
    combineInto(std::move(first), tools, half_spaces, id, what, intersect);
  }

  void csgPrimitive(uint64_t id, const Step21Instance* in, const glm::dmat4& local, int depth) {
    if (!in) throw ItemError{"CSG solid without a tree"};
    if (in->type == "IFCBOOLEANRESULT") return boolean(id, *in, local, depth);
    const glm::dmat4 at = local * axisPlacement(f_.deref(arg(in, 0)));
    if (in->type == "IFCBLOCK") {  // its position is a corner
      const glm::dvec3 size(numberOf(arg(in, 1), 0) * length_, numberOf(arg(in, 2), 0) * length_,
                            numberOf(arg(in, 3), 0) * length_);
      if (!(size.x > 0 && size.y > 0 && size.z > 0)) throw ItemError{"a block without volume"};
      add(at * glm::translate(glm::dmat4(1.0), 0.5 * size), Box{glm::vec3(0.5 * size)});
    } else if (in->type == "IFCRIGHTCIRCULARCYLINDER") {  // centred on its position
      const double h = numberOf(arg(in, 1), 0) * length_, r = numberOf(arg(in, 2), 0) * length_;
      if (!(h > 0 && r > 0)) throw ItemError{"a cylinder without volume"};
      add(at * glm::translate(glm::dmat4(1.0), glm::dvec3(0, 0, -0.5 * h)), Cylinder{float(r), float(h), true});
    } else if (in->type == "IFCSPHERE") {
      const double r = numberOf(arg(in, 1), 0) * length_;
      if (!(r > 0)) throw ItemError{"a sphere without volume"};
      add(at, Sphere{float(r)});
    } else {
      throw ItemError{"CSG primitive " + in->type + " is not read"};
    }
  }

  // Keeps `primitive` at `local`. A scale in `local` along the primitive's own axes (mapped
  // items scale their representation: a unit-depth column stretched to its height) goes into
  // the primitive's parameters, so every placement stays a rotation; a scale that would shear
  // it (a cylinder scaled unevenly across its axis) is an error.
  void add(const glm::dmat4& local, Primitive primitive) {
    glm::dmat4 rigid = local;
    glm::dvec3 s(1.0);
    for (int a = 0; a < 3; ++a) {
      s[a] = glm::length(glm::dvec3(local[a]));
      if (!(s[a] > 1e-12)) throw ItemError{"a placement that flattens the item"};
      rigid[a] = glm::dvec4(glm::dvec3(local[a]) / s[a], 0.0);
    }
    for (int a = 0; a < 3; ++a)
      if (std::abs(glm::dot(glm::dvec3(rigid[a]), glm::dvec3(rigid[(a + 1) % 3]))) > 1e-6)
        throw ItemError{"a placement that shears the item"};
    const bool uniform_xy = std::abs(s.x - s.y) <= 1e-9 * std::max(s.x, s.y);
    const bool uniform = uniform_xy && std::abs(s.x - s.z) <= 1e-9 * std::max(s.x, s.z);
    if (auto* b = std::get_if<Box>(&primitive)) {
      b->half_extents *= glm::vec3(s);
    } else if (auto* c = std::get_if<Cylinder>(&primitive)) {
      if (!uniform_xy) throw ItemError{"a cylinder scaled unevenly across its axis"};
      c->radius *= float(s.x);
      c->height *= float(s.z);
    } else if (auto* e = std::get_if<Extrusion>(&primitive)) {
      for (glm::vec2& p : e->profile) p *= glm::vec2(s);
      e->height *= float(s.z);
    } else if (!uniform) {
      throw ItemError{"a scaled sphere, bend or revolution"};
    } else if (auto* sp = std::get_if<Sphere>(&primitive)) {
      sp->radius *= float(s.x);
    } else if (auto* t = std::get_if<TorusSegment>(&primitive)) {
      t->major_radius *= float(s.x);
      t->minor_radius *= float(s.x);
    } else if (auto* r = std::get_if<Revolution>(&primitive)) {
      for (glm::vec2& p : r->profile) p *= float(s.x);
    }
    if (glm::determinant(glm::dmat3(rigid)) < 0.0) throw ItemError{"a mirrored placement"};
    primitives_.emplace_back(rigid, std::move(primitive));
  }

  // The points of a profile's outer curve, in its plane, counter-clockwise, without the closing
  // repeat.
  std::vector<glm::dvec2> curvePoints(const Step21Instance* curve) const {
    std::vector<glm::dvec2> pts;
    if (!curve) throw ItemError{"a profile without a curve"};
    if (curve->type == "IFCPOLYLINE") {
      for (const Step21Value& p : arg(curve, 0).items) pts.push_back(glm::dvec2(point(f_.deref(p))));
    } else if (curve->type == "IFCINDEXEDPOLYCURVE") {
      pts = indexedPolyCurvePoints(*curve);
    } else if (curve->type == "IFCCOMPOSITECURVE") {
      for (const Step21Value& sv : arg(curve, 0).items) {
        const Step21Instance* segment = f_.deref(sv);
        if (!segment) throw ItemError{"a composite curve with a missing segment"};
        std::vector<glm::dvec2> part = segmentPoints(f_.deref(arg(segment, 2)));
        if (textOf(arg(segment, 1)) == "F") std::reverse(part.begin(), part.end());
        for (const glm::dvec2& p : part)
          if (pts.empty() || glm::length(pts.back() - p) > 1e-9) pts.push_back(p);
      }
    } else {
      throw ItemError{"profile curve " + curve->type + " is not read"};
    }
    if (pts.size() > 1 && glm::length(pts.front() - pts.back()) < 1e-9) pts.pop_back();
    if (pts.size() < 3) throw ItemError{"a profile of fewer than three points"};
    const double area2 = loopArea2(pts);
    if (std::abs(area2) < 1e-18) throw ItemError{"a profile without area"};
    if (area2 < 0.0) std::reverse(pts.begin(), pts.end());
    return pts;
  }

  // An IfcIndexedPolyCurve: its points in order, or, when it lists segments, each line segment's
  // points and each arc (three points: start, one on the way, end) sampled every 10 degrees.
  std::vector<glm::dvec2> indexedPolyCurvePoints(const Step21Instance& curve) const {
    const Step21Instance* list = f_.deref(arg(&curve, 0));
    if (!list) throw ItemError{"an indexed polycurve without points"};
    std::vector<glm::dvec2> coords;
    for (const Step21Value& c : arg(list, 0).items)
      if (c.items.size() >= 2) coords.push_back(glm::dvec2(numberOf(c.items[0], 0), numberOf(c.items[1], 0)) * length_);
    const Step21Value& segments = arg(&curve, 1);
    if (segments.kind != Kind::List || segments.items.empty()) return coords;
    std::vector<glm::dvec2> pts;
    auto append = [&](const glm::dvec2& p) {
      if (pts.empty() || glm::length(pts.back() - p) > 1e-9) pts.push_back(p);
    };
    for (const Step21Value& segment : segments.items) {
      if (segment.kind != Kind::Typed || segment.items.empty())
        throw ItemError{"an indexed polycurve segment that is not a line or arc index"};
      std::vector<glm::dvec2> p;
      for (const Step21Value& i : segment.items[0].items) {
        const double index = numberOf(i, 0);
        if (!(index >= 1.0 && index <= double(coords.size())))
          throw ItemError{"an indexed polycurve segment index outside its points"};
        p.push_back(coords[size_t(index) - 1]);
      }
      if (segment.text == "IFCLINEINDEX") {
        for (const glm::dvec2& q : p) append(q);
      } else if (segment.text == "IFCARCINDEX") {
        if (p.size() != 3) throw ItemError{"an arc index without three points"};
        for (const glm::dvec2& q : arcThrough(p[0], p[1], p[2])) append(q);
      } else {
        throw ItemError{"indexed polycurve segment " + segment.text + " is not read"};
      }
    }
    return pts;
  }

  // The points of one segment of a composite curve: a polyline, or a line or circle trimmed by
  // two Cartesian points (arcs sampled every 10 degrees at most).
  std::vector<glm::dvec2> segmentPoints(const Step21Instance* c) const {
    if (!c) throw ItemError{"a composite curve segment without a curve"};
    std::vector<glm::dvec2> pts;
    if (c->type == "IFCPOLYLINE") {
      for (const Step21Value& p : arg(c, 0).items) pts.push_back(glm::dvec2(point(f_.deref(p))));
      return pts;
    }
    if (c->type != "IFCTRIMMEDCURVE") throw ItemError{"curve segment " + c->type + " is not read"};
    auto trimPoint = [&](const Step21Value& trims) -> std::optional<glm::dvec2> {
      for (const Step21Value& t : trims.items)
        if (const Step21Instance* p = f_.deref(t); p && p->type == "IFCCARTESIANPOINT")
          return glm::dvec2(point(p));
      return std::nullopt;
    };
    const auto a = trimPoint(arg(c, 1)), b = trimPoint(arg(c, 2));
    if (!a || !b) throw ItemError{"a trimmed curve not trimmed by points"};
    const bool sense = textOf(arg(c, 3)) != "F";
    const Step21Instance* basis = f_.deref(arg(c, 0));
    if (basis && basis->type == "IFCLINE") return sense ? std::vector{*a, *b} : std::vector{*b, *a};
    if (!basis || basis->type != "IFCCIRCLE") throw ItemError{"a trimmed curve that is not a line or circle"};
    const glm::dvec2 centre(glm::dvec3(axisPlacement(f_.deref(arg(basis, 0)))[3]));
    const double r = numberOf(arg(basis, 1), 0.0) * length_;
    double t0 = std::atan2(a->y - centre.y, a->x - centre.x);
    double t1 = std::atan2(b->y - centre.y, b->x - centre.x);
    if (sense) { while (t1 <= t0) t1 += 2.0 * std::numbers::pi; }
    else { while (t1 >= t0) t1 -= 2.0 * std::numbers::pi; }
    return arcPoints(centre, r, t0, t1 - t0);
  }

  // A profile as loops in the extrusion's plane (its own 2D placement applied): the outer one
  // and its holes. Circles become 48-gons.
  void profileLoops(const Step21Instance* profile, std::vector<glm::dvec2>& outer,
                    std::vector<std::vector<glm::dvec2>>& holes) const {
    const std::string& t = profile->type;
    auto placed = [&](std::vector<glm::dvec2> pts) {
      const glm::dmat4 plane = axisPlacement(f_.deref(arg(profile, 2)));
      for (glm::dvec2& p : pts) p = glm::dvec2(plane * glm::dvec4(p, 0.0, 1.0));
      return pts;
    };
    if (t == "IFCRECTANGLEPROFILEDEF" || t == "IFCRECTANGLEHOLLOWPROFILEDEF" ||
        t == "IFCROUNDEDRECTANGLEPROFILEDEF") {
      const double x = 0.5 * numberOf(arg(profile, 3), 0) * length_;
      const double y = 0.5 * numberOf(arg(profile, 4), 0) * length_;
      if (!(x > 0 && y > 0)) throw ItemError{"a rectangle without area"};
      outer = placed({{-x, -y}, {x, -y}, {x, y}, {-x, y}});
    } else if (t == "IFCCIRCLEPROFILEDEF" || t == "IFCCIRCLEHOLLOWPROFILEDEF") {
      const double r = numberOf(arg(profile, 3), 0) * length_;
      if (!(r > 0)) throw ItemError{"a circle without radius"};
      std::vector<glm::dvec2> circle;
      for (int i = 0; i < 48; ++i) {
        const double a = 2.0 * std::numbers::pi * i / 48.0;
        circle.push_back(r * glm::dvec2(std::cos(a), std::sin(a)));
      }
      outer = placed(circle);
    } else if (const auto section = steelSectionOf(t)) {
      outer = placed(steelOutline(*section, *profile));
    } else if (t == "IFCARBITRARYCLOSEDPROFILEDEF" || t == "IFCARBITRARYPROFILEDEFWITHVOIDS") {
      outer = curvePoints(f_.deref(arg(profile, 2)));
      if (t == "IFCARBITRARYPROFILEDEFWITHVOIDS")
        for (const Step21Value& inner : arg(profile, 3).items) holes.push_back(curvePoints(f_.deref(inner)));
    } else {
      throw ItemError{"profile " + t + " is not read"};
    }
  }

  // A steel section's outline in its profile's plane (before the profile's own placement): its
  // dimensions follow ProfileType, ProfileName and Position.
  std::vector<glm::dvec2> steelOutline(SteelSection section, const Step21Instance& profile) const {
    std::vector<double> dimensions;
    for (size_t i = 3; i < profile.args.size(); ++i)
      dimensions.push_back(numberOf(profile.args[i], std::numeric_limits<double>::quiet_NaN()) * length_);
    try {
      return steelSectionOutline(section, dimensions);
    } catch (const SteelSectionError& e) {
      throw ItemError{"profile " + profile.type + ": " + e.what()};
    }
  }

  void extruded(const Step21Instance& item, const glm::dmat4& local) {
    const Step21Instance* profile = f_.deref(arg(&item, 0));
    const glm::dmat4 at = local * axisPlacement(f_.deref(arg(&item, 1)));
    const glm::dvec3 dir = direction(f_.deref(arg(&item, 2))).value_or(glm::dvec3(0, 0, 1));
    const double depth = numberOf(arg(&item, 3), 0.0) * length_;
    if (!(depth > 0.0)) throw ItemError{"an extrusion without depth"};
    if (!profile) throw ItemError{"an extrusion without a profile"};
    const std::string& t = profile->type;
    const bool straight = std::abs(dir.z - 1.0) <= 1e-6;
    const bool voids = t == "IFCARBITRARYPROFILEDEFWITHVOIDS" && !arg(profile, 3).items.empty();
    if (!straight || voids) {
      // No primitive holds it: a mesh prism of the profile and its holes along the direction.
      if (!(dir.z > 1e-6)) throw ItemError{"an extrusion along its own profile plane"};
      std::vector<glm::dvec2> outer;
      std::vector<std::vector<glm::dvec2>> holes;
      profileLoops(profile, outer, holes);
      TriangleMesh prism;
      if (appendProfilePrism(outer, holes, dir * depth, prism) == 0)
        throw ItemError{"a profile that does not triangulate"};
      appendMesh(prism, at);
      return;
    }
    const glm::dmat4 plane = at * axisPlacement(f_.deref(arg(profile, 2)));
    if (t == "IFCRECTANGLEPROFILEDEF" || t == "IFCRECTANGLEHOLLOWPROFILEDEF" ||
        t == "IFCROUNDEDRECTANGLEPROFILEDEF") {
      const double x = numberOf(arg(profile, 3), 0) * length_, y = numberOf(arg(profile, 4), 0) * length_;
      if (!(x > 0 && y > 0)) throw ItemError{"a rectangle without area"};
      add(plane * glm::translate(glm::dmat4(1.0), glm::dvec3(0, 0, 0.5 * depth)),
          Box{glm::vec3(float(0.5 * x), float(0.5 * y), float(0.5 * depth))});
    } else if (t == "IFCCIRCLEPROFILEDEF" || t == "IFCCIRCLEHOLLOWPROFILEDEF") {
      const double r = numberOf(arg(profile, 3), 0) * length_;
      if (!(r > 0)) throw ItemError{"a circle without radius"};
      add(plane, Cylinder{float(r), float(depth), true});
    } else if (steelSectionOf(t)) {
      std::vector<glm::dvec2> outer;
      std::vector<std::vector<glm::dvec2>> holes;
      profileLoops(profile, outer, holes);
      Extrusion e;
      for (const glm::dvec2& p : outer) e.profile.push_back(glm::vec2(p));
      e.height = float(depth);
      add(at, std::move(e));
    } else if (t == "IFCARBITRARYCLOSEDPROFILEDEF" || t == "IFCARBITRARYPROFILEDEFWITHVOIDS") {
      Extrusion e;
      for (const glm::dvec2& p : curvePoints(f_.deref(arg(profile, 2)))) e.profile.push_back(glm::vec2(p));
      e.height = float(depth);
      add(at, std::move(e));
    } else {
      throw ItemError{"profile " + t + " is not read"};
    }
  }

  void revolved(const Step21Instance& item, const glm::dmat4& local) {
    const Step21Instance* profile = f_.deref(arg(&item, 0));
    const glm::dmat4 at = local * axisPlacement(f_.deref(arg(&item, 1)));
    const Step21Instance* axis = f_.deref(arg(&item, 2));
    const double sweep = numberOf(arg(&item, 3), 0.0) * angle_;
    if (!profile || !axis) throw ItemError{"a revolution without profile or axis"};
    if (!(sweep > 0.0)) throw ItemError{"a revolution without angle"};
    const glm::dvec3 a = point(f_.deref(arg(axis, 0)));
    const glm::dvec3 u = direction(f_.deref(arg(axis, 1))).value_or(glm::dvec3(0, 0, 1));
    // The profile lies in the position's XY plane; the axis too.
    auto toRevolution = [&](const glm::dvec3& p, glm::dvec3& foot) {
      const double along = glm::dot(p - a, u);
      foot = a + along * u;
      return glm::dvec2(glm::length(p - foot), along);
    };
    const std::string& t = profile->type;
    if (t == "IFCCIRCLEPROFILEDEF" || t == "IFCCIRCLEHOLLOWPROFILEDEF") {
      const glm::dmat4 plane = axisPlacement(f_.deref(arg(profile, 2)));
      const glm::dvec3 c(plane[3]);
      const double r = numberOf(arg(profile, 3), 0) * length_;
      glm::dvec3 foot;
      const glm::dvec2 rz = toRevolution(c, foot);
      if (!(r > 0) || !(rz.x > r)) throw ItemError{"a revolved circle that crosses its axis"};
      add(at * frame(foot, u, c - foot), TorusSegment{float(rz.x), float(r), float(sweep)});
      return;
    }
    if (t != "IFCARBITRARYCLOSEDPROFILEDEF") throw ItemError{"revolved profile " + t + " is not read"};
    const std::vector<glm::dvec2> pts = curvePoints(f_.deref(arg(profile, 2)));
    Revolution rev;
    glm::dvec3 x_dir(0.0), foot;
    for (const glm::dvec2& p : pts) {
      const glm::dvec2 rz = toRevolution(glm::dvec3(p, 0.0), foot);
      if (glm::length(x_dir) == 0.0 && rz.x > 1e-12) x_dir = glm::dvec3(p, 0.0) - foot;
      rev.profile.push_back(glm::vec2(rz));
    }
    if (glm::length(x_dir) == 0.0) throw ItemError{"a revolved profile on its axis"};
    rev.profile.push_back(rev.profile.front());
    rev.sweep_rad = float(sweep);
    add(at * frame(a, u, x_dir), std::move(rev));
  }

  void sweptDisk(const Step21Instance& item, const glm::dmat4& local) {
    const Step21Instance* directrix = f_.deref(arg(&item, 0));
    const double r = numberOf(arg(&item, 1), 0.0) * length_;
    if (!directrix || directrix->type != "IFCPOLYLINE") throw ItemError{"a swept disk along a curve that is not a polyline"};
    if (!(r > 0)) throw ItemError{"a swept disk without radius"};
    std::vector<glm::dvec3> pts;
    for (const Step21Value& p : arg(directrix, 0).items) pts.push_back(point(f_.deref(p)));
    for (size_t i = 0; i + 1 < pts.size(); ++i) {
      const glm::dvec3 d = pts[i + 1] - pts[i];
      const double length = glm::length(d);
      if (length < 1e-9) continue;
      add(local * frame(pts[i], d, glm::dvec3(1, 0, 0)), Cylinder{float(r), float(length), true});
    }
  }

  // --- Meshes --------------------------------------------------------------------------------
  // Appends a planar polygon, triangulated in its best-fitting plane: projected along its
  // normal's largest axis, wound so its own winding is counter-clockwise there, so the
  // triangles keep the face's orientation.
  // A planar face with its holes, triangulated in the plane it faces (holes bridged into the
  // outer loop, profile_prism.h).
  void polygon(const std::vector<glm::dvec3>& pts, const std::vector<std::vector<glm::dvec3>>& holes,
               const glm::dmat4& local) {
    const size_t n = pts.size();
    if (n < 3) return;
    glm::dvec3 normal(0.0);
    for (size_t i = 0; i < n; ++i) normal += glm::cross(pts[i], pts[(i + 1) % n]);
    if (glm::length(normal) < 1e-18) return;
    const int drop = std::abs(normal.x) > std::abs(normal.y)
                         ? (std::abs(normal.x) > std::abs(normal.z) ? 0 : 2)
                         : (std::abs(normal.y) > std::abs(normal.z) ? 1 : 2);
    const int ax = (drop + 1) % 3, ay = (drop + 2) % 3;
    const double sign = normal[drop] > 0 ? 1.0 : -1.0;
    auto projected = [&](const std::vector<glm::dvec3>& loop) {
      std::vector<glm::dvec2> out;
      for (const glm::dvec3& p : loop) out.push_back(glm::dvec2(p[ax], p[ay] * sign));
      return out;
    };
    std::vector<std::vector<glm::dvec2>> holes2;
    for (const auto& hole : holes) holes2.push_back(projected(hole));
    const uint32_t base = uint32_t(mesh_.positions.size());
    auto place = [&](const std::vector<glm::dvec3>& loop) {
      for (const glm::dvec3& p : loop) mesh_.positions.push_back(glm::vec3(local * glm::dvec4(p, 1.0)));
    };
    place(pts);
    for (const auto& hole : holes) place(hole);
    for (uint32_t i : triangulateProfile(projected(pts), holes2)) mesh_.indices.push_back(base + i);
  }

  void shell(const Step21Instance* s, const glm::dmat4& local) {
    if (!s) throw ItemError{"a B-rep without a shell"};
    for (const Step21Value& fv : arg(s, 0).items) {
      const Step21Instance* face = f_.deref(fv);
      if (!face) continue;
      // The outer bound (IfcFaceOuterBound, else the first) and the holes (the other bounds).
      std::vector<glm::dvec3> outer;
      std::vector<std::vector<glm::dvec3>> holes;
      const auto& bounds = arg(face, 0).items;
      size_t outer_at = 0;
      for (size_t b = 0; b < bounds.size(); ++b)
        if (const Step21Instance* bound = f_.deref(bounds[b]); bound && bound->type == "IFCFACEOUTERBOUND")
          outer_at = b;
      for (size_t b = 0; b < bounds.size(); ++b) {
        const Step21Instance* bound = f_.deref(bounds[b]);
        if (!bound) continue;
        const Step21Instance* loop = f_.deref(arg(bound, 0));
        if (!loop || loop->type != "IFCPOLYLOOP") continue;
        std::vector<glm::dvec3> pts;
        for (const Step21Value& p : arg(loop, 0).items) pts.push_back(point(f_.deref(p)));
        if (textOf(arg(bound, 1)) == "F") std::reverse(pts.begin(), pts.end());
        if (b == outer_at) outer = std::move(pts);
        else holes.push_back(std::move(pts));
      }
      polygon(outer, holes, local);
    }
  }

  std::vector<glm::dvec3> pointList(const Step21Instance* list) const {
    std::vector<glm::dvec3> pts;
    if (!list) throw ItemError{"a face set without coordinates"};
    for (const Step21Value& c : arg(list, 0).items) {
      glm::dvec3 p(0.0);
      for (size_t i = 0; i < 3 && i < c.items.size(); ++i) p[int(i)] = numberOf(c.items[i], 0.0) * length_;
      pts.push_back(p);
    }
    return pts;
  }

  // 1-based coordinate index, through PnIndex when the set has one.
  static std::optional<size_t> coordinate(double index, const std::vector<size_t>& pn, size_t count) {
    if (!(index >= 1.0) || index > 1e12) return std::nullopt;
    size_t i = size_t(index) - 1;
    if (!pn.empty()) {
      if (i >= pn.size()) return std::nullopt;
      i = pn[i] - 1;
    }
    return i < count ? std::optional<size_t>(i) : std::nullopt;
  }

  void polygonalFaceSet(const Step21Instance& item, const glm::dmat4& local) {
    const std::vector<glm::dvec3> pts = pointList(f_.deref(arg(&item, 0)));
    std::vector<size_t> pn;
    for (const Step21Value& v : arg(&item, 3).items) pn.push_back(size_t(std::max(1.0, numberOf(v, 1))));
    for (const Step21Value& fv : arg(&item, 2).items) {
      const Step21Instance* face = f_.deref(fv);
      if (!face) continue;
      auto loopOf = [&](const Step21Value& indices) {
        std::vector<glm::dvec3> loop;
        for (const Step21Value& iv : indices.items) {
          const auto i = coordinate(numberOf(iv, 0), pn, pts.size());
          if (!i) throw ItemError{"a face index outside the coordinates"};
          loop.push_back(pts[*i]);
        }
        return loop;
      };
      // IfcIndexedPolygonalFaceWithVoids lists its holes' indices second.
      std::vector<std::vector<glm::dvec3>> holes;
      if (face->type == "IFCINDEXEDPOLYGONALFACEWITHVOIDS")
        for (const Step21Value& inner : arg(face, 1).items) holes.push_back(loopOf(inner));
      polygon(loopOf(arg(face, 0)), holes, local);
    }
  }

  void triangulatedFaceSet(const Step21Instance& item, const glm::dmat4& local) {
    const std::vector<glm::dvec3> pts = pointList(f_.deref(arg(&item, 0)));
    std::vector<size_t> pn;
    for (const Step21Value& v : arg(&item, 4).items) pn.push_back(size_t(std::max(1.0, numberOf(v, 1))));
    const uint32_t base = uint32_t(mesh_.positions.size());
    for (const glm::dvec3& p : pts) mesh_.positions.push_back(glm::vec3(local * glm::dvec4(p, 1.0)));
    for (const Step21Value& t : arg(&item, 3).items) {
      if (t.items.size() != 3) throw ItemError{"a triangle without three indices"};
      uint32_t tri[3];
      for (int k = 0; k < 3; ++k) {
        const auto i = coordinate(numberOf(t.items[size_t(k)], 0), pn, pts.size());
        if (!i) throw ItemError{"a triangle index outside the coordinates"};
        tri[k] = base + uint32_t(*i);
      }
      mesh_.indices.insert(mesh_.indices.end(), {tri[0], tri[1], tri[2]});
    }
  }

  const Step21File& f_;
  SceneSink& sink_;
  const ReadOptions& options_;
  const IfcFrames frames_;
  const double length_;  // metres per file length unit
  const double angle_;   // radians per file angle unit
  const IfcColours colours_;
  std::unordered_map<uint64_t, std::string> layer_of_;
  std::map<std::string, uint32_t> layers_;
  uint32_t next_id_ = 0, products_ = 0;
  int uncut_ = 0, skipped_warnings_ = 0;
  std::unordered_map<uint64_t, std::vector<uint64_t>> openings_of_;  // host -> opening products
  // The product being imported.
  std::string product_type_;
  TriangleMesh mesh_;
  std::vector<std::pair<glm::dmat4, Primitive>> primitives_;
  uint32_t colour_ = 0;
  std::optional<uint32_t> map_colour_found_;  // of the first mapped item whose type has a colour
};

}  // namespace

// IfcProduct's attributes: GlobalId, OwnerHistory, Name, Description, ObjectType,
// ObjectPlacement, Representation. Its subtypes are recognized by that shape, so every class of
// both schemas is read without a schema table.
bool isDrawnIfcProduct(const Step21File& file, const Step21Instance& in) {
  static const std::unordered_set<std::string> not_drawn = {
      "IFCOPENINGELEMENT", "IFCOPENINGSTANDARDCASE", "IFCSPACE", "IFCANNOTATION", "IFCGRID",
      "IFCVIRTUALELEMENT", "IFCSITE"};
  if (in.args.size() < 7 || not_drawn.count(in.type)) return false;
  if (in.args[0].kind != Kind::String || in.args[0].text.size() != 22) return false;
  const Step21Instance* shape = file.deref(in.args[6]);
  return shape && (shape->type == "IFCPRODUCTDEFINITIONSHAPE" ||
                   shape->type == "IFCPRODUCTREPRESENTATION");
}

void readIfc(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options) {
  const Step21File file = Step21File::read(path);
  if (file.schema().rfind("IFC", 0) != 0)
    throw FormatError(path.string(), "not an IFC file: its FILE_SCHEMA is '" + file.schema() + "'");
  IfcImporter importer(file, sink, options);
  importer.run();
  if (importer.objects() == 0)
    throw FormatError(path.string(), "no product with geometry TeraWalk can read (" +
                                         std::to_string(importer.products()) + " products tried)");
}

}  // namespace tw
