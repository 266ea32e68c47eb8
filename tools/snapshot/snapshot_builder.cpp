// Streaming scene -> EmbreeScene conversion for snapshots: tessellate, place, colour, batch.
#include "snapshot_builder.h"

#include <cmath>
#include <exception>
#include <stdexcept>
#include <utility>

namespace tw {

namespace {

bool finite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

constexpr uint32_t kDefaultGrey = 0xffb0b0b0u;  // as Layer's default
constexpr size_t kMaxCountedColors = 64;

// Average of three RGBA8 colours, per channel.
uint32_t averageColor(uint32_t a, uint32_t b, uint32_t c) {
  uint32_t out = 0;
  for (int shift = 0; shift < 32; shift += 8) {
    uint32_t sum = ((a >> shift) & 0xffu) + ((b >> shift) & 0xffu) + ((c >> shift) & 0xffu);
    out |= ((sum + 1) / 3) << shift;
  }
  return out;
}

}  // namespace

SnapshotBuilder::SnapshotBuilder(const SnapshotBuildOptions& options) : options_(options) {
  if (options_.batch_triangles == 0) options_.batch_triangles = 1;
}

SnapshotBuilder::~SnapshotBuilder() = default;

void SnapshotBuilder::onLayer(uint32_t index, const Layer& layer) {
  // Indices come from files; grow only as far as a sane layer count allows.
  if (index >= (1u << 20)) return;
  if (layer_colors_.size() <= index) layer_colors_.resize(index + 1, kDefaultGrey);
  layer_colors_[index] = layer.color_rgba;
}

uint32_t SnapshotBuilder::layerColor(uint32_t layer) const {
  return layer < layer_colors_.size() ? layer_colors_[layer] : kDefaultGrey;
}

void SnapshotBuilder::ensureScene(const SceneObject& first) {
  if (out_.rt) return;
  glm::dvec3 origin(0.0);
  if (options_.origin) {
    origin = *options_.origin;
  } else {
    Aabb b = worldBounds(first);
    if (!b.empty() && finite(b.center())) origin = b.center();
  }
  out_.rt = std::make_unique<EmbreeScene>(origin);
}

uint32_t SnapshotBuilder::slotFor(uint32_t object_id, uint32_t color_rgba) {
  auto [it, inserted] = object_slots_.try_emplace(color_rgba, 0u);
  if (inserted) {
    it->second = static_cast<uint32_t>(out_.slots.size());
    out_.slots.push_back({object_id, color_rgba});
    if (seen_colors_.size() < kMaxCountedColors) seen_colors_.insert(color_rgba);
  }
  return it->second;
}

void SnapshotBuilder::onObject(const SceneObject& object) {
  if (finished_) throw std::logic_error("SnapshotBuilder::onObject after finish");
  ++out_.parts;
  const ObjectInfo& info = object.info;
  if (seen_ids_.insert(info.id).second) ++out_.objects;
  if (!have_object_ || info.id != current_object_) {
    object_slots_.clear();
    current_object_ = info.id;
    have_object_ = true;
  }

  // Triangles in the object's local frame: meshes as they are, everything else tessellated.
  const TriangleMesh* mesh = std::get_if<TriangleMesh>(&object.geometry);
  if (!mesh) {
    scratch_.positions.clear();
    scratch_.normals.clear();
    scratch_.colors.clear();
    scratch_.indices.clear();
    try {
      tessellate(object.geometry, options_.tolerance, scratch_);
    } catch (const std::exception&) {
      // A primitive with parameters the tessellator refuses: leave it out of the picture
      // rather than losing the whole snapshot; the count is reported.
      ++out_.skipped_parts;
      return;
    }
    mesh = &scratch_;
  }
  const size_t triangle_count = mesh->indices.size() / 3;
  if (triangle_count == 0 || mesh->positions.empty()) return;
  ensureScene(object);

  if (!batch_slots_.empty() && batch_slots_.size() + triangle_count > options_.batch_triangles) flushBatch();

  // World placement in double precision, stored relative to the scene origin.
  const glm::dvec3 origin = out_.rt->origin();
  if (batch_positions_.size() + mesh->positions.size() > 0xffffffffull) flushBatch();
  const auto base = static_cast<uint32_t>(batch_positions_.size());
  batch_positions_.reserve(batch_positions_.size() + mesh->positions.size());
  for (const glm::vec3& p : mesh->positions) {
    glm::dvec3 world = info.transform.apply(p);
    out_.bounds.add(world);
    batch_positions_.push_back(glm::vec3(world - origin));
  }

  // Colour: the object's own, else its layer's; per-vertex colours (scans, glTF) win, averaged
  // over each triangle.
  const uint32_t base_color = info.color_rgba != 0 ? info.color_rgba : layerColor(info.layer);
  const bool vertex_colors = mesh->colors.size() == mesh->positions.size();
  const uint32_t uniform_slot = vertex_colors ? 0u : slotFor(info.id, base_color);
  const size_t vertex_count = mesh->positions.size();
  for (size_t t = 0; t < triangle_count; ++t) {
    uint32_t i0 = mesh->indices[3 * t], i1 = mesh->indices[3 * t + 1], i2 = mesh->indices[3 * t + 2];
    if (i0 >= vertex_count || i1 >= vertex_count || i2 >= vertex_count) continue;  // defensive
    batch_indices_.push_back(base + i0);
    batch_indices_.push_back(base + i1);
    batch_indices_.push_back(base + i2);
    batch_slots_.push_back(vertex_colors
                               ? slotFor(info.id, averageColor(mesh->colors[i0], mesh->colors[i1], mesh->colors[i2]))
                               : uniform_slot);
  }
}

void SnapshotBuilder::flushBatch() {
  if (batch_slots_.empty()) return;
  auto user_id = static_cast<uint32_t>(out_.triangle_slots.size());
  out_.triangles += batch_slots_.size();
  out_.rt->addMesh(std::move(batch_positions_), std::move(batch_indices_), user_id);
  out_.triangle_slots.push_back(std::move(batch_slots_));
  batch_positions_ = {};
  batch_indices_ = {};
  batch_slots_ = {};
}

SnapshotScene SnapshotBuilder::finish() {
  if (finished_) throw std::logic_error("SnapshotBuilder::finish called twice");
  finished_ = true;
  if (!out_.rt) out_.rt = std::make_unique<EmbreeScene>(options_.origin.value_or(glm::dvec3(0.0)));
  flushBatch();
  out_.rt->commit();
  out_.distinct_colors = static_cast<uint32_t>(seen_colors_.size());
  return std::move(out_);
}

}  // namespace tw
