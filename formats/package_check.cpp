// checkPackage: every check `terawalk verify` runs beyond PackageView's own (see package_check.h
// and docs/verify.md for the rules).
#include "package_check.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "covered_box_faces.h"
#include "package_writer.h"
#include "sealed_pipe_runs.h"

namespace tw {
namespace {

using pkg::ClusterKind;
using pkg::ClusterRecord;
using pkg::GroupRecord;
using pkg::kNone;
using pkg::PageRecord;
using pkg::SectionType;

std::string num(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.7g", v);
  return buffer;
}
std::string str(uint64_t v) { return std::to_string(v); }
std::string vec(const glm::dvec3& v) {
  char buffer[96];
  std::snprintf(buffer, sizeof(buffer), "(%.7g, %.7g, %.7g)", v.x, v.y, v.z);
  return buffer;
}
glm::dvec3 v3(const float* p) { return {p[0], p[1], p[2]}; }

// Float rounding allowance for a comparison of values of magnitude `m` (records are float).
double roundSlack(double m) { return 4e-7 * std::abs(m) + 1e-12; }

bool isMesh(const ClusterRecord& r) { return r.kind == static_cast<uint8_t>(ClusterKind::Mesh); }

// Sphere a contains sphere b, up to `slack`.
bool sphereContains(const glm::dvec3& ca, double ra, const glm::dvec3& cb, double rb,
                    double slack) {
  return glm::length(cb - ca) + rb <= ra + slack;
}
bool sameSphere(const glm::dvec3& ca, double ra, const glm::dvec3& cb, double rb, double slack) {
  return glm::length(cb - ca) <= slack && std::abs(ra - rb) <= slack;
}
bool boxContains(const glm::dvec3& lo, const glm::dvec3& hi, const glm::dvec3& p, double slack) {
  return glm::all(glm::greaterThanEqual(p, lo - slack)) &&
         glm::all(glm::lessThanEqual(p, hi + slack));
}

// Identifies decoded vertices across clusters and levels. Bit-identical positions are one vertex
// (clusters of one shift, or a packer that snaps shared vertices, decode shared vertices so).
// Otherwise a cluster's *border* vertex (on an edge its cluster does not use exactly twice) also
// matches a border vertex of a cluster with another shift within the sum of both quantization
// errors (docs/package-format.md); only border vertices can be shared, and searching for them
// alone keeps the spatial hash sparse.
class Welder {
 public:
  Welder(double step_m, uint32_t max_shift, double slack_m) : step_m_(step_m), slack_m_(slack_m) {
    cell_m_ = std::max(2.0 * (quantizationErrorM(step_m, max_shift) + slack_m), 1e-12);
  }

  uint32_t add(const glm::vec3& position, uint32_t shift, bool border) {
    auto [exact, inserted] = exact_.try_emplace(bitsOf(position), kNone);
    if (!inserted) return exact->second;
    uint32_t best = border ? nearestBorder(position, shift) : kNone;
    if (best == kNone) {
      best = static_cast<uint32_t>(positions_.size());
      positions_.push_back(position);
      shifts_.push_back(shift);
      if (border) {
        auto [head, fresh] = heads_.try_emplace(key(cellOf(glm::dvec3(position))), best);
        next_.push_back(fresh ? kNone : head->second);
        if (!fresh) head->second = best;
      } else {
        next_.push_back(kNone);
      }
    }
    exact->second = best;
    return best;
  }
  const glm::vec3& position(uint32_t id) const { return positions_[id]; }

 private:
  struct Bits {
    uint32_t x, y, z;
    bool operator==(const Bits&) const = default;
  };
  struct BitsHash {
    size_t operator()(const Bits& b) const {
      return size_t((uint64_t(b.x) * 0x9E3779B97F4A7C15ull) ^
                    (uint64_t(b.y) * 0xC2B2AE3D27D4EB4Full) ^
                    (uint64_t(b.z) * 0x165667B19E3779F9ull));
    }
  };
  static Bits bitsOf(const glm::vec3& p) {
    return {std::bit_cast<uint32_t>(p.x), std::bit_cast<uint32_t>(p.y),
            std::bit_cast<uint32_t>(p.z)};
  }

  // The nearest border vertex of another shift within tolerance, or kNone. The search radius is
  // at most half a hash cell, so the cells it touches are at most 2 per axis.
  uint32_t nearestBorder(const glm::vec3& position, uint32_t shift) const {
    const glm::dvec3 p(position);
    const double own = quantizationErrorM(step_m_, shift) + slack_m_;
    const glm::i64vec3 lo = cellOf(p - 0.5 * cell_m_), hi = cellOf(p + 0.5 * cell_m_);
    uint32_t best = kNone;
    double best_d = std::numeric_limits<double>::infinity();
    for (int64_t z = lo.z; z <= hi.z; ++z)
      for (int64_t y = lo.y; y <= hi.y; ++y)
        for (int64_t x = lo.x; x <= hi.x; ++x) {
          auto it = heads_.find(key({x, y, z}));
          if (it == heads_.end()) continue;
          for (uint32_t v = it->second; v != kNone; v = next_[v]) {
            if (shifts_[v] == shift) continue;  // same grid: only bit-identical matches
            const double d = glm::length(glm::dvec3(positions_[v]) - p);
            if (d <= own + quantizationErrorM(step_m_, shifts_[v]) && d < best_d) {
              best = v;
              best_d = d;
            }
          }
        }
    return best;
  }
  glm::i64vec3 cellOf(const glm::dvec3& p) const { return glm::i64vec3(glm::floor(p / cell_m_)); }
  static uint64_t key(const glm::i64vec3& c) {
    return uint64_t(c.x) * 0x9E3779B97F4A7C15ull ^ uint64_t(c.y) * 0xC2B2AE3D27D4EB4Full ^
           uint64_t(c.z) * 0x165667B19E3779F9ull;
  }

  double step_m_, slack_m_, cell_m_;
  std::vector<glm::vec3> positions_;
  std::vector<uint32_t> shifts_;
  std::vector<uint32_t> next_;                    // chain of border vertices in one hash cell
  std::unordered_map<uint64_t, uint32_t> heads_;  // colliding cells merely share a chain
  std::unordered_map<Bits, uint32_t, BitsHash> exact_;
};

uint64_t edgeKey(uint32_t a, uint32_t b) {
  return a < b ? (uint64_t(a) << 32 | b) : (uint64_t(b) << 32 | a);
}
using EdgeCounts = std::unordered_map<uint64_t, uint32_t>;
// (edge, triangles using it), sorted by edge: cheaper than a hash map for one cluster or group.
using EdgeList = std::vector<std::pair<uint64_t, uint32_t>>;

// Appends the edge keys of `triangles` to `keys` (triangles degenerate after welding are
// skipped, the same way at both levels).
void appendEdges(std::span<const uint32_t> triangles, std::vector<uint64_t>& keys) {
  for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
    const uint32_t a = triangles[t], b = triangles[t + 1], c = triangles[t + 2];
    if (a == b || b == c || a == c) continue;
    keys.insert(keys.end(), {edgeKey(a, b), edgeKey(b, c), edgeKey(c, a)});
  }
}
// Sorts `keys` and counts equal runs into `out`.
void countEdges(std::vector<uint64_t>& keys, EdgeList& out) {
  std::sort(keys.begin(), keys.end());
  out.clear();
  for (size_t i = 0; i < keys.size();) {
    size_t j = i + 1;
    while (j < keys.size() && keys[j] == keys[i]) ++j;
    out.push_back({keys[i], uint32_t(j - i)});
    i = j;
  }
}
uint32_t countOf(const EdgeList& list, uint64_t edge) {
  auto it = std::lower_bound(list.begin(), list.end(), std::make_pair(edge, uint32_t{0}));
  return it != list.end() && it->first == edge ? it->second : 0;
}

class Checker {
 public:
  Checker(const PackageView& view, const CheckOptions& options, Progress* progress)
      : view_(view),
        options_(options),
        progress_(progress),
        clusters_(view.clusters()),
        groups_(view.groups()),
        pages_(view.pages()) {}

  CheckReport run() {
    // Each stage runs only if the ones before it passed.
    (void)(checksums() && references() && sealedRuns() && boxFaces() && errors() && bounds() &&
           (!options_.cracks || cracks()));
    return std::move(report_);
  }

 private:
  // Records the failure; returns false so that callers can `return fail(...)`.
  bool fail(const char* check, std::string what, uint64_t offset, uint32_t cluster = kNone,
            uint32_t group = kNone, uint32_t page = kNone) {
    report_.failure = CheckFailure{check, std::move(what), offset, cluster, group, page};
    endStage(progress_);
    return false;
  }
  bool cancelled() {
    if (progress_ && progress_->cancelled()) {
      report_.cancelled = true;
      endStage(progress_);
      return true;
    }
    return false;
  }
  uint64_t clusterAt(uint32_t c) const {
    return view_.section(SectionType::Clusters).offset + uint64_t{c} * sizeof(ClusterRecord);
  }
  uint64_t groupAt(uint32_t g) const {
    return view_.section(SectionType::Groups).offset + uint64_t{g} * sizeof(GroupRecord);
  }
  // A record of a table that may be stored compressed: its own offset, or the frame's.
  uint64_t recordAt(SectionType type, uint64_t index, uint64_t record_bytes) const {
    const pkg::SectionEntry& e = view_.section(type);
    return e.stored_bytes != 0 ? e.offset : e.offset + index * record_bytes;
  }
  uint64_t pageAt(uint32_t p) const {
    return view_.section(SectionType::PageData).offset + pages_[p].offset;
  }
  std::string clusterName(uint32_t c) const {
    return "cluster " + str(c) + " (level " + str(clusters_[c].level) + ")";
  }
  double tolerance(uint32_t shift) const {
    return quantizationErrorM(view_.positionStepM(), shift) + options_.position_slack_m;
  }

  // (a) Every checksum, and zero padding, so that any changed byte is caught: the file read again
  // now, section by section.
  bool checksums() {
    const pkg::PackageHeader& h = view_.header();
    const uint64_t file_bytes = view_.fileBytes();
    beginStage(progress_, "checksums", file_bytes);
    uint64_t done = 0;
    std::vector<pkg::SectionEntry> table(h.section_count);
    view_.readFileBytes(h.header_bytes, table.size() * sizeof(pkg::SectionEntry),
                        reinterpret_cast<uint8_t*>(table.data()));
    pkg::PackageHeader file_header{};
    view_.readFileBytes(0, sizeof(file_header), reinterpret_cast<uint8_t*>(&file_header));
    const uint64_t header_sum = packageHeaderChecksum(file_header, table);
    ++report_.counts.checksums;
    if (header_sum != file_header.header_checksum)
      return fail("checksums",
                  "header checksum is " + str(header_sum) + ", header says " +
                      str(file_header.header_checksum),
                  offsetof(pkg::PackageHeader, header_checksum));
    std::vector<std::pair<uint64_t, uint64_t>> used{
        {0, h.header_bytes + uint64_t{h.section_count} * sizeof(pkg::SectionEntry)}};
    for (uint32_t i = 0; i < table.size(); ++i) {
      const pkg::SectionEntry& e = table[i];
      const uint64_t stored = pkg::storedBytes(e);
      if (e.offset > file_bytes || stored > file_bytes - e.offset)
        return fail("checksums", "section " + str(i) + " runs past the end of the file", e.offset);
      if (stored > 0) used.push_back({e.offset, e.offset + stored});
      // Page data: its pages are checked one by one first, so a failure names the page.
      if (i == static_cast<uint32_t>(SectionType::PageData) && !pageChecksums()) return false;
      const uint64_t sum = view_.fileChecksum(e.offset, stored);
      ++report_.counts.checksums;
      done += stored;
      updateProgress(progress_, done);
      if (cancelled()) return false;
      if (sum != e.checksum)
        return fail("checksums",
                    std::string("section ") +
                        (i < pkg::kSectionCount ? pkg::kSectionNames[i] : str(i).c_str()) +
                        " checksum is " + str(sum) + ", its table entry says " + str(e.checksum),
                    e.offset);
    }
    std::sort(used.begin(), used.end());
    used.push_back({file_bytes, file_bytes});
    uint64_t cursor = 0;
    std::vector<uint8_t> gap;
    for (const auto& [begin, end] : used) {
      if (begin > cursor) {
        gap.resize(begin - cursor);
        view_.readFileBytes(cursor, gap.size(), gap.data());
        for (uint64_t b = 0; b < gap.size(); ++b)
          if (gap[b] != 0)
            return fail("checksums",
                        "byte " + str(cursor + b) + " lies outside every section but is not zero",
                        cursor + b);
      }
      cursor = std::max(cursor, end);
    }
    endStage(progress_);
    return true;
  }

  bool pageChecksums() {
    std::vector<uint8_t> stored;
    for (uint32_t p = 0; p < pages_.size(); ++p) {
      const uint64_t sum = packageSectionChecksum(view_.pageStored(p, stored));
      ++report_.counts.checksums;
      if (sum != pages_[p].checksum)
        return fail("checksums",
                    "page " + str(p) + " checksum is " + str(sum) + ", its record says " +
                        str(pages_[p].checksum),
                    pageAt(p), kNone, kNone, p);
    }
    return true;
  }

  // (b) Links the view does not check: group -> cluster direction, children, page contents,
  // header totals.
  // (b2) Sealed-run flags: in a marked package, every instance's roles are what the search finds
  // (a wrong member flag would cull the inside of a pipe that can be seen).
  bool sealedRuns() {
    if (!(view_.header().flags & pkg::kHeaderSealedRunsMarked)) return true;
    beginStage(progress_, "sealed runs", 0);
    const auto instances = view_.instances();
    const std::vector<uint8_t> roles = findSealedRuns(instances);
    constexpr uint32_t kRoleBits = pkg::kInstanceSealedRunMember | pkg::kInstanceSealedRunCloser;
    for (uint32_t i = 0; i < instances.size(); ++i) {
      const uint32_t stored = instances[i].flags & kRoleBits, found = sealedRunInstanceFlags(roles[i]);
      if (stored != found)
        return fail("sealed runs",
                    "instance " + str(i) + " has sealed-run flags " + str(stored) +
                        " but the search finds " + str(found) + " (member 2, closer 4)",
                    recordAt(SectionType::Instances, i, sizeof(pkg::InstanceRecord)));
    }
    endStage(progress_);
    return !cancelled();
  }

  // (b3) Covered box faces: in a marked package, every box's are what the search finds (a wrong
  // one would leave a hole where a box's side shows).
  bool boxFaces() {
    if (!(view_.header().flags & pkg::kHeaderCoveredFacesMarked)) return true;
    beginStage(progress_, "box faces", 0);
    const auto instances = view_.instances();
    std::vector<uint32_t> object_layers;
    object_layers.reserve(view_.objects().size());
    for (const pkg::ObjectRecord& o : view_.objects()) object_layers.push_back(o.layer);
    const std::vector<uint8_t> faces = findCoveredBoxFaces(instances, object_layers);
    for (uint32_t i = 0; i < instances.size(); ++i) {
      const uint32_t stored = tw::coveredFaces(instances[i].flags), found = faces[i];
      if (stored != found)
        return fail("box faces",
                    "instance " + str(i) + " has covered faces " + str(stored) +
                        " but the search finds " + str(found) + " (bit f: -X, +X, -Y, +Y, -Z, +Z)",
                    recordAt(SectionType::Instances, i, sizeof(pkg::InstanceRecord)));
    }
    endStage(progress_);
    return !cancelled();
  }

  bool references() {
    beginStage(progress_, "references", clusters_.size());
    const pkg::PackageHeader& h = view_.header();
    // Children of each group, as a compressed list.
    child_begin_.assign(groups_.size() + 1, 0);
    for (const ClusterRecord& r : clusters_)
      if (r.parent_group != kNone) ++child_begin_[r.parent_group + 1];
    for (size_t g = 0; g < groups_.size(); ++g) child_begin_[g + 1] += child_begin_[g];
    children_.resize(child_begin_.back());
    {
      std::vector<uint32_t> fill(child_begin_.begin(), child_begin_.end() - 1);
      for (uint32_t c = 0; c < clusters_.size(); ++c)
        if (clusters_[c].parent_group != kNone) children_[fill[clusters_[c].parent_group]++] = c;
    }
    for (uint32_t g = 0; g < groups_.size(); ++g) {
      const GroupRecord& gr = groups_[g];
      if (children(g).empty())
        return fail("references",
                    "group " + str(g) + " (level " + str(gr.level) +
                        ") replaces no cluster (no cluster has it as parent group)",
                    groupAt(g), kNone, g);
      for (uint32_t c = gr.first_cluster; c < gr.first_cluster + gr.cluster_count; ++c)
        if (clusters_[c].group != g)
          return fail(
              "references",
              "group " + str(g) + " lists " + clusterName(c) +
                  " among its produced clusters, but the cluster names group " +
                  (clusters_[c].group == kNone ? std::string("none") : str(clusters_[c].group)),
              clusterAt(c), c, g);
    }
    // Page contents: the clusters pointing into each page, their byte ranges disjoint.
    std::vector<std::vector<uint32_t>> by_page(pages_.size());
    uint32_t max_level = 0, max_triangles = 0;
    uint64_t level0_triangles = 0;
    for (uint32_t c = 0; c < clusters_.size(); ++c) {
      const ClusterRecord& r = clusters_[c];
      if (isMesh(r)) by_page[r.page].push_back(c);
      max_level = std::max<uint32_t>(max_level, r.level);
      max_triangles = std::max(max_triangles, r.triangle_count);
      if (r.level == 0) level0_triangles += r.triangle_count;
    }
    for (uint32_t p = 0; p < pages_.size(); ++p) {
      auto& list = by_page[p];
      if (list.size() != pages_[p].cluster_count)
        return fail("references",
                    "page " + str(p) + " records " + str(pages_[p].cluster_count) +
                        " clusters but " + str(list.size()) + " clusters point into it",
                    view_.section(SectionType::Pages).offset + uint64_t{p} * sizeof(PageRecord),
                    kNone, kNone, p);
      std::sort(list.begin(), list.end(), [&](uint32_t a, uint32_t b) {
        return clusters_[a].page_offset < clusters_[b].page_offset;
      });
      for (size_t i = 1; i < list.size(); ++i) {
        const ClusterRecord& a = clusters_[list[i - 1]];
        if (uint64_t{a.page_offset} + a.encoded_bytes > clusters_[list[i]].page_offset)
          return fail("references",
                      "clusters " + str(list[i - 1]) + " and " + str(list[i]) +
                          " overlap in page " + str(p) + " (bytes " + str(a.page_offset) + "+" +
                          str(a.encoded_bytes) + " and " + str(clusters_[list[i]].page_offset) +
                          ")",
                      clusterAt(list[i]), list[i], kNone, p);
      }
    }
    if (!clusters_.empty() && h.level_count != max_level + 1)
      return fail("references",
                  "header level count " + str(h.level_count) +
                      " but the highest cluster level is " + str(max_level),
                  offsetof(pkg::PackageHeader, level_count));
    if (h.max_cluster_triangles != max_triangles)
      return fail("references",
                  "header largest cluster " + str(h.max_cluster_triangles) +
                      " triangles but the largest has " + str(max_triangles),
                  offsetof(pkg::PackageHeader, max_cluster_triangles));
    if (h.total_triangles != level0_triangles)
      return fail("references",
                  "header total triangles " + str(h.total_triangles) +
                      " but level-0 clusters hold " + str(level0_triangles),
                  offsetof(pkg::PackageHeader, total_triangles));
    updateProgress(progress_, clusters_.size());
    endStage(progress_);
    return true;
  }

  std::span<const uint32_t> children(uint32_t g) const {
    return std::span<const uint32_t>(children_).subspan(child_begin_[g],
                                                        child_begin_[g + 1] - child_begin_[g]);
  }

  // (c) Errors monotone toward the roots and the lod spheres they are projected with.
  bool errors() {
    beginStage(progress_, "errors", groups_.size() + clusters_.size());
    for (uint32_t g = 0; g < groups_.size(); ++g) {
      const GroupRecord& gr = groups_[g];
      const glm::dvec3 gc = v3(gr.lod_center);
      const double gr_slack = roundSlack(glm::length(gc) + gr.lod_radius);
      float max_parent = gr.error;
      if (gr.cluster_count > 0) max_parent = 0.0f;
      for (uint32_t c = gr.first_cluster; c < gr.first_cluster + gr.cluster_count; ++c) {
        const ClusterRecord& r = clusters_[c];
        max_parent = std::max(max_parent, r.parent_error);
        if (!sameSphere(gc, gr.lod_radius, v3(r.lod_center), r.lod_radius, gr_slack))
          return fail("errors",
                      clusterName(c) + " produced by group " + str(g) + " has lod sphere " +
                          vec(v3(r.lod_center)) + " r " + num(r.lod_radius) + ", not its group's " +
                          vec(gc) + " r " + num(gr.lod_radius),
                      clusterAt(c) + offsetof(ClusterRecord, lod_center), c, g);
      }
      if (max_parent != gr.max_parent_error)
        return fail("errors",
                    "group " + str(g) + " max parent error " + num(gr.max_parent_error) +
                        " but its produced clusters' largest parent error is " + num(max_parent),
                    groupAt(g) + offsetof(GroupRecord, max_parent_error), kNone, g);
      for (uint32_t c : children(g)) {
        const ClusterRecord& r = clusters_[c];
        if (!(r.error <= gr.error))
          return fail("errors",
                      "group " + str(g) + " error " + num(gr.error) + " is below its child " +
                          clusterName(c) + " error " + num(r.error) + " (not monotone)",
                      groupAt(g) + offsetof(GroupRecord, error), c, g);
        if (!sameSphere(gc, gr.lod_radius, v3(r.parent_lod_center), r.parent_lod_radius, gr_slack))
          return fail("errors",
                      clusterName(c) + " child of group " + str(g) + " has parent lod sphere " +
                          vec(v3(r.parent_lod_center)) + " r " + num(r.parent_lod_radius) +
                          ", not its parent group's " + vec(gc) + " r " + num(gr.lod_radius),
                      clusterAt(c) + offsetof(ClusterRecord, parent_lod_center), c, g);
      }
      ++report_.counts.groups;
      updateProgress(progress_, g + 1);
      if (cancelled()) return false;
    }
    for (uint32_t c = 0; c < clusters_.size(); ++c) {
      const ClusterRecord& r = clusters_[c];
      if (r.parent_group == kNone) continue;
      // The projected error grows toward the roots only if the parent sphere holds the child's.
      const glm::dvec3 pc = v3(r.parent_lod_center), lc = v3(r.lod_center);
      const double slack = roundSlack(glm::length(pc) + r.parent_lod_radius);
      if (!sphereContains(pc, r.parent_lod_radius, lc, r.lod_radius, slack))
        return fail("errors",
                    clusterName(c) + " lod sphere " + vec(lc) + " r " + num(r.lod_radius) +
                        " is not inside its parent lod sphere " + vec(pc) + " r " +
                        num(r.parent_lod_radius) + " (projected error not monotone; outside by " +
                        num(glm::length(lc - pc) + r.lod_radius - r.parent_lod_radius) + " m)",
                    clusterAt(c) + offsetof(ClusterRecord, parent_lod_center), c, r.parent_group);
      if (c % 4096 == 0) {
        updateProgress(progress_, groups_.size() + c);
        if (cancelled()) return false;
      }
    }
    endStage(progress_);
    return true;
  }

  // Decodes the mesh clusters of `ids` page by page (each page loaded once) and hands each to
  // `fn`, which returns false to stop. Decoding failures become "decode" failures.
  bool forEachDecoded(std::vector<uint32_t> ids,
                      const std::function<bool(uint32_t, const DecodedCluster&)>& fn) {
    std::sort(ids.begin(), ids.end(), [&](uint32_t a, uint32_t b) {
      return clusters_[a].page != clusters_[b].page ? clusters_[a].page < clusters_[b].page : a < b;
    });
    std::vector<uint8_t> scratch;
    std::span<const uint8_t> raw;
    uint32_t loaded = kNone;
    DecodedCluster decoded;
    for (uint32_t c : ids) {
      const ClusterRecord& r = clusters_[c];
      if (r.page != loaded) {
        try {
          raw = view_.loadPage(r.page, scratch);
        } catch (const FormatError& e) {
          return fail("decode", e.reason(), e.position(), c, kNone, r.page);
        }
        loaded = r.page;
      }
      const DecodeStatus status =
          decodeCluster(raw.subspan(r.page_offset, r.encoded_bytes), view_.positionStepM(),
                        static_cast<uint32_t>(view_.objects().size()), decoded);
      if (!status.ok())
        return fail("decode",
                    clusterName(c) + " at raw byte " + str(r.page_offset + status.offset) +
                        " of page " + str(r.page) + ": " + status.error,
                    pageAt(r.page), c, kNone, r.page);
      if (decoded.vertices.size() != r.vertex_count ||
          decoded.triangle_objects.size() != r.triangle_count)
        return fail("decode",
                    clusterName(c) + " record says " + str(r.vertex_count) + " vertices, " +
                        str(r.triangle_count) + " triangles; its geometry has " +
                        str(decoded.vertices.size()) + ", " + str(decoded.triangle_objects.size()),
                    clusterAt(c) + offsetof(ClusterRecord, triangle_count), c);
      if (decoded.triangle_objects.front() != r.object_min ||
          decoded.triangle_objects.back() != r.object_max)
        return fail("decode",
                    clusterName(c) + " record object range [" + str(r.object_min) + ", " +
                        str(r.object_max) + "] but its triangles use [" +
                        str(decoded.triangle_objects.front()) + ", " +
                        str(decoded.triangle_objects.back()) + "]",
                    clusterAt(c) + offsetof(ClusterRecord, object_min), c);
      if (!fn(c, decoded)) return false;
    }
    return true;
  }

  // (d) Geometry inside its bounds, bounds inside their group's and the header's.
  bool bounds() {
    beginStage(progress_, "bounds", clusters_.size());
    const pkg::PackageHeader& h = view_.header();
    const glm::dvec3 h_lo = v3(h.bounds_min), h_hi = v3(h.bounds_max);
    const double h_slack = roundSlack(glm::length(h_hi) + glm::length(h_lo));
    auto boxCheck = [&](uint32_t c, const glm::dvec3& lo, const glm::dvec3& hi,
                        const glm::dvec3& box_lo, const glm::dvec3& box_hi, double slack,
                        const std::string& whose, uint64_t offset, uint32_t g) {
      if (boxContains(box_lo, box_hi, lo, slack) && boxContains(box_lo, box_hi, hi, slack))
        return true;
      return fail("bounds",
                  clusterName(c) + " box " + vec(lo) + "-" + vec(hi) + " is not inside " + whose +
                      " box " + vec(box_lo) + "-" + vec(box_hi),
                  offset, c, g);
    };
    for (uint32_t c = 0; c < clusters_.size(); ++c) {
      const ClusterRecord& r = clusters_[c];
      const glm::dvec3 lo = v3(r.aabb_min), hi = v3(r.aabb_max);
      if (!boxCheck(c, lo, hi, h_lo, h_hi, h_slack, "the header's",
                    offsetof(pkg::PackageHeader, bounds_min), kNone))
        return false;
      // A group's box holds its produced clusters (its children when it produced none).
      uint32_t g = r.group;
      if (g == kNone && r.parent_group != kNone && groups_[r.parent_group].cluster_count == 0)
        g = r.parent_group;
      if (g != kNone) {
        const GroupRecord& gr = groups_[g];
        const glm::dvec3 g_lo = v3(gr.aabb_min), g_hi = v3(gr.aabb_max);
        if (!boxCheck(c, lo, hi, g_lo, g_hi, roundSlack(glm::length(g_lo) + glm::length(g_hi)),
                      "group " + str(g) + "'s", groupAt(g) + offsetof(GroupRecord, aabb_min), g))
          return false;
      }
      if (!isMesh(r) && !instancesInside(c)) return false;
    }
    std::vector<uint32_t> mesh;
    for (uint32_t c = 0; c < clusters_.size(); ++c)
      if (isMesh(clusters_[c])) mesh.push_back(c);
    uint64_t done = 0;
    const auto objects = view_.objects();
    struct Worst {
      double excess = 0.0;  // metres outside the object's box (float rounding allowed for)
      uint32_t cluster = kNone, triangle = 0, object = 0;
      glm::dvec3 position{0.0};
    } worst;
    uint32_t max_shift = 0;
    bool ok = forEachDecoded(std::move(mesh), [&](uint32_t c, const DecodedCluster& d) {
      const ClusterRecord& r = clusters_[c];
      const glm::dvec3 lo = v3(r.aabb_min), hi = v3(r.aabb_max), center = v3(r.center);
      const double tol = tolerance(d.shift) + roundSlack(glm::length(center) + r.radius);
      for (size_t v = 0; v < d.positions.size(); ++v) {
        const glm::dvec3 p(d.positions[v]);
        if (!boxContains(lo, hi, p, tol))
          return fail("bounds",
                      clusterName(c) + " vertex " + str(v) + " at " + vec(p) +
                          " lies outside the cluster box " + vec(lo) + "-" + vec(hi) +
                          " by more than the quantization error " + num(tol) + " m",
                      clusterAt(c) + offsetof(ClusterRecord, aabb_min), c);
        const double d_m = glm::length(p - center);
        if (d_m > r.radius + tol)
          return fail("bounds",
                      clusterName(c) + " vertex " + str(v) + " at " + vec(p) + " is " + num(d_m) +
                          " m from the sphere centre, radius " + num(r.radius) + " (+" + num(tol) +
                          ")",
                      clusterAt(c), c);
      }
      if (r.group != kNone) {
        // The group's lod sphere holds its produced clusters' geometry (not necessarily their
        // bounding spheres, which need not be minimal).
        const GroupRecord& gr = groups_[r.group];
        const glm::dvec3 gc = v3(gr.lod_center);
        const double g_tol = tolerance(d.shift) + roundSlack(glm::length(gc) + gr.lod_radius);
        for (size_t v = 0; v < d.positions.size(); ++v) {
          const double d_m = glm::length(glm::dvec3(d.positions[v]) - gc);
          if (d_m > gr.lod_radius + g_tol)
            return fail("bounds",
                        clusterName(c) + " vertex " + str(v) + " at " +
                            vec(glm::dvec3(d.positions[v])) + " is " + num(d_m) +
                            " m from its group " + str(r.group) + "'s lod sphere centre " +
                            vec(gc) + ", radius " + num(gr.lod_radius),
                        groupAt(r.group), c, r.group);
        }
      }
      report_.counts.vertices += d.positions.size();
      max_shift = std::max(max_shift, d.shift);
      if (r.level == 0) {
        // Objects' boxes are of their level-0 input geometry. A packer may snap a shared vertex
        // to the grid of the coarsest cluster using it, so how far outside is judged after the
        // pass, against the coarsest shift of the package; keep the worst vertex.
        for (size_t t = 0; t < d.triangle_objects.size(); ++t) {
          const pkg::ObjectRecord& o = objects[d.triangle_objects[t]];
          const glm::dvec3 o_lo = v3(o.aabb_min), o_hi = v3(o.aabb_max);
          for (int k = 0; k < 3; ++k) {
            const glm::dvec3 p(d.positions[d.indices[3 * t + k]]);
            const glm::dvec3 out = glm::max(o_lo - p, p - o_hi);
            const double excess =
                std::max({out.x, out.y, out.z}) - roundSlack(glm::length(o_lo) + glm::length(o_hi));
            if (excess > worst.excess) worst = {excess, c, uint32_t(t), d.triangle_objects[t], p};
          }
        }
      }
      ++report_.counts.clusters;
      updateProgress(progress_, ++done);
      return !cancelled();
    });
    if (!ok) return false;
    const double object_tol = tolerance(max_shift);
    if (worst.excess > object_tol) {
      const pkg::ObjectRecord& o = objects[worst.object];
      return fail("bounds",
                  clusterName(worst.cluster) + " triangle " + str(worst.triangle) + " of object " +
                      str(worst.object) + " has a vertex at " + vec(worst.position) + " " +
                      num(worst.excess) + " m outside the object's box " + vec(v3(o.aabb_min)) +
                      "-" + vec(v3(o.aabb_max)) + " (allowed: the quantization error " +
                      num(object_tol) + " m of the coarsest shift " + str(max_shift) + ")",
                  recordAt(SectionType::Objects, worst.object, sizeof(pkg::ObjectRecord)),
                  worst.cluster);
    }
    report_.counts.pages = pages_.size();
    endStage(progress_);
    return true;
  }

  bool instancesInside(uint32_t c) {
    const ClusterRecord& r = clusters_[c];
    const glm::dvec3 lo = v3(r.aabb_min), hi = v3(r.aabb_max), center = v3(r.center);
    const double slack =
        roundSlack(glm::length(lo) + glm::length(hi) + r.radius) + options_.position_slack_m;
    for (uint32_t i = r.instance_first; i < r.instance_first + r.instance_count; ++i) {
      glm::vec3 i_lo, i_hi;
      instanceBounds(view_.instances()[i], view_.profilePoints(), i_lo, i_hi);
      for (int k = 0; k < 8; ++k) {
        const glm::dvec3 p(k & 1 ? i_hi.x : i_lo.x, k & 2 ? i_hi.y : i_lo.y,
                           k & 4 ? i_hi.z : i_lo.z);
        if (!boxContains(lo, hi, p, slack) || glm::length(p - center) > r.radius + slack)
          return fail("bounds",
                      "parametric " + clusterName(c) + " instance " + str(i) + " box " +
                          vec(glm::dvec3(i_lo)) + "-" + vec(glm::dvec3(i_hi)) +
                          " is not inside the cluster box " + vec(lo) + "-" + vec(hi) +
                          " and sphere r " + num(r.radius),
                      recordAt(SectionType::Instances, i, sizeof(pkg::InstanceRecord)),
                      c);
      }
      ++report_.counts.instances;
    }
    ++report_.counts.clusters;
    return true;
  }

  // (e) Crack-freedom, level by level (docs/verify.md, "Cracks"). The front of level L is what
  // the groups of level L were simplified against: every cluster of level <= L not yet replaced
  // by a group below L (children of a group at L, groups above L, or roots).
  bool cracks() {
    const uint32_t levels = view_.header().level_count;
    beginStage(progress_, "cracks", groups_.size());
    std::vector<std::vector<uint32_t>> groups_by_level(levels);
    for (uint32_t g = 0; g < groups_.size(); ++g) groups_by_level[groups_[g].level].push_back(g);
    std::vector<std::vector<uint32_t>> mesh_by_level(levels);
    for (uint32_t c = 0; c < clusters_.size(); ++c)
      if (isMesh(clusters_[c])) mesh_by_level[clusters_[c].level].push_back(c);
    uint64_t done = 0;
    const std::vector<uint32_t> none;
    for (uint32_t level = 0; level < levels; ++level) {
      if (groups_by_level[level].empty()) continue;
      std::vector<uint32_t> front;
      for (uint32_t l = 0; l <= level; ++l)
        for (uint32_t c : mesh_by_level[l]) {
          const uint32_t parent = clusters_[c].parent_group;
          if (parent == kNone || groups_[parent].level >= level) front.push_back(c);
        }
      // A group of the top level can only have produced nothing (the view checks levels).
      if (!crackLevel(level, groups_by_level[level], front,
                      level + 1 < levels ? mesh_by_level[level + 1] : none))
        return false;
      done += groups_by_level[level].size();
      updateProgress(progress_, done);
      if (cancelled()) return false;
    }
    endStage(progress_);
    return true;
  }

  bool crackLevel(uint32_t level, const std::vector<uint32_t>& level_groups,
                  const std::vector<uint32_t>& fine, const std::vector<uint32_t>& coarse) {
    // Decode both levels, keeping positions until the welder's cell size is known.
    struct Geometry {
      std::vector<glm::vec3> positions;
      std::vector<uint32_t> indices;  // into positions, then rewritten to welded ids
      uint32_t shift = 0;
    };
    std::unordered_map<uint32_t, Geometry> geometry;
    uint32_t max_shift = 0;
    auto keep = [&](uint32_t c, const DecodedCluster& d) {
      Geometry& g = geometry[c];
      g.positions = d.positions;
      g.indices = d.indices;
      g.shift = d.shift;
      max_shift = std::max(max_shift, d.shift);
      return true;
    };
    if (!forEachDecoded(fine, keep) || !forEachDecoded(coarse, keep)) return false;
    Welder welder(view_.positionStepM(), max_shift, options_.position_slack_m);
    std::vector<uint64_t> keys;
    EdgeList local;
    std::vector<uint8_t> border;
    auto weld = [&](const std::vector<uint32_t>& ids) {
      for (uint32_t c : ids) {
        Geometry& g = geometry[c];
        // Border vertices of the cluster, on its own (unwelded) indices.
        keys.clear();
        appendEdges(g.indices, keys);
        countEdges(keys, local);
        border.assign(g.positions.size(), 0);
        for (const auto& [edge, count] : local)
          if (count != 2) border[uint32_t(edge >> 32)] = border[uint32_t(edge)] = 1;
        std::vector<uint32_t> welded(g.positions.size());
        for (size_t v = 0; v < welded.size(); ++v)
          welded[v] = welder.add(g.positions[v], g.shift, border[v] != 0);
        for (uint32_t& i : g.indices) i = welded[i];
        g.positions = {};
      }
    };
    weld(fine);
    weld(coarse);

    // For every edge on the border of some cluster of the front: how many such clusters have it
    // on their border. An edge on the border of a child and of a front cluster outside the group
    // is one the group shares with its neighbours.
    EdgeCounts border_clusters;
    auto clusterEdges = [&](uint32_t c, EdgeList& out) {
      keys.clear();
      appendEdges(geometry[c].indices, keys);
      countEdges(keys, out);
    };
    for (uint32_t c : fine) {
      clusterEdges(c, local);
      for (const auto& [edge, count] : local)
        if (count != 2) ++border_clusters[edge];
    }

    // Per group: child edges with their triangle count and the number of children having them
    // on their border; produced edges with their triangle count.
    struct ChildEdge {
      uint64_t edge;
      uint32_t triangles, borders;
    };
    std::vector<ChildEdge> child_edges, merged;
    std::vector<uint32_t> rim_vertices, shared_vertices;
    EdgeList produced_counts;
    for (uint32_t g : level_groups) {
      const GroupRecord& gr = groups_[g];
      child_edges.clear();
      for (uint32_t c : children(g)) {
        if (!isMesh(clusters_[c])) continue;
        clusterEdges(c, local);
        for (const auto& [edge, count] : local)
          child_edges.push_back({edge, count, count != 2 ? 1u : 0u});
      }
      std::sort(child_edges.begin(), child_edges.end(),
                [](const ChildEdge& x, const ChildEdge& y) { return x.edge < y.edge; });
      merged.clear();
      for (const ChildEdge& e : child_edges) {
        if (!merged.empty() && merged.back().edge == e.edge) {
          merged.back().triangles += e.triangles;
          merged.back().borders += e.borders;
        } else {
          merged.push_back(e);
        }
      }
      keys.clear();
      for (uint32_t c = gr.first_cluster; c < gr.first_cluster + gr.cluster_count; ++c)
        if (isMesh(clusters_[c])) appendEdges(geometry[c].indices, keys);
      countEdges(keys, produced_counts);
      auto childCount = [&](uint64_t edge) -> uint32_t {
        auto it =
            std::lower_bound(merged.begin(), merged.end(), edge,
                             [](const ChildEdge& x, uint64_t value) { return x.edge < value; });
        return it != merged.end() && it->edge == edge ? it->triangles : 0;
      };
      auto edgeText = [&](uint64_t edge) {
        return vec(glm::dvec3(welder.position(uint32_t(edge >> 32)))) + "-" +
               vec(glm::dvec3(welder.position(uint32_t(edge))));
      };
      // Vertices on the children's rims (edges not used exactly twice) and on the shared border.
      rim_vertices.clear();
      shared_vertices.clear();
      for (const ChildEdge& e : merged)
        if (e.triangles != 2) {
          rim_vertices.push_back(uint32_t(e.edge >> 32));
          rim_vertices.push_back(uint32_t(e.edge));
        }
      // The border shared with the neighbours is kept, triangle for triangle.
      for (const ChildEdge& e : merged) {
        if (e.borders == 0) continue;
        const uint64_t edge = e.edge;
        auto it = border_clusters.find(edge);
        const uint32_t outside = it == border_clusters.end() ? 0 : it->second - e.borders;
        if (outside == 0) continue;
        shared_vertices.push_back(uint32_t(edge >> 32));
        shared_vertices.push_back(uint32_t(edge));
        ++report_.counts.border_edges;
        const uint32_t before = e.triangles;
        const uint32_t after = countOf(produced_counts, edge);
        if (before != after)
          return fail("cracks",
                      "group " + str(g) + " (level " + str(level) + "): border edge " +
                          edgeText(edge) + " shared with " + str(outside) +
                          " other cluster(s) of the level-" + str(level) + " front is used by " +
                          str(before) + " child triangle(s) but " + str(after) +
                          " produced triangle(s): the locked border moved (crack)",
                      groupAt(g), kNone, g);
      }
      // No hole: every boundary edge of the produced clusters was a boundary edge of the
      // children, or outlines one of their openings anew (both ends on a child rim edge, not
      // both on the shared border), so the coarse level shows no opening inside a surface that
      // the fine one did not have.
      auto sortUnique = [](std::vector<uint32_t>& v) {
        std::sort(v.begin(), v.end());
        v.erase(std::unique(v.begin(), v.end()), v.end());
      };
      sortUnique(rim_vertices);
      sortUnique(shared_vertices);
      auto in = [](const std::vector<uint32_t>& v, uint32_t x) {
        return std::binary_search(v.begin(), v.end(), x);
      };
      auto outlinesOpening = [&](uint64_t edge) {
        const uint32_t a = uint32_t(edge >> 32), b = uint32_t(edge);
        return in(rim_vertices, a) && in(rim_vertices, b) &&
               !(in(shared_vertices, a) && in(shared_vertices, b));
      };
      for (const auto& [edge, count] : produced_counts) {
        if (count != 1) continue;
        ++report_.counts.boundary_edges;
        const uint32_t in_children = childCount(edge);
        if (in_children != 1 && !outlinesOpening(edge))
          return fail("cracks",
                      "group " + str(g) + " (level " + str(level) + "): produced clusters have " +
                          "boundary edge " + edgeText(edge) + " that the children " +
                          (in_children == 0 ? std::string("do not have")
                                            : "use " + str(in_children) + " times") +
                          " (new hole or moved border)",
                      groupAt(g), kNone, g);
      }
    }
    return true;
  }

  const PackageView& view_;
  const CheckOptions& options_;
  Progress* progress_;
  std::span<const ClusterRecord> clusters_;
  std::span<const GroupRecord> groups_;
  std::span<const PageRecord> pages_;
  std::vector<uint32_t> child_begin_, children_;
  CheckReport report_;
};

}  // namespace

CheckReport checkPackage(const PackageView& view, const CheckOptions& options, Progress* progress) {
  return Checker(view, options, progress).run();
}

}  // namespace tw
