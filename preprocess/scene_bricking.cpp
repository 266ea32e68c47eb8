// Out-of-core bricking: survey pass, binning pass with bounded write buffers, streaming splits of
// over-full bricks, and the readers of what it spilled (the files themselves: spill_file.h).
#include "scene_bricking.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <stdexcept>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "byte_packing.h"
#include "closed_surface.h"
#include "consistent_winding.h"
#include "repeated_triangles.h"
#include "format_error.h"
#include "nurbs_conforming.h"
#include "position_key.h"
#include "scene_io.h"
#include "scene_stats.h"
#include "spill_file.h"

namespace tw {
namespace {

// An ObjectBounds record (spill_file.h): min and max (vec3 each) and the surface kind (uint32):
// what the object's mesh pieces make (closed_surface.h); none for objects without mesh geometry.
constexpr uint64_t kObjectBoundsRecordBytes = 28;
constexpr uint32_t kNoSurface = 0, kClosedSurface = 1, kOpenSurface = 2;

// One triangle in a brick file: positions relative to the package origin, dense object index.
struct TriangleRecord {
  float v[9];
  uint32_t object;
};
static_assert(sizeof(TriangleRecord) == 40);

void putPrimitive(ByteWriter& w, const Primitive& primitive) {
  w.put(static_cast<uint8_t>(primitive.index()));
  std::visit(
      [&](const auto& p) {
        using T = std::decay_t<decltype(p)>;
        if constexpr (std::is_same_v<T, Cylinder>) {
          w.put(p.radius), w.put(p.height), w.put(static_cast<uint8_t>(p.capped));
        } else if constexpr (std::is_same_v<T, Cone>) {
          w.put(p.radius_bottom), w.put(p.radius_top), w.put(p.height);
          w.put(static_cast<uint8_t>(p.capped));
        } else if constexpr (std::is_same_v<T, Sphere>) {
          w.put(p.radius);
        } else if constexpr (std::is_same_v<T, TorusSegment>) {
          w.put(p.major_radius), w.put(p.minor_radius), w.put(p.sweep_rad);
        } else if constexpr (std::is_same_v<T, Box>) {
          w.put(p.half_extents);
        } else if constexpr (std::is_same_v<T, Extrusion>) {
          w.putVec2s(p.profile), w.put(p.height);
        } else {
          w.putVec2s(p.profile), w.put(p.sweep_rad);
        }
      },
      primitive);
}

Primitive getPrimitive(ByteReader& r) {
  switch (r.get<uint8_t>()) {
    case 0: {
      Cylinder c;
      c.radius = r.get<float>();
      c.height = r.get<float>();
      c.capped = r.get<uint8_t>() != 0;
      return c;
    }
    case 1: {
      Cone c;
      c.radius_bottom = r.get<float>();
      c.radius_top = r.get<float>();
      c.height = r.get<float>();
      c.capped = r.get<uint8_t>() != 0;
      return c;
    }
    case 2: {
      Sphere s;
      s.radius = r.get<float>();
      return s;
    }
    case 3: {
      TorusSegment t;
      t.major_radius = r.get<float>();
      t.minor_radius = r.get<float>();
      t.sweep_rad = r.get<float>();
      return t;
    }
    case 4: {
      Box b;
      b.half_extents = r.get<glm::vec3>();
      return b;
    }
    case 5: {
      Extrusion e;
      e.profile = r.getVec2s();
      e.height = r.get<float>();
      return e;
    }
    case 6: {
      Revolution v;
      v.profile = r.getVec2s();
      v.sweep_rad = r.get<float>();
      return v;
    }
    default:
      r.fail("unknown primitive type");
  }
}

// --- Pass 1 ---

// Bounds of what becomes triangles (meshes and NURBS hulls), next to SceneStats' totals.
class TriangleBoundsSink : public SceneSink {
 public:
  void onLayer(uint32_t, const Layer&) override {}
  void onObject(const SceneObject& object) override {
    if (kindOf(object.geometry) != GeometryKind::Parametric) bounds.add(worldBounds(object));
  }
  Aabb bounds;
};

// Reports one input's bytes as part of a multi-input total, and forwards cancellation.
class OffsetProgress : public Progress {
 public:
  OffsetProgress(Progress* inner, uint64_t base) : inner_(inner), base_(base) {}
  void beginStage(std::string_view, uint64_t) override {}
  void update(uint64_t done) override { updateProgress(inner_, base_ + done); }
  void endStage() override {}
  bool cancelled() const override { return inner_ && inner_->cancelled(); }

 private:
  Progress* inner_;
  uint64_t base_;
};

void checkCancelled(Progress* progress) {
  if (progress && progress->cancelled()) throw std::runtime_error("cancelled");
}

uint64_t fileBytes(const std::filesystem::path& path) {
  std::error_code ec;
  uint64_t n = std::filesystem::file_size(path, ec);
  return ec ? 0 : n;
}

// --- Pass 2 ---

struct BrickState {
  std::unique_ptr<SpillWriter> writer;  // created on the first triangle
  uint64_t count = 0;
  glm::vec3 min{INFINITY}, max{-INFINITY};    // triangle bounds
  glm::vec3 cmin{INFINITY}, cmax{-INFINITY};  // centroid bounds
  void add(const TriangleRecord& t, const glm::vec3& centroid) {
    ++count;
    for (int i = 0; i < 3; ++i) {
      glm::vec3 p{t.v[3 * i], t.v[3 * i + 1], t.v[3 * i + 2]};
      min = glm::min(min, p);
      max = glm::max(max, p);
    }
    cmin = glm::min(cmin, centroid);
    cmax = glm::max(cmax, centroid);
  }
};

glm::vec3 centroidOf(const TriangleRecord& t) {
  return glm::vec3((glm::dvec3(t.v[0], t.v[1], t.v[2]) + glm::dvec3(t.v[3], t.v[4], t.v[5]) +
                    glm::dvec3(t.v[6], t.v[7], t.v[8])) /
                   3.0);
}

class BrickingSink : public SceneSink {
 public:
  BrickingSink(BrickedScene& scene, const BrickingOptions& options, const glm::dvec3& grid_min,
               const glm::dvec3& cell_size)
      : scene_(scene),
        options_(options),
        grid_min_(grid_min),
        cell_size_(cell_size),
        cells_(scene.grid.x * scene.grid.y * scene.grid.z) {
    BrickingStats& stats = scene_.stats;
    stats.buffer_cap_bytes = std::max<uint64_t>(options.memory_budget_bytes / 8, 64 * 1024);
    const uint64_t per_cell = stats.buffer_cap_bytes / cells_.size();
    per_cell_bytes_ = std::clamp<uint64_t>(per_cell, 1024, 64 * 1024);
    objects_ =
        std::make_unique<SpillWriter>(scene.work_dir / scene.objects_file, SpillKind::Objects);
    parametrics_ = std::make_unique<SpillWriter>(scene.work_dir / scene.parametrics_file,
                                                 SpillKind::Parametrics);
  }

  void reserveObjects(uint64_t objects) {
    object_bounds_.reserve(static_cast<size_t>(std::min<uint64_t>(objects, 1ull << 28)));
  }

  void beginInput(uint32_t input, const std::string& name) {
    input_ = input;
    input_name_ = name;
    layer_map_.clear();
    id_map_.clear();
    has_last_ = false;
  }

  void onLayer(uint32_t index, const Layer& layer) override {
    auto [it, inserted] = layer_index_.try_emplace(layer.name, uint32_t(scene_.layers.size()));
    if (inserted) scene_.layers.push_back(layer);
    if (layer_map_.size() <= index) layer_map_.resize(index + 1, UINT32_MAX);
    layer_map_[index] = it->second;
  }

  void onObject(const SceneObject& object) override {
    checkCancelled(options_.progress);
    const uint32_t dense = objectIndex(object.info);
    const Transform& t = object.info.transform;
    if (const auto* mesh = std::get_if<TriangleMesh>(&object.geometry)) {
      PendingMesh piece;
      piece.mesh = *mesh;
      queueMesh(std::move(piece), t, dense);
    } else if (const auto* nurbs = std::get_if<NurbsPatchSet>(&object.geometry)) {
      PendingMesh piece;
      piece.nurbs = *nurbs;
      queueMesh(std::move(piece), t, dense);
    } else {
      ByteWriter w;
      w.put(dense);
      w.put(t.origin);
      w.put(t.linear);
      putPrimitive(w, std::get<Primitive>(object.geometry));
      const auto n = static_cast<uint32_t>(w.bytes.size());
      parametrics_->append(&n, sizeof n);
      parametrics_->append(w.bytes.data(), w.bytes.size());
      parametrics_->countRecord();
      if (parametrics_->buffered() >= kSideBufferBytes) parametrics_->flush(false);
      ++scene_.parametric_count;
      Aabb box = worldBounds(object);
      if (!box.empty()) {
        growObject(dense, glm::vec3(box.min - scene_.origin));
        growObject(dense, glm::vec3(box.max - scene_.origin));
      }
    }
  }

  // The end of one input: its queued meshes are binned (their errors name this input).
  void endInput() { binPending(); }

  // Completes every spill file of the binning pass.
  void finish() {
    binPending();
    flushAll();
    objects_->finish();
    parametrics_->finish();
    SpillWriter bounds(scene_.work_dir / scene_.object_bounds_file, SpillKind::ObjectBounds);
    for (const auto& b : object_bounds_) {
      bounds.append(&b, sizeof b);
      bounds.countRecord();
      if (bounds.buffered() >= kSideBufferBytes) bounds.flush(false);
    }
    bounds.finish();
    for (auto& cell : cells_)
      if (cell.writer) {
        cell.writer->finish();
        scene_.stats.spill_bytes_written += cell.writer->bytesWritten();
      }
    scene_.stats.spill_bytes_written +=
        objects_->bytesWritten() + parametrics_->bytesWritten() + bounds.bytesWritten();
    scene_.object_count = object_bounds_.size();
  }

  std::vector<BrickState>& cells() { return cells_; }

 private:
  static constexpr size_t kSideBufferBytes = 1 << 20;

  uint32_t objectIndex(const ObjectInfo& info) {
    if (has_last_ && info.id == last_id_) return last_dense_;
    auto [it, inserted] = id_map_.try_emplace(info.id, uint32_t(object_bounds_.size()));
    if (inserted) {
      if (info.layer >= layer_map_.size() || layer_map_[info.layer] == UINT32_MAX)
        throw FormatError(input_name_, "object " + std::to_string(info.id) +
                                           " is on undeclared layer " + std::to_string(info.layer));
      ByteWriter w;
      w.put(input_);
      w.put(info.id);
      w.put(layer_map_[info.layer]);
      w.put(info.color_rgba);
      w.putString(info.name);
      w.putString(info.db_key);
      objects_->append(w.bytes.data(), w.bytes.size());
      objects_->countRecord();
      if (objects_->buffered() >= kSideBufferBytes) objects_->flush(false);
      object_bounds_.push_back({glm::vec3(INFINITY), glm::vec3(-INFINITY), kNoSurface});
      // Estimate: an unordered_map entry costs about a node (32 bytes) plus a bucket (8).
      scene_.stats.object_table_bytes =
          std::max<uint64_t>(scene_.stats.object_table_bytes,
                             object_bounds_.capacity() * sizeof(ObjectBox) + id_map_.size() * 40);
    }
    has_last_ = true;
    last_id_ = info.id;
    last_dense_ = it->second;
    return last_dense_;
  }

  void growObject(uint32_t dense, const glm::vec3& p) {
    object_bounds_[dense].min = glm::min(object_bounds_[dense].min, p);
    object_bounds_[dense].max = glm::max(object_bounds_[dense].max, p);
  }

  // A mesh piece waiting to be binned. What a piece needs before binning depends on it alone,
  // so queued pieces are prepared on TBB and binned in reading order (the spill files are the
  // same whatever the thread count).
  struct PendingMesh {
    TriangleMesh mesh;
    NurbsPatchSet nurbs;  // tessellated into mesh when it has patches
    Transform t;
    uint32_t dense = 0;
    uint64_t repeated = 0, turned = 0;
    bool solid = false;
    double stored_extent = 0.0;        // largest coordinate as the reader stored it (scaled)
    std::vector<glm::dvec3> relative;  // positions relative to the scene origin, on the step
  };
  static constexpr uint64_t kPendingTriangles = 1 << 18;

  void queueMesh(PendingMesh piece, const Transform& t, uint32_t dense) {
    piece.t = t;
    piece.dense = dense;
    pending_triangles_ += piece.mesh.indices.size() / 3 + 1;
    for (const NurbsPatch& patch : piece.nurbs.patches)
      pending_triangles_ += uint64_t(patch.control_points.size()) * 8;
    pending_.push_back(std::move(piece));
    if (pending_triangles_ >= kPendingTriangles) binPending();
  }

  void binPending() {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, pending_.size(), 1),
                      [&](const tbb::blocked_range<size_t>& range) {
                        for (size_t i = range.begin(); i != range.end(); ++i)
                          prepare(pending_[i]);
                      });
    for (PendingMesh& piece : pending_) addMesh(piece);
    pending_.clear();
    pending_triangles_ = 0;
  }

  // Exact repeats of a triangle go first (repeated_triangles.h); then triangles wound against
  // their neighbours are turned, so that edge collapse can coarsen the piece and a closed piece
  // can count as a solid (consistent_winding.h).
  void prepare(PendingMesh& piece) const {
    if (!piece.nurbs.patches.empty()) {
      tessellateNurbsConforming(piece.nurbs, options_.nurbs_tolerance, piece.mesh);
      piece.nurbs = {};
    }
    const std::vector<uint32_t> repeats = repeatedTriangles(piece.mesh);
    if (!repeats.empty()) piece.mesh = withoutTriangles(piece.mesh, repeats);
    piece.repeated = repeats.size();
    const std::vector<uint32_t> turn = trianglesToTurn(piece.mesh);
    turnTriangles(piece.mesh, turn);
    piece.turned = turn.size();
    // An object is a closed solid when each of its mesh pieces is one (closed_surface.h). The
    // transform must keep the orientation: a mirror turns the surface inside out.
    piece.solid = glm::determinant(glm::dmat3(piece.t.linear)) > 0.0 &&
                  checkClosedSurface(piece.mesh).enclosesSolid();
    piece.relative.resize(piece.mesh.positions.size());
    const double step = options_.position_step_m;
    for (size_t i = 0; i < piece.mesh.positions.size(); ++i) {
      glm::dvec3& r = piece.relative[i];
      const glm::dvec3 placed = piece.t.apply(piece.mesh.positions[i]);
      const glm::dvec3 stored = glm::abs(placed - piece.t.origin);
      if (std::isfinite(stored.x + stored.y + stored.z))
        piece.stored_extent = std::max({piece.stored_extent, stored.x, stored.y, stored.z});
      r = placed - scene_.origin;
      if (step > 0.0 && std::isfinite(r.x + r.y + r.z)) r = glm::round(r / step) * step;
    }
  }

  void addMesh(const PendingMesh& piece) {
    scene_.triangles_repeated += piece.repeated;
    scene_.triangles_turned += piece.turned;
    scene_.stored_coordinate_extent = std::max(scene_.stored_coordinate_extent, piece.stored_extent);
    uint32_t& surface = object_bounds_[piece.dense].surface;
    if (surface != kOpenSurface) surface = piece.solid ? kClosedSurface : kOpenSurface;
    const TriangleMesh& mesh = piece.mesh;
    const std::vector<glm::dvec3>& relative_ = piece.relative;
    const uint32_t dense = piece.dense;
    const size_t n = mesh.indices.size() / 3 * 3;
    for (size_t i = 0; i < n; i += 3) {
      TriangleRecord record;
      glm::dvec3 centroid(0.0);
      for (int k = 0; k < 3; ++k) {
        uint32_t index = mesh.indices[i + k];
        if (index >= relative_.size())
          throw FormatError(input_name_, "mesh index " + std::to_string(index) + " out of range");
        const glm::dvec3& p = relative_[index];
        centroid += p;
        glm::vec3 f(p);
        record.v[3 * k] = f.x, record.v[3 * k + 1] = f.y, record.v[3 * k + 2] = f.z;
        growObject(dense, f);
      }
      record.object = dense;
      append(cellOf(centroid / 3.0), record);
    }
  }

  uint32_t cellOf(const glm::dvec3& c) const {
    const glm::uvec3& n = scene_.grid;
    uint32_t idx[3];
    for (int a = 0; a < 3; ++a) {
      double f = cell_size_[a] > 0 ? std::floor((c[a] - grid_min_[a]) / cell_size_[a]) : 0.0;
      idx[a] = f <= 0 ? 0u : f >= double(n[a] - 1) ? n[a] - 1 : uint32_t(f);
    }
    return (idx[2] * n.y + idx[1]) * n.x + idx[0];
  }

  void append(uint32_t cell_index, const TriangleRecord& record) {
    BrickState& cell = cells_[cell_index];
    // The global cap holds the sum of all buffers: flush everything before going over it.
    if (buffered_ + sizeof record > scene_.stats.buffer_cap_bytes) flushAll();
    if (!cell.writer)
      cell.writer = std::make_unique<SpillWriter>(
          scene_.work_dir / ("cell-" + std::to_string(cell_index) + ".bin"), SpillKind::Brick);
    // One allocation of the cell's share: cells * share <= cap (or 1 KiB each for huge grids).
    if (cell.writer->buffered() == 0) cell.writer->reserve(per_cell_bytes_);
    cell.writer->append(&record, sizeof record);
    cell.writer->countRecord();
    cell.add(record, centroidOf(record));
    buffered_ += sizeof record;
    scene_.stats.peak_buffered_bytes = std::max(scene_.stats.peak_buffered_bytes, buffered_);
    if (cell.writer->buffered() + sizeof record > per_cell_bytes_) {
      buffered_ -= cell.writer->buffered();
      cell.writer->flush(false);
      ++scene_.stats.flushes;
    }
  }

  void flushAll() {
    for (auto& cell : cells_)
      if (cell.writer && cell.writer->buffered()) {
        cell.writer->flush(true);
        ++scene_.stats.flushes;
      }
    buffered_ = 0;
  }

  // Per object: its bounds and what its mesh pieces make (the ObjectBounds spill record).
  struct ObjectBox {
    glm::vec3 min, max;
    uint32_t surface;
  };
  static_assert(sizeof(ObjectBox) == kObjectBoundsRecordBytes);

  BrickedScene& scene_;
  const BrickingOptions& options_;
  glm::dvec3 grid_min_, cell_size_;
  std::vector<BrickState> cells_;
  uint64_t per_cell_bytes_ = 0;
  uint64_t buffered_ = 0;
  std::unique_ptr<SpillWriter> objects_, parametrics_;
  std::vector<ObjectBox> object_bounds_;
  std::map<std::string, uint32_t> layer_index_;
  // Per input: local layer -> merged layer, and object id -> dense index.
  uint32_t input_ = 0;
  std::string input_name_;
  std::vector<uint32_t> layer_map_;
  std::unordered_map<uint32_t, uint32_t> id_map_;
  bool has_last_ = false;
  uint32_t last_id_ = 0, last_dense_ = 0;
  std::vector<PendingMesh> pending_;
  uint64_t pending_triangles_ = 0;
};

// Splits an over-full brick file into two by streaming it: halves its centroid bounds along the
// longest axis, or (all centroids equal) halves it by position in the file. Recurses until each
// part holds at most `limit`; appends the final bricks in left-to-right order.
void splitBrick(BrickState& state, const std::filesystem::path& dir, uint64_t limit,
                uint32_t& next_split, std::vector<BrickState>& out, BrickingStats& stats,
                Progress* progress) {
  if (state.count <= limit) {
    out.push_back(std::move(state));
    return;
  }
  checkCancelled(progress);
  ++stats.split_passes;
  glm::vec3 extent = state.cmax - state.cmin;
  int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
  const float mid = state.cmin[axis] + extent[axis] * 0.5f;
  const bool by_position = !(extent[axis] > 0.0f) || !std::isfinite(mid);
  const uint64_t half = state.count / 2;

  BrickState parts[2];
  for (auto& part : parts)
    part.writer = std::make_unique<SpillWriter>(
        dir / ("split-" + std::to_string(next_split++) + ".bin"), SpillKind::Brick);
  const std::filesystem::path source = state.writer->path();
  {
    SpillReader reader(source, SpillKind::Brick);
    if (reader.records() != state.count) reader.fail("record count differs from the binning pass");
    for (uint64_t i = 0; i < state.count; ++i) {
      auto record = reader.readValue<TriangleRecord>();
      glm::vec3 c = centroidOf(record);
      // The midpoint can round onto cmax; fall back to position order so both sides fill.
      int side = by_position ? (i >= half)
                             : (c[axis] > mid || (mid >= state.cmax[axis] && c[axis] >= mid));
      BrickState& part = parts[side];
      part.writer->append(&record, sizeof record);
      part.writer->countRecord();
      part.add(record, c);
      if (part.writer->buffered() >= (1u << 20)) part.writer->flush(false);
    }
    reader.finish();
  }
  if (parts[0].count == 0 || parts[1].count == 0)  // the rules above always fill both sides
    throw std::logic_error(source.string() + ": brick split left one side empty");
  for (auto& part : parts) {
    part.writer->finish();
    stats.spill_bytes_written += part.writer->bytesWritten();
  }
  std::filesystem::remove(source);
  for (auto& part : parts) splitBrick(part, dir, limit, next_split, out, stats, progress);
}

}  // namespace

uint64_t effectiveMaxBrickTriangles(const BrickingOptions& options) {
  if (options.max_brick_triangles) return options.max_brick_triangles;
  return std::clamp<uint64_t>(options.memory_budget_bytes / 400, kMinBrickTriangles,
                              4 * 1024 * 1024);
}

SceneSurvey surveyScene(const std::vector<std::filesystem::path>& inputs, float nurbs_tolerance,
                        Progress* progress, const std::vector<std::string>& exclude_layers,
                        UpAxis up, const CadOptions& cad,
                        uint64_t vertex_memory_bytes, const std::filesystem::path& spill_dir) {
  SceneSurvey survey;
  for (const auto& input : inputs) survey.input_bytes += fileBytes(input);
  beginStage(progress, "survey", survey.input_bytes);
  uint64_t base = 0;
  for (const auto& input : inputs) {
    SceneStats stats(nurbs_tolerance);
    TriangleBoundsSink bounds;
    FanOutSink fan;
    fan.add(stats);
    fan.add(bounds);
    OffsetProgress sub(progress, base);
    ReadOptions read_options;
    read_options.progress = &sub;
    read_options.exclude_layers = exclude_layers;
    read_options.up = up;
    read_options.cad = cad;
    read_options.vertex_memory_bytes = vertex_memory_bytes;
    read_options.spill_dir = spill_dir;
    readScene(input, fan, read_options);
    checkCancelled(progress);
    survey.bounds.add(stats.bounds);
    survey.triangle_bounds.add(bounds.bounds);
    survey.mesh_triangles += stats.mesh_triangles;
    survey.nurbs_triangles += stats.nurbs_triangles;
    for (uint64_t n : stats.primitives_by_type) survey.primitives += n;
    survey.objects += stats.objects;
    base += fileBytes(input);
  }
  endStage(progress);
  return survey;
}

BrickedScene brickScene(const std::vector<std::filesystem::path>& inputs, const SceneSurvey& survey,
                        const BrickingOptions& options) {
  BrickedScene scene;
  scene.work_dir = options.work_dir;
  std::filesystem::create_directories(scene.work_dir);
  scene.max_brick_triangles = effectiveMaxBrickTriangles(options);
  scene.objects_file = "objects.bin";
  scene.object_bounds_file = "object-bounds.bin";
  scene.parametrics_file = "parametrics.bin";
  // Leftovers of an earlier run would be confused with this run's bricks.
  for (const auto& entry : std::filesystem::directory_iterator(scene.work_dir)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("cell-", 0) == 0 || name.rfind("split-", 0) == 0)
      std::filesystem::remove(entry.path());
  }

  // Origin: the centre of everything, rounded to a metre so that it reads well in tools.
  if (!survey.bounds.empty()) scene.origin = glm::round(survey.bounds.center());

  // Grid: add cells along the axis whose cells are longest until the uniform-density estimate
  // fits the limit (flat plants get a flat grid). Capped so that per-cell state stays small.
  constexpr uint32_t kMaxCells = 16384;
  glm::dvec3 grid_min(0.0), extent(0.0);
  if (!survey.triangle_bounds.empty()) {
    grid_min = survey.triangle_bounds.min - scene.origin;
    extent = survey.triangle_bounds.extent();
  }
  const uint64_t wanted = std::min<uint64_t>(
      kMaxCells, (survey.triangles() + scene.max_brick_triangles - 1) / scene.max_brick_triangles);
  glm::uvec3 n(1u);
  while (uint64_t{n.x} * n.y * n.z < wanted) {
    int axis = -1;
    double longest = 0.0;
    for (int a = 0; a < 3; ++a)
      if (extent[a] / n[a] > longest) longest = extent[a] / n[a], axis = a;
    if (axis < 0) break;  // a point: no axis to split
    ++n[axis];
  }
  scene.grid = n;
  scene.stats.grid_cells = n.x * n.y * n.z;
  const glm::dvec3 cell_size = extent / glm::dvec3(n);

  BrickingSink sink(scene, options, grid_min, cell_size);
  sink.reserveObjects(survey.objects);
  beginStage(options.progress, "bricking", survey.input_bytes);
  uint64_t base = 0;
  for (uint32_t i = 0; i < inputs.size(); ++i) {
    sink.beginInput(i, inputs[i].string());
    OffsetProgress sub(options.progress, base);
    ReadOptions read_options;
    read_options.progress = &sub;
    read_options.exclude_layers = options.exclude_layers;
    read_options.up = options.up;
    read_options.cad = options.cad;
    read_options.warn = [](const std::string&) {};  // the survey's reading reported them
    read_options.vertex_memory_bytes = readerVertexBytes(options.memory_budget_bytes);
    read_options.spill_dir = scene.work_dir;
    readScene(inputs[i], sink, read_options);
    sink.endInput();
    checkCancelled(options.progress);
    base += fileBytes(inputs[i]);
  }
  sink.finish();
  endStage(options.progress);

  // Split over-full cells; number the final bricks in cell order, split parts left to right.
  std::vector<BrickState> finals;
  uint32_t next_split = 0;
  uint64_t over = 0;
  for (auto& cell : sink.cells()) over += cell.count > scene.max_brick_triangles;
  beginStage(options.progress, "splitting dense bricks", over);
  uint64_t done = 0;
  for (auto& cell : sink.cells()) {
    if (!cell.writer) continue;
    if (cell.count > scene.max_brick_triangles) {
      ++scene.stats.cells_split;
      updateProgress(options.progress, ++done);
    }
    splitBrick(cell, scene.work_dir, scene.max_brick_triangles, next_split, finals, scene.stats,
               options.progress);
  }
  endStage(options.progress);
  for (auto& state : finals) {
    BrickInfo info;
    info.index = static_cast<uint32_t>(scene.bricks.size());
    info.bounds_min = state.min;
    info.bounds_max = state.max;
    info.triangle_count = state.count;
    info.file = state.writer->path().filename().string();
    scene.triangle_count += state.count;
    scene.bricks.push_back(std::move(info));
  }
  return scene;
}

BrickMesh loadBrick(const BrickedScene& scene, uint32_t brick) {
  const BrickInfo& info = scene.bricks.at(brick);
  SpillReader reader(scene.work_dir / info.file, SpillKind::Brick);
  if (reader.records() != info.triangle_count)
    reader.fail("brick holds " + std::to_string(reader.records()) + " triangles, expected " +
                std::to_string(info.triangle_count));
  if (reader.contentRemaining() != info.triangle_count * sizeof(TriangleRecord))
    reader.fail("brick content size does not match its triangle count");
  BrickMesh mesh;
  mesh.indices.reserve(info.triangle_count * 3);
  mesh.triangle_object_ids.reserve(info.triangle_count);
  std::unordered_map<PositionKey, uint32_t, PositionHash> weld;
  weld.reserve(info.triangle_count);
  std::vector<TriangleRecord> chunk(4096);
  for (uint64_t left = info.triangle_count; left > 0;) {
    size_t n = static_cast<size_t>(std::min<uint64_t>(left, chunk.size()));
    reader.read(chunk.data(), n * sizeof(TriangleRecord));
    left -= n;
    for (size_t t = 0; t < n; ++t) {
      for (int k = 0; k < 3; ++k) {
        glm::vec3 p(chunk[t].v[3 * k], chunk[t].v[3 * k + 1], chunk[t].v[3 * k + 2]);
        auto [it, inserted] = weld.try_emplace(positionKeyOf(p), uint32_t(mesh.positions.size()));
        if (inserted) mesh.positions.push_back(p);
        mesh.indices.push_back(it->second);
      }
      if (chunk[t].object >= scene.object_count)
        reader.fail("object index " + std::to_string(chunk[t].object) + " out of range");
      mesh.triangle_object_ids.push_back(chunk[t].object);
    }
  }
  reader.finish();
  return mesh;
}

bool verifyBrickedScene(const BrickedScene& scene, bool full) {
  try {
    auto check = [&](const std::string& file, SpillKind kind, uint64_t records,
                     uint64_t record_bytes) {
      SpillReader reader(scene.work_dir / file, kind);
      if (reader.records() != records) return false;
      if (record_bytes && reader.contentRemaining() != records * record_bytes) return false;
      if (full) {
        std::vector<uint8_t> buffer(1 << 20);
        while (reader.contentRemaining() > 0) {
          size_t n =
              static_cast<size_t>(std::min<uint64_t>(buffer.size(), reader.contentRemaining()));
          reader.read(buffer.data(), n);
        }
        reader.finish();
      }
      return true;
    };
    for (const auto& b : scene.bricks)
      if (!check(b.file, SpillKind::Brick, b.triangle_count, sizeof(TriangleRecord))) return false;
    return check(scene.objects_file, SpillKind::Objects, scene.object_count, 0) &&
           check(scene.object_bounds_file, SpillKind::ObjectBounds, scene.object_count,
                 kObjectBoundsRecordBytes) &&
           check(scene.parametrics_file, SpillKind::Parametrics, scene.parametric_count, 0);
  } catch (const FormatError&) {
    return false;
  }
}

void forEachObject(const BrickedScene& scene, const std::function<void(const BrickedObject&)>& fn) {
  SpillReader objects(scene.work_dir / scene.objects_file, SpillKind::Objects);
  SpillReader bounds(scene.work_dir / scene.object_bounds_file, SpillKind::ObjectBounds);
  if (objects.records() != scene.object_count || bounds.records() != scene.object_count)
    objects.fail("object count differs from the description");
  for (uint64_t i = 0; i < scene.object_count; ++i) {
    BrickedObject object;
    object.index = static_cast<uint32_t>(i);
    uint32_t fixed[4];
    objects.read(fixed, sizeof fixed);
    object.input = fixed[0], object.source_id = fixed[1], object.layer = fixed[2];
    object.color_rgba = fixed[3];
    if (object.layer >= scene.layers.size()) objects.fail("object layer out of range");
    for (std::string* s : {&object.name, &object.db_key}) {
      auto n = objects.readValue<uint32_t>();
      if (n > objects.contentRemaining()) objects.fail("string runs past the end of the content");
      s->resize(n);
      objects.read(s->data(), n);
    }
    object.bounds_min = bounds.readValue<glm::vec3>();
    object.bounds_max = bounds.readValue<glm::vec3>();
    const auto surface = bounds.readValue<uint32_t>();
    if (surface > kOpenSurface) bounds.fail("object surface kind out of range");
    object.closed_surface = surface == kClosedSurface;
    fn(object);
  }
  objects.finish();
  bounds.finish();
}

void forEachParametricBatch(const BrickedScene& scene, size_t batch_size,
                            const std::function<void(std::span<const ParametricRecord>)>& fn) {
  SpillReader reader(scene.work_dir / scene.parametrics_file, SpillKind::Parametrics);
  if (reader.records() != scene.parametric_count)
    reader.fail("parametric count differs from the description");
  std::vector<ParametricRecord> batch;
  batch.reserve(std::max<size_t>(batch_size, 1));
  std::vector<uint8_t> bytes;
  for (uint64_t i = 0; i < scene.parametric_count; ++i) {
    // Each record is length-prefixed: object, origin, linear, then the primitive's fields.
    auto n = reader.readValue<uint32_t>();
    if (n > reader.contentRemaining()) reader.fail("record runs past the end of the content");
    const uint64_t at = reader.offset();
    bytes.resize(n);
    reader.read(bytes.data(), n);
    ByteReader br(bytes, reader.name(), at);
    ParametricRecord record;
    record.object = br.get<uint32_t>();
    if (record.object >= scene.object_count) br.fail("object index out of range");
    record.transform.origin = br.get<glm::dvec3>();
    record.transform.linear = br.get<glm::mat3>();
    record.primitive = getPrimitive(br);
    if (br.remaining() != 0) br.fail("unexpected bytes after the primitive");
    batch.push_back(std::move(record));
    if (batch.size() >= batch_size) {
      fn(batch);
      batch.clear();
    }
  }
  if (!batch.empty()) fn(batch);
  reader.finish();
}

}  // namespace tw
