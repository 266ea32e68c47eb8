// Rows of equal boxes end to end. See box_rows.h.
#include "box_rows.h"

#include <algorithm>
#include <cmath>

#include "covered_box_faces.h"

namespace tw {
namespace {

// Whether an instance's profile lies within the profile table (the view checks packages, and a
// row never reads past the table whatever it is given).
bool profileInRange(const pkg::InstanceRecord& in, size_t points) {
  return in.profile_first <= points && in.profile_count <= points - in.profile_first;
}

bool isBox(const pkg::InstanceRecord& in) { return in.type == uint32_t(pkg::PrimitiveType::Box); }

// Equal members: the same type, transform columns, parameters and flags (but for a box's covered
// faces), and for extrusions the same profile point for point.
bool sameShape(const pkg::InstanceRecord& a, const pkg::InstanceRecord& b,
               std::span<const glm::vec2> profile_points) {
  constexpr uint32_t kOwnFlags = ~pkg::kInstanceCoveredFaces;
  if (a.type != b.type || !std::equal(a.linear, a.linear + 9, b.linear) ||
      !std::equal(a.params, a.params + 6, b.params) || (a.flags & kOwnFlags) != (b.flags & kOwnFlags) ||
      a.profile_count != b.profile_count)
    return false;
  if (a.profile_first == b.profile_first || a.profile_count == 0) return true;
  const auto points = [&](const pkg::InstanceRecord& in) {
    return profile_points.subspan(in.profile_first, in.profile_count);
  };
  const auto pa = points(a), pb = points(b);
  return std::equal(pa.begin(), pa.end(), pb.begin());
}

// Whether `next` lies one member length from `at` along canonical axis `axis`: a box's centre,
// the face between them covered on both sides; an extrusion's start (along its own axis, 2, by
// its height).
bool follows(const pkg::InstanceRecord& at, const pkg::InstanceRecord& next, int axis) {
  double step = 0.0;
  if (isBox(at)) {
    const uint8_t at_faces = coveredFaces(at.flags), next_faces = coveredFaces(next.flags);
    if (!((at_faces >> (2 * axis + 1)) & 1u) || !((next_faces >> (2 * axis)) & 1u)) return false;
    step = 2.0 * double(at.params[axis]);
  } else {
    if (axis != 2) return false;
    step = double(at.params[0]);
  }
  for (int k = 0; k < 3; ++k) {
    const double expected = double(at.origin[k]) + double(at.linear[3 * axis + k]) * step;
    if (std::abs(double(next.origin[k]) - expected) > kFaceToleranceM) return false;
  }
  return true;
}

// The rows among `boxes` (Box instances with a covered face, and extrusions), each in cluster
// `cluster_of`.
void rowsOf(std::span<const pkg::InstanceRecord> instances, std::span<const glm::vec2> profile_points,
            std::vector<uint32_t>& boxes, std::span<const uint32_t> cluster_of,
            std::vector<BoxRow>& out) {
  std::sort(boxes.begin(), boxes.end(), [&](uint32_t a, uint32_t b) {
    return instances[a].object != instances[b].object ? instances[a].object < instances[b].object : a < b;
  });
  // next[k]: the position in `boxes` of the box that follows boxes[k] along axis_of[k], or none.
  constexpr uint32_t kNone = ~0u;
  std::vector<uint32_t> next(boxes.size(), kNone);
  std::vector<uint8_t> axis_of(boxes.size(), 0), has_previous(boxes.size(), 0);
  for (size_t k = 0; k + 1 < boxes.size(); ++k) {
    const pkg::InstanceRecord& at = instances[boxes[k]];
    const pkg::InstanceRecord& after = instances[boxes[k + 1]];
    if (after.object != at.object + 1 || !sameShape(at, after, profile_points)) continue;
    for (int axis = 0; axis < 3; ++axis)
      if (follows(at, after, axis)) {
        next[k] = uint32_t(k + 1);
        axis_of[k] = uint8_t(axis);
        break;
      }
  }
  // A row keeps one axis: a link along another starts a row of its own.
  for (size_t k = 1; k < boxes.size(); ++k)
    if (next[k] != kNone && next[k - 1] == k && axis_of[k - 1] != axis_of[k]) next[k] = kNone;
  for (size_t k = 0; k < boxes.size(); ++k)
    if (next[k] != kNone) has_previous[next[k]] = 1;
  auto emit = [&](BoxRow& row) {
    row.cluster = cluster_of[row.instances.front()];
    row.member_clusters.clear();
    for (uint32_t i : row.instances) row.member_clusters.push_back(cluster_of[i]);
    const pkg::InstanceRecord& head = instances[row.instances.front()];
    const float n = float(row.instances.size());
    pkg::InstanceRecord& r = row.record;
    r = head;
    if (!isBox(head)) {  // an extrusion from the head's start, n heights long
      r.params[0] = head.params[0] * n;
      out.push_back(row);
      return;
    }
    uint8_t sides = 0x3f;
    for (uint32_t i : row.instances) sides &= coveredFaces(instances[i].flags);
    const pkg::InstanceRecord& tail = instances[row.instances.back()];
    const int a = row.axis;
    const uint8_t ends = uint8_t(1u << (2 * a)) | uint8_t(1u << (2 * a + 1));
    const uint8_t covered = uint8_t((sides & ~ends) | (coveredFaces(head.flags) & (1u << (2 * a))) |
                                    (coveredFaces(tail.flags) & (1u << (2 * a + 1))));
    for (int k = 0; k < 3; ++k)  // the centre of the row: halfway from the head's to the tail's
      r.origin[k] = 0.5f * (head.origin[k] + tail.origin[k]);
    r.params[a] = head.params[a] * n;
    r.flags = (head.flags & ~pkg::kInstanceCoveredFaces) | coveredFaceInstanceFlags(covered);
    out.push_back(row);
  };
  for (size_t k = 0; k < boxes.size(); ++k) {
    if (has_previous[k] || next[k] == kNone) continue;
    BoxRow row;
    row.axis = axis_of[k];
    for (uint32_t at = uint32_t(k); at != kNone; at = next[at]) {
      if (row.instances.size() == kMaxBoxRowMembers) {
        emit(row);
        row.instances.clear();
      }
      row.instances.push_back(boxes[at]);
    }
    if (row.instances.size() >= 2) emit(row);
  }
}

}  // namespace

std::vector<BoxRow> findBoxRows(std::span<const pkg::InstanceRecord> instances,
                                std::span<const pkg::ClusterRecord> clusters,
                                std::span<const glm::vec2> profile_points) {
  constexpr uint32_t kNoCluster = ~0u;
  std::vector<uint32_t> cluster_of(instances.size(), kNoCluster);
  for (uint32_t c = 0; c < clusters.size(); ++c) {
    const pkg::ClusterRecord& r = clusters[c];
    if (r.kind != uint8_t(pkg::ClusterKind::Parametric) || r.instance_first > instances.size() ||
        r.instance_count > instances.size() - r.instance_first)
      continue;
    for (uint32_t i = r.instance_first; i < r.instance_first + r.instance_count; ++i) cluster_of[i] = c;
  }
  std::vector<uint32_t> boxes;
  for (uint32_t i = 0; i < instances.size(); ++i)
    if (cluster_of[i] != kNoCluster &&
        ((isBox(instances[i]) && coveredFaces(instances[i].flags)) ||
         (instances[i].type == uint32_t(pkg::PrimitiveType::Extrusion) &&
          profileInRange(instances[i], profile_points.size()))))
      boxes.push_back(i);
  std::vector<BoxRow> rows;
  rowsOf(instances, profile_points, boxes, cluster_of, rows);
  std::sort(rows.begin(), rows.end(), [](const BoxRow& a, const BoxRow& b) {
    return a.instances.front() < b.instances.front();
  });
  return rows;
}

}  // namespace tw
