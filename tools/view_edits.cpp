// The viewer's edits, the gizmo and the exploded view (view_edits.h).
#include "view_edits.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include <imgui.h>

#include "bcf_ids.h"
#include "change_set_view.h"
#include "view_log.h"

namespace tw {
namespace {

constexpr double kExplodeSeconds = 0.5;
constexpr double kGizmoScreenShare = 0.12;  // the arrows' length, of the view's height
const glm::dvec3 kAxes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
const ImU32 kAxisColours[3] = {IM_COL32(220, 50, 40, 255), IM_COL32(40, 180, 60, 255),
                               IM_COL32(50, 90, 230, 255)};

double snap(double value, double step) { return std::round(value / step) * step; }

// A world point on the window, y down; nullopt behind the eye.
std::optional<glm::dvec2> screen(const Camera& camera, int width, int height, const glm::dvec3& p) {
  return imagePoint(camera, width, height, p);
}

double distanceToSegment(const glm::dvec2& p, const glm::dvec2& a, const glm::dvec2& b) {
  const glm::dvec2 ab = b - a;
  const double t = std::clamp(glm::dot(p - a, ab) / std::max(glm::dot(ab, ab), 1e-12), 0.0, 1.0);
  return glm::length(p - (a + t * ab));
}

// The ring about `axis`: points on the circle of `radius` around `centre`.
std::vector<glm::dvec3> ringPoints(const glm::dvec3& centre, int axis, double radius) {
  const glm::dvec3 u = kAxes[(axis + 1) % 3], v = kAxes[(axis + 2) % 3];
  std::vector<glm::dvec3> points;
  for (int k = 0; k <= 48; ++k) {
    const double a = 2.0 * std::numbers::pi * k / 48;
    points.push_back(centre + radius * (std::cos(a) * u + std::sin(a) * v));
  }
  return points;
}

// The square of the plane whose normal is `axis`: its four corners.
std::array<glm::dvec3, 4> planeSquare(const glm::dvec3& centre, int axis, double length) {
  const glm::dvec3 u = kAxes[(axis + 1) % 3], v = kAxes[(axis + 2) % 3];
  const double a = 0.2 * length, b = 0.38 * length;
  return {centre + a * u + a * v, centre + b * u + a * v, centre + b * u + b * v, centre + a * u + b * v};
}

}  // namespace

ViewEdits::ViewEdits(Walkthrough& walk, ViewSelection& selection, std::filesystem::path changes_file,
                     std::string author)
    : walk_(walk), selection_(selection), file_(std::move(changes_file)), author_(std::move(author)) {
  try {
    changes_ = readChangeSet(file_);
    refresh();
    if (!changes_.empty())
      viewSay("edits: %zu changes from %s\n", changes_.changes().size(), file_.string().c_str());
  } catch (const std::exception& e) {
    load_error_ = e.what();
    changes_ = ChangeSet();
    std::fprintf(stderr, "terawalk: %s; edits are kept in memory, that file is not written over\n",
                 load_error_.c_str());
  }
}

std::vector<std::string> ViewEdits::selectedKeys() const {
  std::vector<std::string> keys;
  const PackageView& view = walk_.package();
  for (uint32_t o : selection_.selected()) {
    std::string key(view.objectDbKey(o));
    if (key.empty()) key = std::string(view.objectName(o));
    if (!key.empty() && std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
  }
  return keys;
}

bool ViewEdits::keyCentre(const std::string& key, glm::dvec3& centre) const {
  glm::dvec3 lo, hi;
  if (!movedBounds(walk_.package(), objectsOfChangeKey(walk_.package(), key), changes_.placement(key), lo, hi))
    return false;
  centre = 0.5 * (lo + hi);
  return true;
}

bool ViewEdits::selectionCentre(glm::dvec3& centre, double& size) const {
  glm::dvec3 lo(1e300), hi(-1e300);
  bool any = false;
  for (const std::string& key : selectedKeys()) {
    glm::dvec3 c;
    if (!keyCentre(key, c)) continue;
    lo = glm::min(lo, c);
    hi = glm::max(hi, c);
    any = true;
  }
  if (!any) return false;
  centre = 0.5 * (lo + hi);
  size = glm::length(hi - lo);
  return true;
}

void ViewEdits::addPerKey(const std::vector<std::string>& keys,
                          const std::function<Change(const std::string&, const glm::dvec3&)>& make) {
  const std::string date = bcf::utcNow();
  for (const std::string& key : keys) {
    glm::dvec3 centre;
    if (!keyCentre(key, centre)) continue;
    Change c = make(key, centre);
    c.key = key;
    c.author = author_;
    c.date = date;
    changes_.add(std::move(c));
  }
  refresh();
}

void ViewEdits::moveSelection(const glm::dvec3& translation) {
  const glm::dvec3 t(snap(translation.x, kMoveStepM), snap(translation.y, kMoveStepM),
                     snap(translation.z, kMoveStepM));
  if (t == glm::dvec3(0.0)) return;
  addPerKey(selectedKeys(), [&](const std::string&, const glm::dvec3& centre) {
    Change c;
    c.kind = Change::Kind::Move;
    c.old_pivot = centre;
    c.new_pivot = centre + t;
    c.transform = moveTransform(centre, t);
    return c;
  });
  if (!drag_)
    viewSay("edits: moved %zu objects by (%.3f, %.3f, %.3f) m\n", selectedKeys().size(), t.x, t.y, t.z);
}

void ViewEdits::rotateSelection(const glm::dvec3& axis, double degrees) {
  const double d = snap(degrees, kRotateStepDeg);
  if (d == 0.0) return;
  addPerKey(selectedKeys(), [&](const std::string&, const glm::dvec3& centre) {
    Change c;
    c.kind = Change::Kind::Move;
    c.old_pivot = c.new_pivot = centre;
    c.transform = moveTransform(centre, glm::dvec3(0.0), axis, d * std::numbers::pi / 180.0);
    return c;
  });
  if (!drag_) viewSay("edits: rotated %zu objects by %.0f degrees\n", selectedKeys().size(), d);
}

void ViewEdits::scaleSelection(double factor) {
  if (!(factor > 0.0) || factor == 1.0) return;
  addPerKey(selectedKeys(), [&](const std::string&, const glm::dvec3& centre) {
    Change c;
    c.kind = Change::Kind::Move;
    c.old_pivot = c.new_pivot = centre;
    c.transform = moveTransform(centre, glm::dvec3(0.0), {0, 0, 1}, 0.0, factor);
    return c;
  });
}

void ViewEdits::hideSelection() {
  addPerKey(selectedKeys(), [&](const std::string&, const glm::dvec3&) {
    Change c;
    c.kind = Change::Kind::Hide;
    c.hidden = true;
    return c;
  });
  selection_.clear();
}

void ViewEdits::commentSelection(const std::string& text) {
  if (text.empty()) return;
  addPerKey(selectedKeys(), [&](const std::string&, const glm::dvec3&) {
    Change c;
    c.kind = Change::Kind::Comment;
    c.text = text;
    return c;
  });
}

bool ViewEdits::undo() {
  const bool done = changes_.undo();
  if (done) refresh();
  viewSay("edits: %s (%zu changes, %zu to redo)\n", done ? "undone" : "nothing to undo",
              changes_.undoable(), changes_.redoable());
  return done;
}

bool ViewEdits::redo() {
  const bool done = changes_.redo();
  if (done) refresh();
  viewSay("edits: %s (%zu changes, %zu to redo)\n", done ? "redone" : "nothing to redo",
              changes_.undoable(), changes_.redoable());
  return done;
}

bool ViewEdits::save() {
  if (!load_error_.empty()) {
    std::fprintf(stderr, "terawalk: %s could not be read; not written over\n", file_.string().c_str());
    return false;
  }
  try {
    writeChangeSet(file_, changes_);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "terawalk: %s\n", e.what());
    return false;
  }
  viewSay("edits: %zu changes saved to %s\n", changes_.changes().size(), file_.string().c_str());
  return true;
}

void ViewEdits::explode(double factor, double now_s) {
  if (factor != 1.0) {
    // Each selected object pushed from the selection's common centre along its own offset.
    const PackageView& view = walk_.package();
    explode_offsets_.clear();
    std::vector<std::pair<uint32_t, glm::dvec3>> centres;
    glm::dvec3 common(0.0);
    for (uint32_t o : selection_.selected()) {
      std::string key(view.objectDbKey(o));
      if (key.empty()) key = std::string(view.objectName(o));
      glm::dvec3 lo, hi;
      if (!movedBounds(view, {o}, changes_.placement(key), lo, hi)) continue;
      centres.emplace_back(o, 0.5 * (lo + hi));
      common += 0.5 * (lo + hi);
    }
    if (centres.empty()) return;
    common /= double(centres.size());
    for (const auto& [o, c] : centres) explode_offsets_[o] = c - common;
  }
  explode_from_ = explode_now_;
  explode_to_ = factor;
  explode_start_s_ = now_s;
  viewSay("edits: explode to %.2f over %zu objects\n", factor, explode_offsets_.size());
}

void ViewEdits::update(double now_s) {
  if (explode_now_ == explode_to_) return;
  const double s = std::clamp((now_s - explode_start_s_) / kExplodeSeconds, 0.0, 1.0);
  const double eased = s * s * (3.0 - 2.0 * s);
  explode_now_ = s >= 1.0 ? explode_to_ : explode_from_ + (explode_to_ - explode_from_) * eased;
  if (explode_now_ == 1.0 && explode_to_ == 1.0) explode_offsets_.clear();
  refresh();
}

void ViewEdits::refresh() {
  const PackageView& view = walk_.package();
  // Each object's placement: its key's moves, then its explode offset.
  std::map<uint32_t, glm::dmat4> places;
  for (const std::string& key : changes_.movedKeys())
    for (uint32_t o : objectsOfChangeKey(view, key)) places[o] = changes_.placement(key);
  for (const auto& [o, offset] : explode_offsets_) {
    auto [it, added] = places.emplace(o, glm::dmat4(1.0));
    if (added) {
      std::string key(view.objectDbKey(o));
      if (key.empty()) key = std::string(view.objectName(o));
      it->second = changes_.placement(key);
    }
    it->second[3] += glm::dvec4((explode_now_ - 1.0) * offset, 0.0);
  }
  std::vector<MovedMesh> meshes;
  for (const auto& [o, place] : places) {
    if (place == glm::dmat4(1.0)) continue;  // where it stands: the clusters draw it
    auto cached = geometry_.find(o);
    if (cached == geometry_.end()) cached = geometry_.emplace(o, objectMeshes(view, {o}).front()).first;
    MovedMesh mesh = cached->second;
    mesh.move = packageMove(view, place);
    meshes.push_back(std::move(mesh));
  }
  walk_.setMovedObjects(std::move(meshes));
  // Hidden by edits: what the change set hides now, and no more than that.
  ObjectStates& states = walk_.objectStates();
  for (uint32_t o : hidden_by_edits_) states.set(o, kObjectHidden, false);
  hidden_by_edits_.clear();
  for (const Change& c : changes_.changes())
    if (c.kind == Change::Kind::Hide)
      for (uint32_t o : objectsOfChangeKey(view, c.key)) {
        states.set(o, kObjectHidden, c.hidden);
        if (c.hidden) hidden_by_edits_.push_back(o);
      }
}

std::optional<ViewEdits::Gizmo> ViewEdits::gizmo(const Camera& camera, int height) const {
  (void)height;
  Gizmo g;
  double size = 0.0;
  if (!selectionCentre(g.centre, size)) return std::nullopt;
  const double distance = std::max(glm::length(g.centre - camera.position), camera.near_m * 4.0);
  g.length_m = 2.0 * distance * std::tan(0.5 * camera.fov_y_rad) * kGizmoScreenShare;
  return g;
}

ViewEdits::Handle ViewEdits::hit(const Gizmo& g, const Camera& camera, int width, int height,
                                 double x, double y) const {
  const glm::dvec2 mouse(x, y);
  const auto c = screen(camera, width, height, g.centre);
  if (!c) return {};
  for (int a = 0; a < 3; ++a) {
    const auto tip = screen(camera, width, height, g.centre + kAxes[a] * g.length_m);
    if (tip && glm::length(mouse - *c) > 0.35 * glm::length(*tip - *c) &&
        distanceToSegment(mouse, *c, *tip) < 7.0)
      return {Handle::Kind::Arrow, a};
  }
  for (int a = 0; a < 3; ++a) {
    const auto square = planeSquare(g.centre, a, g.length_m);
    std::array<glm::dvec2, 4> s;
    bool seen = true;
    for (int k = 0; k < 4; ++k) {
      const auto p = screen(camera, width, height, square[k]);
      if (!p) seen = false;
      else s[k] = *p;
    }
    if (!seen) continue;
    // Inside the quad: the same side of its four edges.
    int sign = 0;
    bool inside = true;
    for (int k = 0; k < 4 && inside; ++k) {
      const glm::dvec2 e = s[(k + 1) % 4] - s[k], m = mouse - s[k];
      const int side = e.x * m.y - e.y * m.x > 0 ? 1 : -1;
      if (sign == 0) sign = side;
      inside = side == sign;
    }
    if (inside) return {Handle::Kind::Plane, a};
  }
  for (int a = 0; a < 3; ++a) {
    const std::vector<glm::dvec3> ring = ringPoints(g.centre, a, 0.75 * g.length_m);
    for (size_t k = 0; k + 1 < ring.size(); ++k) {
      const auto p = screen(camera, width, height, ring[k]), q = screen(camera, width, height, ring[k + 1]);
      if (p && q && distanceToSegment(mouse, *p, *q) < 6.0) return {Handle::Kind::Ring, a};
    }
  }
  return {};
}

void ViewEdits::toggleGizmo() {
  show_gizmo_ = !show_gizmo_;
  if (!show_gizmo_) release();
  viewSay("edits: gizmo %s\n", show_gizmo_ ? "on" : "off");
}

bool ViewEdits::press(const Camera& camera, int width, int height, double x, double y) {
  if (!show_gizmo_) return false;
  const auto g = gizmo(camera, height);
  if (!g) return false;
  const Handle h = hit(*g, camera, width, height, x, y);
  if (h.kind == Handle::Kind::None) return false;
  drag_ = Drag{h, *g, camera, width, height, x, y, changes_.undoable()};
  return true;
}

void ViewEdits::dragTo(double x, double y) {
  if (!drag_) return;
  const Drag d = *drag_;
  // The drag so far replaces what it did at its previous step.
  while (changes_.undoable() > d.changes_before) changes_.undo();
  const auto c = screen(d.camera, d.width, d.height, d.gizmo.centre);
  if (!c) return;
  const glm::dvec2 delta(x - d.x0, y - d.y0);
  auto axisOnScreen = [&](int a) {
    const auto tip = screen(d.camera, d.width, d.height, d.gizmo.centre + kAxes[a] * d.gizmo.length_m);
    return tip ? *tip - *c : glm::dvec2(0.0);
  };
  if (d.handle.kind == Handle::Kind::Arrow) {
    const glm::dvec2 s = axisOnScreen(d.handle.axis);
    const double len = glm::length(s);
    if (len > 1e-6) moveSelection(kAxes[d.handle.axis] * (glm::dot(delta, s) / (len * len)) * d.gizmo.length_m);
  } else if (d.handle.kind == Handle::Kind::Plane) {
    const int i = (d.handle.axis + 1) % 3, j = (d.handle.axis + 2) % 3;
    const glm::dvec2 si = axisOnScreen(i), sj = axisOnScreen(j);
    const double det = si.x * sj.y - si.y * sj.x;
    if (std::abs(det) > 1e-6) {
      const double u = (delta.x * sj.y - delta.y * sj.x) / det, v = (si.x * delta.y - si.y * delta.x) / det;
      moveSelection((u * kAxes[i] + v * kAxes[j]) * d.gizmo.length_m);
    }
  } else if (d.handle.kind == Handle::Kind::Ring) {
    // Counter-clockwise on the screen (y down) is a positive turn about an axis toward the eye.
    const double a0 = std::atan2(-(d.y0 - c->y), d.x0 - c->x), a1 = std::atan2(-(y - c->y), x - c->x);
    double turn = std::remainder(a1 - a0, 2.0 * std::numbers::pi) * 180.0 / std::numbers::pi;
    if (glm::dot(kAxes[d.handle.axis], d.camera.forward()) > 0.0) turn = -turn;
    rotateSelection(kAxes[d.handle.axis], turn);
  }
  refresh();
}

void ViewEdits::release() {
  if (!drag_) return;
  const size_t made = changes_.undoable() - std::min(changes_.undoable(), drag_->changes_before);
  drag_.reset();
  if (made == 0) return;
  const Change& last = changes_.changes().back();
  const glm::dvec3 t = last.new_pivot - last.old_pivot;
  viewSay("edits: gizmo drag: %zu changes, the last moving %s by (%.3f, %.3f, %.3f) m\n", made,
              last.key.c_str(), t.x, t.y, t.z);
}

void ViewEdits::drawGizmo(const Camera& camera, int width, int height) const {
  if (!show_gizmo_) return;
  const auto g = gizmo(camera, height);
  if (!g) return;
  ImDrawList* draw = ImGui::GetForegroundDrawList();
  const auto c = screen(camera, width, height, g->centre);
  if (!c) return;
  auto im = [](const glm::dvec2& p) { return ImVec2(float(p.x), float(p.y)); };
  for (int a = 0; a < 3; ++a) {  // rings
    const std::vector<glm::dvec3> ring = ringPoints(g->centre, a, 0.75 * g->length_m);
    for (size_t k = 0; k + 1 < ring.size(); ++k) {
      const auto p = screen(camera, width, height, ring[k]), q = screen(camera, width, height, ring[k + 1]);
      if (p && q) draw->AddLine(im(*p), im(*q), kAxisColours[a], 2.0f);
    }
  }
  for (int a = 0; a < 3; ++a) {  // plane squares
    const auto square = planeSquare(g->centre, a, g->length_m);
    ImVec2 s[4];
    bool seen = true;
    for (int k = 0; k < 4; ++k) {
      const auto p = screen(camera, width, height, square[k]);
      if (!p) seen = false;
      else s[k] = im(*p);
    }
    if (seen) draw->AddQuadFilled(s[0], s[1], s[2], s[3], (kAxisColours[a] & 0x00ffffffu) | 0x90000000u);
  }
  for (int a = 0; a < 3; ++a) {  // arrows
    const auto tip = screen(camera, width, height, g->centre + kAxes[a] * g->length_m);
    if (!tip) continue;
    draw->AddLine(im(*c), im(*tip), kAxisColours[a], 3.0f);
    const glm::dvec2 dir = *tip - *c;
    const double len = glm::length(dir);
    if (len < 1.0) continue;
    const glm::dvec2 u = dir / len, n(-u.y, u.x);
    draw->AddTriangleFilled(im(*tip + u * 12.0), im(*tip + n * 6.0), im(*tip - n * 6.0), kAxisColours[a]);
  }
  draw->AddCircleFilled(im(*c), 4.0f, IM_COL32(240, 240, 240, 255));
}

void ViewEdits::drawPanel(double now_s) {
  // A section of the review window (ImGui appends to a window begun again by name).
  ImGui::Begin("Review");
  if (!ImGui::CollapsingHeader("Edit", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::End();
    return;
  }
  ImGui::Text("%zu changes, %zu to redo%s", changes_.undoable(), changes_.redoable(),
              load_error_.empty() ? "" : "  (the change set file could not be read)");
  if (bool shown = show_gizmo_; ImGui::Checkbox("gizmo [G]", &shown)) toggleGizmo();
  ImGui::SameLine();
  if (ImGui::Button("Undo")) undo();
  ImGui::SameLine();
  if (ImGui::Button("Redo")) redo();
  ImGui::SameLine();
  if (ImGui::Button("Save")) save();
  ImGui::Text("gizmo: arrows, squares move (%.0f mm); rings turn (%.0f deg)", kMoveStepM * 1000.0,
              kRotateStepDeg);
  static float factor = 2.0f;
  ImGui::SliderFloat("explode", &factor, 1.0f, 4.0f, "%.1f");
  if (ImGui::Button("Explode selection")) explode(factor, now_s);
  ImGui::SameLine();
  if (ImGui::Button("Collapse")) collapse(now_s);
  if (ImGui::Button("Hide selection")) hideSelection();
  static char comment[256] = {};
  ImGui::InputText("##comment", comment, sizeof comment);
  ImGui::SameLine();
  if (ImGui::Button("Comment")) {
    commentSelection(comment);
    comment[0] = '\0';
  }
  ImGui::End();
}

}  // namespace tw
