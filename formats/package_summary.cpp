// summarizePackage: per-level statistics of a .twk package from its records (package_summary.h).
#include "package_summary.h"

#include <algorithm>
#include <bit>
#include <limits>

namespace tw {

const char* packagePrimitiveTypeName(uint32_t type) {
  static constexpr const char* kNames[pkg::kPrimitiveTypeCount] = {
      "cylinder", "cone", "sphere", "torus", "box", "extrusion", "revolution"};
  return type < pkg::kPrimitiveTypeCount ? kNames[type] : "unknown";
}

PackageSummary summarizePackage(const PackageView& view) {
  const pkg::PackageHeader& h = view.header();
  PackageSummary s;
  s.file = view.fileName();
  s.file_bytes = view.fileBytes();
  s.version = h.version;
  s.minor_version = h.minor_version;
  s.database_path = std::string(view.databasePath());
  s.origin = view.origin();
  s.position_step_m = h.position_step_m;
  s.bounds_min = glm::vec3(h.bounds_min[0], h.bounds_min[1], h.bounds_min[2]);
  s.bounds_max = glm::vec3(h.bounds_max[0], h.bounds_max[1], h.bounds_max[2]);
  s.level_count = h.level_count;
  s.total_triangles = h.total_triangles;
  s.max_cluster_triangles = h.max_cluster_triangles;
  s.target_page_bytes = h.target_page_bytes;
  s.input_hash = h.input_hash;
  for (uint32_t i = 0; i < pkg::kSectionCount; ++i) {
    const pkg::SectionEntry& e = view.section(static_cast<pkg::SectionType>(i));
    s.section_bytes[i] = pkg::storedBytes(e);
    s.section_raw_bytes[i] = e.bytes;
  }

  // The view guarantees every level < level_count.
  s.levels.resize(h.level_count);
  for (uint32_t l = 0; l < h.level_count; ++l) {
    s.levels[l].level = l;
    s.levels[l].min_error_m = std::numeric_limits<float>::infinity();
  }
  const auto instances = view.instances();
  for (const pkg::ClusterRecord& c : view.clusters()) {
    PackageLevelSummary& l = s.levels[c.level];
    ++l.clusters;
    l.triangles += c.triangle_count;
    l.vertices += c.vertex_count;
    if (c.parent_group == pkg::kNone) ++l.roots;
    if (c.kind == static_cast<uint8_t>(pkg::ClusterKind::Parametric)) {
      ++l.parametric_clusters;
      l.instances += c.instance_count;
    } else {
      l.encoded_bytes += c.encoded_bytes;
    }
    l.min_error_m = std::min(l.min_error_m, c.error);
    l.max_error_m = std::max(l.max_error_m, c.error);
    l.mean_error_m += c.error;
    s.all_level_triangles += c.triangle_count;
    if (c.flags & pkg::kClusterFarProxy) {
      ++s.far_proxy_clusters;
      s.far_proxy_triangles += c.triangle_count;
    }
  }
  for (PackageLevelSummary& l : s.levels) {
    if (l.clusters) {
      l.mean_error_m /= double(l.clusters);
    } else {
      l.min_error_m = 0.0f;
    }
  }
  for (const pkg::GroupRecord& g : view.groups()) ++s.levels[g.level].groups;
  s.clusters = view.clusters().size();
  s.groups = view.groups().size();

  s.pages = view.pages().size();
  for (const pkg::PageRecord& p : view.pages()) {
    s.page_stored_bytes += p.stored_bytes;
    s.page_raw_bytes += p.raw_bytes;
    if (p.codec != static_cast<uint32_t>(pkg::PageCodec::None)) ++s.pages_compressed;
  }

  s.instances = instances.size();
  s.sealed_runs_marked = (view.header().flags & pkg::kHeaderSealedRunsMarked) != 0;
  s.covered_faces_marked = (view.header().flags & pkg::kHeaderCoveredFacesMarked) != 0;
  for (const pkg::InstanceRecord& in : instances) {
    ++s.instances_by_type[in.type];
    s.sealed_run_members += (in.flags & pkg::kInstanceSealedRunMember) != 0;
    s.sealed_run_closers += (in.flags & pkg::kInstanceSealedRunCloser) != 0;
    s.covered_box_faces += uint64_t(std::popcount(in.flags & pkg::kInstanceCoveredFaces));
  }
  s.profile_points = view.profilePoints().size();

  s.objects = view.objects().size();
  s.layers.resize(view.layers().size());
  for (uint32_t l = 0; l < view.layers().size(); ++l) {
    s.layers[l].name = std::string(view.layerName(l));
    s.layers[l].color_rgba = view.layers()[l].color_rgba;
  }
  for (const pkg::ObjectRecord& o : view.objects()) {
    ++s.layers[o.layer].objects;
    if (o.db_key_bytes > 0) ++s.objects_with_db_key;
    if (o.flags & pkg::kObjectClosedSurface) ++s.closed_objects;
  }

  const VisibilityView& vis = view.visibilityCells();
  PackageSummary::Visibility& v = s.visibility;
  v.bytes = view.section(pkg::SectionType::Visibility).bytes;
  if (!vis.empty()) {
    const pkg::VisibilityHeader& vh = vis.header();
    v.present = true;
    v.cells = vh.cell_count;
    v.solid_cells = vh.solid_cells;
    v.grid_dims = glm::uvec3(vh.grid_dims[0], vh.grid_dims[1], vh.grid_dims[2]);
    v.grid_min = glm::dvec3(vh.grid_min[0], vh.grid_min[1], vh.grid_min[2]);
    v.cell_size_m = vh.cell_size_m;
    v.rays_cast = vh.rays_cast;
    v.rays_per_cell = vh.rays_per_cell;
    v.candidate_level = vh.candidate_level;
    v.candidate_triangles = vh.candidate_triangles;
    v.visible_sets = (vh.flags & pkg::kVisibleSetsPresent) != 0;
    v.parametric_candidates = (vh.flags & pkg::kParametricCandidates) != 0;
    v.occluder_ids = vh.occluder_id_count;
    v.visible_ids = vh.visible_id_count;
    v.average_occluders = vis.averageOccluders();
    uint64_t visible = 0;
    double coverage = 0.0;
    for (const pkg::VisibilityCellRecord& c : vis.cells()) {
      visible += c.visible_count;
      coverage += c.occluder_coverage;
    }
    if (v.cells) {
      v.average_visible = double(visible) / double(v.cells);
      v.average_coverage = coverage / double(v.cells);
    }
  }
  return s;
}

}  // namespace tw
