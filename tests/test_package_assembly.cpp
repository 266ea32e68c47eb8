// Tests for turning DAGs and parametric primitives into packages: a DAG written, re-opened with
// full verification and decoded keeps its per-level triangle counts, errors, groups and object
// ids, its decoded cuts stay closed despite per-cluster quantization shifts, and the bytes are
// deterministic (bunny and KiCad connector, bytes per input triangle measured); parametric clusters
// hold each instance exactly once, one type each, with bounds containing every instance, and
// are deterministic; bad inputs are refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <random>
#include <unordered_map>

#include "cluster_dag.h"
#include "dag_merge.h"
#include "obj_reader.h"
#include "package_assembly.h"
#include "package_view.h"
#include "position_key.h"
#include "package_writer.h"
#include "parametrics/parametric_clusters.h"
#include "quantization_snap.h"
#include "test_support.h"

namespace {

double defaultStepM() { return tw::pkg::kDefaultPositionStepM; }

using tw::ClusterDag;
using tw::PackageStorage;
using tw::PackageView;

// A model as one buffer, object ids dense (0..objects-1, in order of appearance), with the
// objects' infos for the package's object table.
struct Model {
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;
  std::vector<uint32_t> ids;
  std::vector<tw::ObjectInfo> objects;
  std::vector<std::pair<glm::vec3, glm::vec3>> object_boxes;
  glm::dvec3 origin{0.0};

  size_t triangles() const { return indices.size() / 3; }
};

Model loadModel(const std::filesystem::path& path) {
  tw::test::CollectingSink sink;
  tw::readObj(path, sink);
  Model m;
  bool first = true;
  for (const auto& object : sink.objects) {
    const auto* mesh = std::get_if<tw::TriangleMesh>(&object.geometry);
    if (!mesh) continue;
    if (first) m.origin = object.info.transform.origin;
    first = false;
    const uint32_t dense = uint32_t(m.objects.size());
    m.objects.push_back(object.info);
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    uint32_t base = uint32_t(m.positions.size());
    for (const glm::vec3& p : mesh->positions) {
      m.positions.push_back(glm::vec3(object.info.transform.apply(p) - m.origin));
      lo = glm::min(lo, m.positions.back());
      hi = glm::max(hi, m.positions.back());
    }
    m.object_boxes.push_back({lo, hi});
    for (uint32_t i : mesh->indices) m.indices.push_back(base + i);
    for (size_t t = 0; t < mesh->triangleCount(); ++t) m.ids.push_back(dense);
  }
  return m;
}

void addObjects(const Model& m, PackageStorage& storage) {
  storage.origin = m.origin;
  storage.addLayer(tw::Layer{"default", 0xff808080u});
  for (size_t o = 0; o < m.objects.size(); ++o) {
    tw::ObjectInfo info = m.objects[o];
    info.layer = 0;
    storage.addObject(info, m.object_boxes[o].first, m.object_boxes[o].second);
  }
}

// Edges used by exactly one triangle, vertices welded by exact position.
template <typename ForEachTriangle>
size_t boundaryEdges(ForEachTriangle&& for_each) {
  std::unordered_map<tw::PositionKey, uint32_t, tw::PositionHash> weld;
  std::unordered_map<uint64_t, uint32_t> counts;
  auto id = [&](const glm::vec3& p) {
    return weld.emplace(tw::positionKeyOf(p), uint32_t(weld.size())).first->second;
  };
  for_each([&](const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
    uint32_t v[3] = {id(a), id(b), id(c)};
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) return;
    for (int k = 0; k < 3; ++k) {
      uint32_t x = std::min(v[k], v[(k + 1) % 3]), y = std::max(v[k], v[(k + 1) % 3]);
      ++counts[(uint64_t(x) << 32) | y];
    }
  });
  size_t boundary = 0;
  for (const auto& [e, n] : counts) boundary += n == 1;
  return boundary;
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Builds the DAG, writes the package, re-opens it with Verify::All and decodes every cluster:
// per-level triangle counts, LOD fields, group records and object ids must match the DAG.
// Returns the package bytes per input triangle.
double roundTrip(const char* name, const Model& model) {
  auto start = std::chrono::steady_clock::now();
  ClusterDag dag = tw::buildClusterDag({model.positions, model.indices, model.ids});
  const double dag_seconds = secondsSince(start);
  PackageStorage storage;
  addObjects(model, storage);
  start = std::chrono::steady_clock::now();
  tw::DagPlacement placement = tw::addDagToPackage(dag, storage);
  const double assemble_seconds = secondsSince(start);
  EXPECT_EQ(placement.first_cluster, 0u);
  {
    // Parallel encoding, sequential placement: a second run gives the same bytes.
    PackageStorage again;
    addObjects(model, again);
    tw::addDagToPackage(dag, again);
    EXPECT_EQ(again.pages, storage.pages);
    EXPECT_TRUE(again.clusters.size() == storage.clusters.size() &&
                std::memcmp(again.clusters.data(), storage.clusters.data(),
                            storage.clusters.size() * sizeof(tw::pkg::ClusterRecord)) == 0);
  }
  auto path = tw::test::scratchDir() / "model.twk";
  start = std::chrono::steady_clock::now();
  tw::PackageWriteStats written = tw::writePackage(storage, path);
  const double write_seconds = secondsSince(start);

  PackageView view = PackageView::open(path, PackageView::Verify::All);
  EXPECT_EQ(view.header().level_count, dag.levelCount());
  EXPECT_EQ(view.header().total_triangles, model.triangles() - dag.stats.skipped_triangles);
  const auto clusters = view.clusters();
  EXPECT_EQ(clusters.size(), dag.clusters.size());
  EXPECT_EQ(view.groups().size(), dag.groups.size());
  if (clusters.size() != dag.clusters.size()) return 0.0;

  std::vector<uint64_t> per_level(dag.levelCount(), 0);
  std::map<uint32_t, uint64_t> level0_objects_dag, level0_objects_pkg;
  std::vector<uint8_t> scratch;
  tw::DecodedCluster decoded;
  uint32_t loaded_page = tw::pkg::kNone;
  std::span<const uint8_t> raw;
  std::vector<std::vector<glm::vec3>> decoded_tris(clusters.size());  // 3 corners per triangle
  uint32_t max_shift = 0;
  uint32_t min_shift = tw::pkg::kMaxPositionShift;
  for (size_t c = 0; c < clusters.size(); ++c) {
    const auto& r = clusters[c];
    const tw::DagCluster& d = dag.clusters[c];
    if (r.page != loaded_page) {
      raw = view.loadPage(r.page, scratch);
      loaded_page = r.page;
    }
    view.decodeCluster(uint32_t(c), raw, decoded);
    decoded_tris[c].reserve(decoded.indices.size());
    for (uint32_t i : decoded.indices) decoded_tris[c].push_back(decoded.positions[i]);
    EXPECT_EQ(decoded.indices.size(), d.indices.size());
    per_level.at(r.level) += decoded.indices.size() / 3;
    max_shift = std::max(max_shift, decoded.shift);
    min_shift = std::min(min_shift, decoded.shift);
    EXPECT_EQ(r.level, d.level);
    EXPECT_EQ(r.error, d.error);
    EXPECT_EQ(r.parent_error, d.parent_error);
    EXPECT_EQ(r.group, d.group == tw::kNoGroup ? tw::pkg::kNone : d.group);
    EXPECT_EQ(r.parent_group, d.parent_group == tw::kNoGroup ? tw::pkg::kNone : d.parent_group);
    EXPECT_EQ(r.lod_radius, d.lod_radius + placement.lod_slack);
    EXPECT_EQ(r.parent_lod_radius, d.parent_lod_radius + placement.lod_slack);
    EXPECT_EQ(glm::vec3(r.lod_center[0], r.lod_center[1], r.lod_center[2]), d.lod_center);
    // Decoded geometry stays within quantization error of the DAG's (a shared vertex is on the
    // grid of the coarsest cluster using it, see package_assembly.h).
    const float tolerance =
        float(tw::quantizationErrorM(view.positionStepM(), placement.max_shift)) * 1.001f;
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(r.aabb_min[a], d.box_min[a], tolerance);
      EXPECT_NEAR(r.aabb_max[a], d.box_max[a], tolerance);
    }
    if (d.level == 0) {
      for (uint32_t id : d.triangle_object_ids) ++level0_objects_dag[id];
      for (uint32_t id : decoded.triangle_objects) ++level0_objects_pkg[id];
    }
  }
  EXPECT_EQ(per_level, dag.triangles_per_level);
  EXPECT_EQ(level0_objects_pkg, level0_objects_dag);
  for (size_t g = 0; g < dag.groups.size(); ++g) {
    const auto& r = view.groups()[g];
    const tw::DagGroup& d = dag.groups[g];
    EXPECT_EQ(r.error, d.error);
    EXPECT_EQ(r.level, d.level);
    EXPECT_EQ(r.cluster_count, d.clusters.size());
    if (!d.clusters.empty()) {
      EXPECT_EQ(r.first_cluster, d.clusters[0]);
    }
    EXPECT_EQ(r.lod_radius, d.sphere_radius + placement.lod_slack);
  }

  // Cuts of the decoded package, welded by exact position: boundary edges beyond the input's own
  // would be cracks that quantization added (clusters of different shifts decoding a shared
  // vertex differently); the shared-grid snap must leave none.
  size_t input_boundary = boundaryEdges([&](auto&& emit) {
    for (size_t i = 0; i + 2 < model.indices.size(); i += 3)
      emit(model.positions[model.indices[i]], model.positions[model.indices[i + 1]],
           model.positions[model.indices[i + 2]]);
  });
  size_t worst_extra = 0;
  float top = 0.0f;
  for (const auto& r : clusters) top = std::max(top, r.error);
  for (int step = 0; step < 12; ++step) {
    const float tau = top * 1.2f * float(step) / 11.0f;
    size_t boundary = boundaryEdges([&](auto&& emit) {
      for (size_t c = 0; c < clusters.size(); ++c) {
        if (!(clusters[c].error <= tau && tau < clusters[c].parent_error)) continue;
        const auto& t = decoded_tris[c];
        for (size_t i = 0; i + 2 < t.size(); i += 3) emit(t[i], t[i + 1], t[i + 2]);
      }
    });
    worst_extra = std::max(worst_extra, boundary > input_boundary ? boundary - input_boundary : 0);
  }
  EXPECT_EQ(worst_extra, 0u) << "quantization must not open cracks between clusters";
  EXPECT_EQ(max_shift, placement.max_shift);

  uint64_t all_triangles = 0;
  for (uint64_t t : dag.triangles_per_level) all_triangles += t;
  const double per_triangle = double(written.file_bytes) / double(model.triangles());
  std::printf("[ package ] %s: %zu input triangles, %llu in all %u levels (%.2fx), file %llu bytes "
              "= %.2f B per input triangle (pages %.2f, cluster table %.2f); DAG %.3f s, encode "
              "%.3f s, write %.3f s\n",
              name, model.triangles(), (unsigned long long)all_triangles, dag.levelCount(),
              double(all_triangles) / double(model.triangles()),
              (unsigned long long)written.file_bytes, per_triangle,
              double(written.section_bytes[size_t(tw::pkg::SectionType::PageData)]) /
                  double(model.triangles()),
              double(written.section_bytes[size_t(tw::pkg::SectionType::Clusters)]) /
                  double(model.triangles()),
              dag_seconds, assemble_seconds, write_seconds);
  std::printf("[ package ] %s: quantization shifts %u..%u, %llu positions snapped to a coarser "
              "shared grid; decoded cuts: at most %zu boundary edges beyond the input's %zu\n",
              name, min_shift, max_shift, (unsigned long long)placement.coarsened_vertices,
              worst_extra, input_boundary);
  return per_triangle;
}

TEST(PackageAssembly, BunnyRoundTrip) {
  Model bunny = loadModel(tw::test::sharedDataDir() / "stanford-bunny.obj");
  ASSERT_EQ(bunny.triangles(), 69451u);
  double bytes = roundTrip("stanford-bunny", bunny);
  EXPECT_GT(bytes, 1.0);
  EXPECT_LE(bytes, 24.0) << "the package budget is 24 bytes per input triangle, all levels";
}

TEST(PackageAssembly, KicadConnectorRoundTrip) {
  Model kicad = loadModel(tw::test::sharedDataDir() / "kicad_dsub62.obj");
  ASSERT_EQ(kicad.triangles(), 94176u);
  ASSERT_EQ(kicad.objects.size(), 648u);
  double bytes = roundTrip("kicad_dsub62", kicad);
  EXPECT_GT(bytes, 1.0);
  EXPECT_LE(bytes, 24.0) << "the package budget is 24 bytes per input triangle, all levels";
}

TEST(PackageAssembly, RefusesObjectIdsOutsideTheObjectTable) {
  std::vector<glm::vec3> positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  std::vector<uint32_t> indices = {0, 1, 2}, ids = {3};
  ClusterDag dag = tw::buildClusterDag({positions, indices, ids});
  PackageStorage storage;
  storage.addLayer(tw::Layer{});
  storage.addObject(tw::ObjectInfo{}, glm::vec3(0.0f), glm::vec3(1.0f));
  EXPECT_THROW(tw::addDagToPackage(dag, storage), std::invalid_argument);
  EXPECT_TRUE(storage.clusters.empty());
}

// Snapping piece by piece (two seam-locked halves, then their merged levels, as the preprocessor
// streams them) gives exactly the whole-DAG snapping, and every distinct position decodes to one
// point in every cluster that uses it (what keeps cuts closed across pieces).
TEST(PackageAssembly, PiecewiseSnappingEqualsWholeDagSnapping) {
  Model bunny = loadModel(tw::test::sharedDataDir() / "stanford-bunny.obj");
  for (glm::vec3& p : bunny.positions) p *= 2000.0f;  // ~300 m: clusters of many shifts
  float mid = 0.0f;
  for (const glm::vec3& p : bunny.positions) mid += p.x / float(bunny.positions.size());
  std::vector<uint32_t> half_indices[2], half_ids[2];
  for (size_t t = 0; t < bunny.ids.size(); ++t) {
    const uint32_t* v = &bunny.indices[3 * t];
    float cx = (bunny.positions[v[0]].x + bunny.positions[v[1]].x + bunny.positions[v[2]].x) / 3;
    int h = cx < mid ? 0 : 1;
    half_indices[h].insert(half_indices[h].end(), v, v + 3);
    half_ids[h].push_back(bunny.ids[t]);
  }
  tw::DagOptions brick_options;
  brick_options.cluster_size = 128;
  brick_options.lock_open_boundaries = true;
  std::vector<ClusterDag> bricks;
  for (int h = 0; h < 2; ++h)
    bricks.push_back(tw::buildClusterDag({bunny.positions, half_indices[h], half_ids[h]},
                                         brick_options));
  tw::DagOptions merge_options;
  merge_options.cluster_size = 128;

  // Pieces: each brick (its roots exported), then the merged levels.
  tw::QuantizationSnapper pieces(defaultStepM());
  std::vector<std::vector<uint8_t>> exported(2);
  std::vector<tw::DagCluster> roots;
  for (int h = 0; h < 2; ++h) {
    for (const tw::DagCluster& c : bricks[h].clusters) {
      exported[h].push_back(c.parent_group == tw::kNoGroup);
      if (exported[h].back()) roots.push_back(c);
    }
    pieces.solve(h, {bricks[h].clusters, exported[h], tw::SharedPositions::SeamsAndRoots, {}});
  }
  tw::MergedRoots merged = tw::mergeBrickRoots(roots, merge_options);
  std::vector<tw::DagCluster> upper(merged.dag.clusters.begin() + merged.front_count,
                                    merged.dag.clusters.end());
  ASSERT_FALSE(upper.empty());
  pieces.solve(2, {upper, {}, tw::SharedPositions::All, {}});
  int rounds = 0;
  for (auto stale = pieces.stalePieces(); !stale.empty(); stale = pieces.stalePieces()) {
    ASSERT_LT(++rounds, 40);
    for (uint32_t p : stale)
      pieces.solve(p, p == 2 ? tw::SnapPiece{upper, {}, tw::SharedPositions::All, {}}
                             : tw::SnapPiece{bricks[p].clusters, exported[p],
                                             tw::SharedPositions::SeamsAndRoots, {}});
  }
  std::vector<std::vector<glm::vec3>> piecewise;
  std::vector<uint32_t> piecewise_shifts, shifts;
  for (uint32_t p = 0; p < 3; ++p) {
    tw::SnapPiece input = p == 2 ? tw::SnapPiece{upper, {}, tw::SharedPositions::All, {}}
                                 : tw::SnapPiece{bricks[p].clusters, exported[p],
                                                 tw::SharedPositions::SeamsAndRoots, {}};
    for (auto& snapped : pieces.snap(p, input, shifts)) piecewise.push_back(std::move(snapped));
    piecewise_shifts.insert(piecewise_shifts.end(), shifts.begin(), shifts.end());
  }

  // The whole DAG at once.
  ClusterDag whole = tw::mergeBrickDags(bricks, merge_options);
  ASSERT_EQ(whole.clusters.size(), piecewise.size());
  tw::QuantizationSnapper at_once(defaultStepM());
  at_once.solve(0, {whole.clusters, {}, tw::SharedPositions::None, {}});
  std::vector<uint32_t> whole_shifts;
  std::vector<std::vector<glm::vec3>> snapped = at_once.snap(0, {whole.clusters, {}, tw::SharedPositions::None, {}}, whole_shifts);
  EXPECT_EQ(piecewise_shifts, whole_shifts);
  EXPECT_EQ(piecewise, snapped);
  EXPECT_EQ(pieces.maxShift(), at_once.maxShift());
  EXPECT_EQ(pieces.coarsenedVertices(), at_once.coarsenedVertices());
  EXPECT_GT(pieces.maxShift(), 0u) << "the test needs several quantization grids";
  EXPECT_GT(pieces.sharedPositions(), 0u);

  // One snapped point per distinct position, whichever cluster uses it.
  std::unordered_map<tw::PositionKey, glm::vec3, tw::PositionHash> point;
  size_t conflicts = 0;
  for (size_t c = 0; c < whole.clusters.size(); ++c)
    for (size_t v = 0; v < whole.clusters[c].positions.size(); ++v) {
      auto [it, inserted] =
          point.emplace(tw::positionKeyOf(whole.clusters[c].positions[v]), piecewise[c][v]);
      conflicts += !inserted && it->second != piecewise[c][v];
    }
  EXPECT_EQ(conflicts, 0u);
}

// Random primitives of every type over a 100 m site, far from the world origin.
std::vector<tw::ParametricItem> randomItems(size_t count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<tw::ParametricItem> items(count);
  for (size_t i = 0; i < count; ++i) {
    tw::ParametricItem& it = items[i];
    it.object = uint32_t(i % 7);
    it.transform.origin = glm::dvec3(500000.0, 6000000.0, 10.0) +
                          glm::dvec3(unit(rng) * 100.0, unit(rng) * 100.0, unit(rng) * 20.0);
    float angle = unit(rng) * 6.28f;
    it.transform.linear = glm::mat3(std::cos(angle), std::sin(angle), 0.0f, -std::sin(angle),
                                    std::cos(angle), 0.0f, 0.0f, 0.0f, 1.0f) *
                          (0.5f + unit(rng));
    float r = 0.05f + unit(rng);
    switch (rng() % 7) {
      case 0: it.primitive = tw::Cylinder{r, 2.0f * r + 0.1f, true}; break;
      case 1: it.primitive = tw::Cone{r, 0.5f * r, r, false}; break;
      case 2: it.primitive = tw::Sphere{r}; break;
      case 3: it.primitive = tw::TorusSegment{2.0f * r, 0.5f * r, 1.5f}; break;
      case 4: it.primitive = tw::Box{glm::vec3(r, 0.5f * r, 2.0f * r)}; break;
      case 5: it.primitive = tw::Extrusion{{{0, 0}, {r, 0}, {r, r}, {0, 2 * r}}, r}; break;
      default: it.primitive = tw::Revolution{{{0, 0}, {r, 0.5f}, {0, 1}}, 3.14f}; break;
    }
  }
  return items;
}

TEST(ParametricClusters, EveryInstanceOnceInAClusterOfItsTypeWithinBounds) {
  auto items = randomItems(3000, 7);
  const glm::dvec3 origin(500050.0, 6000050.0, 0.0);
  const uint32_t max_per_cluster = 100;
  tw::ParametricClustering clustering = tw::clusterPrimitives(items, origin, max_per_cluster);
  ASSERT_EQ(clustering.offsets.size(), clustering.clusterCount() + 1);
  std::vector<int> seen(items.size(), 0);
  for (size_t c = 0; c < clustering.clusterCount(); ++c) {
    const uint32_t size = clustering.offsets[c + 1] - clustering.offsets[c];
    EXPECT_GT(size, 0u);
    EXPECT_LE(size, max_per_cluster);
    for (uint32_t i = clustering.offsets[c]; i < clustering.offsets[c + 1]; ++i) {
      const uint32_t item = clustering.order[i];
      ++seen[item];
      EXPECT_EQ(items[item].primitive.index(), size_t(clustering.types[c]));
    }
  }
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; }));
  // Runs are balanced: 3000 items of 7 types need about 3000 / 100 + 7 clusters, not more.
  EXPECT_LE(clustering.clusterCount(), items.size() / max_per_cluster + 7);

  PackageStorage storage;
  storage.origin = origin;
  storage.addLayer(tw::Layer{});
  for (int o = 0; o < 7; ++o)
    storage.addObject(tw::ObjectInfo{uint32_t(o), "part", 0, "", 0, {}}, glm::vec3(-200.0f),
                      glm::vec3(200.0f));
  std::vector<uint32_t> ids = tw::addParametricClusters(items, clustering, storage);
  ASSERT_EQ(ids.size(), clustering.clusterCount());
  ASSERT_EQ(storage.instances.size(), items.size());
  std::vector<int> instance_seen(storage.instances.size(), 0);
  for (size_t c = 0; c < ids.size(); ++c) {
    const tw::pkg::ClusterRecord& r = storage.clusters[ids[c]];
    EXPECT_EQ(r.kind, uint8_t(tw::pkg::ClusterKind::Parametric));
    EXPECT_EQ(r.error, 0.0f);
    EXPECT_TRUE(std::isinf(r.parent_error));
    EXPECT_EQ(r.level, 0u);
    const float slack = 1e-4f;
    for (uint32_t i = r.instance_first; i < r.instance_first + r.instance_count; ++i) {
      ++instance_seen[i];
      const tw::pkg::InstanceRecord& in = storage.instances[i];
      EXPECT_EQ(in.type, uint32_t(clustering.types[c]));
      glm::vec3 lo, hi;
      tw::instanceBounds(in, storage.profile_points, lo, hi);
      for (int a = 0; a < 3; ++a) {
        EXPECT_LE(r.aabb_min[a], lo[a] + slack);
        EXPECT_GE(r.aabb_max[a], hi[a] - slack);
      }
      glm::vec3 center(r.center[0], r.center[1], r.center[2]);
      for (int corner = 0; corner < 8; ++corner) {
        glm::vec3 p(corner & 1 ? hi.x : lo.x, corner & 2 ? hi.y : lo.y, corner & 4 ? hi.z : lo.z);
        EXPECT_LE(glm::length(p - center), r.radius * 1.0001f + slack);
      }
    }
  }
  EXPECT_TRUE(
      std::all_of(instance_seen.begin(), instance_seen.end(), [](int n) { return n == 1; }));

  // Spatial compactness: Morton runs must be much tighter than the same runs in input order.
  auto meanDiagonal = [&](const std::vector<uint32_t>& order) {
    double sum = 0.0;
    for (size_t c = 0; c < clustering.clusterCount(); ++c) {
      glm::dvec3 lo(INFINITY), hi(-INFINITY);
      for (uint32_t i = clustering.offsets[c]; i < clustering.offsets[c + 1]; ++i) {
        lo = glm::min(lo, items[order[i]].transform.origin);
        hi = glm::max(hi, items[order[i]].transform.origin);
      }
      sum += glm::length(hi - lo);
    }
    return sum / double(clustering.clusterCount());
  };
  std::vector<uint32_t> naive;  // same types, same run sizes, input order within a type
  for (size_t type = 0; type < 7; ++type)
    for (uint32_t i = 0; i < items.size(); ++i)
      if (items[i].primitive.index() == type) naive.push_back(i);
  const double morton = meanDiagonal(clustering.order), unsorted = meanDiagonal(naive);
  EXPECT_LT(morton, 0.75 * unsorted);
  std::printf("[ parametric ] %zu instances -> %zu clusters; mean run diagonal %.1f m (input "
              "order: %.1f m)\n",
              items.size(), ids.size(), morton, unsorted);

  // The package accepts it.
  auto path = tw::test::scratchDir() / "parametric.twk";
  tw::writePackage(storage, path);
  PackageView view = PackageView::open(path, PackageView::Verify::All);
  EXPECT_EQ(view.instances().size(), items.size());
}

TEST(ParametricClusters, ShowWidthIsTheSecondLargestSize) {
  tw::Transform unit;
  tw::Transform stretched;  // columns of length 2, 1, 3 (rotated about z for the first two)
  stretched.linear = glm::mat3(0.0f, 2.0f, 0.0f, -1.0f, 0.0f, 0.0f, 0.0f, 0.0f, 3.0f);
  EXPECT_FLOAT_EQ(tw::parametricShowWidth(tw::Cylinder{0.1f, 6.0f, true}, unit), 0.2f);
  EXPECT_FLOAT_EQ(tw::parametricShowWidth(tw::Cylinder{0.1f, 0.05f, true}, unit), 0.2f);  // a disc
  EXPECT_FLOAT_EQ(tw::parametricShowWidth(tw::Cylinder{0.1f, 6.0f, true}, stretched), 0.4f);
  EXPECT_FLOAT_EQ(tw::parametricShowWidth(tw::Cone{0.1f, 0.3f, 1.0f, true}, unit), 0.6f);
  EXPECT_FLOAT_EQ(tw::parametricShowWidth(tw::Sphere{0.25f}, stretched), 1.0f);  // 1 x 0.5 x 1.5
  EXPECT_FLOAT_EQ(tw::parametricShowWidth(tw::TorusSegment{0.6f, 0.1f, 1.57f}, unit), 0.2f);
  // A deck plate shows by its shorter side, a beam by its depth.
  EXPECT_FLOAT_EQ(tw::parametricShowWidth(tw::Box{glm::vec3(4.0f, 2.75f, 0.01f)}, unit), 5.5f);
  EXPECT_FLOAT_EQ(tw::parametricShowWidth(tw::Box{glm::vec3(0.05f, 0.15f, 3.0f)}, unit), 0.3f);
  EXPECT_FLOAT_EQ(tw::parametricShowWidth(tw::Box{glm::vec3(0.05f, 0.15f, 3.0f)}, stretched), 0.3f);
  const std::vector<glm::vec2> i_profile = {{-0.075f, -0.15f}, {0.075f, -0.15f}, {0.075f, 0.15f},
                                            {-0.075f, 0.15f}};
  EXPECT_FLOAT_EQ(tw::parametricShowWidth(tw::Extrusion{i_profile, 6.0f}, unit), 0.3f);
  const tw::Revolution vessel{{{0.0f, 0.0f}, {1.2f, 0.5f}, {0.0f, 4.0f}}, 6.28f};
  EXPECT_FLOAT_EQ(tw::parametricShowWidth(vessel, unit), 2.4f);
  EXPECT_EQ(tw::parametricShowWidth(tw::Extrusion{{}, 1.0f}, unit), 0.0f);  // no profile
}

TEST(ParametricClusters, InstancesOfAClusterGoWidestFirst) {
  auto items = randomItems(3000, 7);
  const glm::dvec3 origin(500050.0, 6000050.0, 0.0);
  const tw::ParametricClustering clustering = tw::clusterPrimitives(items, origin, 100);
  auto width = [&](uint32_t item) {
    return tw::parametricShowWidth(items[item].primitive, items[item].transform);
  };
  size_t pairs = 0, ties = 0;
  for (size_t c = 0; c < clustering.clusterCount(); ++c)
    for (uint32_t i = clustering.offsets[c] + 1; i < clustering.offsets[c + 1]; ++i) {
      const float before = width(clustering.order[i - 1]), after = width(clustering.order[i]);
      EXPECT_GE(before, after) << "cluster " << c << " at " << i;
      ++pairs;
      ties += before == after;
    }
  EXPECT_GT(pairs, 2500u);
  EXPECT_LT(ties, pairs / 10);  // random widths: the order is the widths', not an accident
  // The instance records follow the order.
  PackageStorage storage;
  storage.origin = origin;
  tw::addParametricClusters(items, clustering, storage);
  for (size_t k = 0; k < clustering.order.size(); ++k)
    ASSERT_EQ(storage.instances[k].object, items[clustering.order[k]].object);
}

TEST(ParametricClusters, Deterministic) {
  auto items = randomItems(1000, 11);
  const glm::dvec3 origin(500000.0, 6000000.0, 0.0);
  auto a = tw::clusterPrimitives(items, origin, 64);
  auto b = tw::clusterPrimitives(items, origin, 64);
  EXPECT_EQ(a.order, b.order);
  EXPECT_EQ(a.offsets, b.offsets);
  EXPECT_EQ(a.types, b.types);
  PackageStorage sa, sb;
  sa.origin = sb.origin = origin;
  tw::addParametricClusters(items, a, sa);
  tw::addParametricClusters(items, b, sb);
  ASSERT_EQ(sa.clusters.size(), sb.clusters.size());
  EXPECT_EQ(0, std::memcmp(sa.clusters.data(), sb.clusters.data(),
                           sa.clusters.size() * sizeof(tw::pkg::ClusterRecord)));
  EXPECT_EQ(0, std::memcmp(sa.instances.data(), sb.instances.data(),
                           sa.instances.size() * sizeof(tw::pkg::InstanceRecord)));
}

TEST(ParametricClusters, BadInputs) {
  auto items = randomItems(10, 3);
  EXPECT_THROW(tw::clusterPrimitives(items, glm::dvec3(0.0), 0), std::invalid_argument);
  items[4].primitive = tw::Sphere{-1.0f};
  EXPECT_THROW(tw::clusterPrimitives(items, glm::dvec3(0.0), 8), std::invalid_argument);
  auto none = tw::clusterPrimitives({}, glm::dvec3(0.0), 8);
  EXPECT_EQ(none.clusterCount(), 0u);
  EXPECT_TRUE(none.order.empty());
  PackageStorage storage;
  EXPECT_TRUE(tw::addParametricClusters({}, none, storage).empty());
  // A clustering that does not match the items.
  auto good = randomItems(10, 3);
  auto clustering = tw::clusterPrimitives(good, glm::dvec3(0.0), 8);
  clustering.order.pop_back();
  EXPECT_THROW(tw::addParametricClusters(good, clustering, storage), std::invalid_argument);
}

}  // namespace
