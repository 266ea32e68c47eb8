// Expanding one visible parametric instance into a batch. See parametric_instance_expansion.h.
#include "parametric_instance_expansion.h"

#include <algorithm>
#include <cmath>

#include "parametric_meshes.h"

namespace tw::instance_forms {

namespace {

// A unit-mesh point `q` of a primitive with parameters `p`, in its canonical frame (scene.h).
glm::vec3 shapedPoint(pkg::PrimitiveType type, const float* p, const glm::vec4& q) {
  const float rim = std::min(q.w, 1.0f);  // tubes: 0 at a cap centre
  switch (type) {
    case pkg::PrimitiveType::Cylinder: return {rim * p[0] * q.x, rim * p[0] * q.y, q.z * p[1]};
    case pkg::PrimitiveType::Cone: {
      const float r = rim * (p[0] + (p[1] - p[0]) * q.z);
      return {r * q.x, r * q.y, q.z * p[2]};
    }
    case pkg::PrimitiveType::Sphere: return p[0] * glm::vec3(q.z * q.x, q.z * q.y, q.w);
    case pkg::PrimitiveType::TorusSegment: {
      const float a = q.x * p[2], rho = p[0] + p[1] * q.y;
      return {rho * std::cos(a), rho * std::sin(a), p[1] * q.z};
    }
    case pkg::PrimitiveType::Box: return glm::vec3(q) * glm::vec3(p[0], p[1], p[2]);
    default: return glm::vec3(0.0f);  // profiles are drawn in the box frame only
  }
}

// The surface normal at unit-mesh point `q` in the canonical frame (not normalized for cones);
// zero where the surface is flat there (caps, boxes) or for lines and points.
glm::vec3 shapedNormal(pkg::PrimitiveType type, Shape shape, const float* p, const glm::vec4& q) {
  switch (shape) {
    case Shape::Tube:
      if (q.w != 1.0f) return glm::vec3(0.0f);
      if (type == pkg::PrimitiveType::Cone) {
        const glm::vec2 c = glm::vec2(q) / std::max(glm::length(glm::vec2(q)), 1e-30f);
        return {p[2] * c.x, p[2] * c.y, p[0] - p[1]};
      }
      return {q.x, q.y, 0.0f};
    case Shape::Sphere: return {q.z * q.x, q.z * q.y, q.w};
    case Shape::Torus: {
      const float a = q.x * p[2];
      return {q.y * std::cos(a), q.y * std::sin(a), q.z};
    }
    default: return glm::vec3(0.0f);
  }
}

}  // namespace

OwnedUnitMesh makeUnitMesh(Shape shape, uint32_t a, uint32_t b) {
  UnitMeshBuilder builder;
  UnitMesh m;
  switch (shape) {
    case Shape::Tube: m = builder.tube(kLevels[a]); break;
    case Shape::Sphere: m = builder.sphere(kLevels[a], kLevels[b]); break;
    case Shape::Torus: m = builder.torus(kLevels[a], kLevels[b]); break;
    case Shape::Box: m = builder.box(); break;
    case Shape::Point:  // the box centre (appendPoint)
    case Shape::Profile:
    case Shape::Lathe:
    case Shape::Ribbon:
    case Shape::None: break;  // never expanded from a unit mesh
  }
  m.vertex_count = static_cast<uint32_t>(builder.shapes.size()) - m.base_vertex;
  OwnedUnitMesh owned;
  owned.mesh = m;
  owned.shapes = std::move(builder.shapes);
  owned.indices = std::move(builder.indices);
  return owned;
}

void InstanceBatch::clear() {
  vertices.clear();
  beam_vertices.clear();
  row_vertices.clear();
  for (auto& list : indices) list.clear();
}

void InstanceBatch::append(const InstanceBatch& other) {
  const auto base = static_cast<uint32_t>(vertices.size());
  const auto beam_base = static_cast<uint32_t>(beam_vertices.size());
  const auto row_base = static_cast<uint32_t>(row_vertices.size());
  vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
  beam_vertices.insert(beam_vertices.end(), other.beam_vertices.begin(), other.beam_vertices.end());
  row_vertices.insert(row_vertices.end(), other.row_vertices.begin(), other.row_vertices.end());
  for (uint32_t batch = 0; batch < kBatchCount; ++batch) {
    const uint32_t offset = batch == kBeams ? beam_base : batch == kRows ? row_base : base;
    for (uint32_t index : other.indices[batch]) indices[batch].push_back(offset + index);
  }
}

size_t InstanceBatch::primitives() const {
  size_t triangle_indices = 0;
  for (uint32_t batch = 0; batch < kBatchCount; ++batch)
    if (batch != kPoints) triangle_indices += indices[batch].size();
  return indices[kPoints].size() + triangle_indices / 3;
}

void appendSurface(InstanceBatch& batch, const pkg::InstanceRecord& in,
                   std::span<const glm::vec2> profile_points, const InstanceBounds& b,
                   const glm::vec3& anchor_eye, const Form& f, const OwnedUnitMesh& unit) {
  std::vector<SmoothVertex>& vertices = batch.vertices;
  const UnitMesh& mesh = unit.mesh;
  const glm::mat3 linear = instanceLinear(in);
  const uint32_t base = static_cast<uint32_t>(vertices.size());
  const uint32_t vertex_count = mesh.vertex_count;
  if (f.box_frame) {
    glm::vec3 lo, hi;
    if (!instanceLocalBox(in, profile_points, lo, hi)) return;
    const glm::vec3 centre = anchor_eye + b.centre, half = 0.5f * (hi - lo);
    const glm::mat3 half_axes(linear[0] * half.x, linear[1] * half.y, linear[2] * half.z);
    for (uint32_t v = 0; v < vertex_count; ++v)
      vertices.push_back(
          {centre + half_axes * glm::vec3(unit.shapes[mesh.base_vertex + v]), in.object, 0u});
  } else {
    const glm::vec3 origin = anchor_eye + b.origin;
    const auto type = static_cast<pkg::PrimitiveType>(in.type);
    const glm::mat3 normal_matrix = normalMatrix(linear);  // scale normalized away below
    for (uint32_t v = 0; v < vertex_count; ++v) {
      const glm::vec4& q = unit.shapes[mesh.base_vertex + v];
      const glm::vec3 n = normal_matrix * shapedNormal(type, f.shape, in.params, q);
      const float length = glm::length(n);
      vertices.push_back({origin + linear * shapedPoint(type, in.params, q), in.object,
                          packNormal(length > 1e-20f ? n / length : glm::vec3(0.0f))});
    }
  }
  const uint32_t count = f.capped ? mesh.all_indices : mesh.side_indices;
  std::vector<uint32_t>& out = batch.indices[f.batch];
  const uint32_t* unit_indices = unit.indices.data() + mesh.first_index;
  // A box's faces that another box's face covers are left out, and a thin plate's rims
  // (Form::thin_faces): the unit box holds two triangles a face, in the bits' order.
  const uint32_t covered = f.shape == Shape::Box ? uint32_t(b.covered_faces | f.thin_faces) : 0u;
  auto face_covered = [&](uint32_t k) { return ((covered >> (k / 6)) & 1u) != 0; };
  if (f.batch == kTwoSided || f.batch == kPoints) {
    // Two-sided triangles go out wound counter-clockwise seen from outside, a mirrored
    // instance's turned, so a shader can tell the inside of a solid that a section cut open by
    // gl_FrontFacing where the vertices carry no normal (a box's flat faces).
    const bool turn = f.batch == kTwoSided && (b.flags & kMirrored) != 0;
    if (!covered && !turn) {
      for (uint32_t k = 0; k < count; ++k) out.push_back(base + unit_indices[k]);
      return;
    }
    for (uint32_t k = 0; k + 2 < count; k += 3)
      if (!covered || !face_covered(k))
        out.insert(out.end(), {base + unit_indices[k], base + unit_indices[turn ? k + 2 : k + 1],
                               base + unit_indices[turn ? k + 1 : k + 2]});
    return;
  }
  // A closed surface seen from outside: its back faces are left out here, where the eye-relative
  // positions make the test one dot product, instead of being shaded, set up and then culled
  // by llvmpipe on the render thread. The plane test is the rasterizer's own (the eye behind
  // the triangle's plane); edge-on triangles are kept.
  const float front = f.batch == kCullCw ? -1.0f : 1.0f;
  for (uint32_t k = 0; k + 2 < count; k += 3) {
    if (covered && face_covered(k)) continue;
    const glm::vec3& a = vertices[base + unit_indices[k]].position;
    const glm::vec3& b1 = vertices[base + unit_indices[k + 1]].position;
    const glm::vec3& c1 = vertices[base + unit_indices[k + 2]].position;
    if (front * glm::dot(glm::cross(b1 - a, c1 - a), a) > 0.0f) continue;  // eye behind it
    out.insert(out.end(),
               {base + unit_indices[k], base + unit_indices[k + 1], base + unit_indices[k + 2]});
  }
}

void appendBoxRow(InstanceBatch& batch, const pkg::InstanceRecord& row, const InstanceBounds& b,
                  const glm::vec3& anchor_eye, const Form& f, const OwnedUnitMesh& unit,
                  uint32_t members, int axis) {
  std::vector<RowVertex>& vertices = batch.row_vertices;
  const UnitMesh& mesh = unit.mesh;
  const glm::mat3 linear(row.linear[0], row.linear[1], row.linear[2], row.linear[3], row.linear[4],
                         row.linear[5], row.linear[6], row.linear[7], row.linear[8]);
  const glm::vec3 origin = anchor_eye + b.origin;
  const glm::vec3 half(row.params[0], row.params[1], row.params[2]);
  const float count = float(members);
  const uint32_t base = static_cast<uint32_t>(vertices.size());
  for (uint32_t v = 0; v < mesh.vertex_count; ++v) {
    const glm::vec3 q(unit.shapes[mesh.base_vertex + v]);
    vertices.push_back({origin + linear * (q * half), row.object, 0.5f * (q[axis] + 1.0f) * count,
                        members - 1});
  }
  const uint32_t left_out = b.covered_faces | f.thin_faces;
  const bool cull = f.batch == kCullCcw || f.batch == kCullCw;
  // Triangles go out wound counter-clockwise seen from outside, mirrored rows too, so the row
  // shader's gl_FrontFacing tells the inside of a box a section cut open.
  const bool mirrored = (b.flags & kMirrored) != 0;
  std::vector<uint32_t>& out = batch.indices[kRows];
  const uint32_t* unit_indices = unit.indices.data() + mesh.first_index;
  for (uint32_t k = 0; k + 2 < mesh.side_indices; k += 3) {
    if ((left_out >> (k / 6)) & 1u) continue;  // two triangles a face, in the bits' order
    const uint32_t ia = base + unit_indices[k];
    const uint32_t ib = base + unit_indices[mirrored ? k + 2 : k + 1];
    const uint32_t ic = base + unit_indices[mirrored ? k + 1 : k + 2];
    const glm::vec3& a = vertices[ia].position;
    if (cull && glm::dot(glm::cross(vertices[ib].position - a, vertices[ic].position - a), a) > 0.0f)
      continue;  // the eye behind it
    out.insert(out.end(), {ia, ib, ic});
  }
}

void appendLathe(InstanceBatch& batch, LatheScratch& scratch, const pkg::InstanceRecord& in,
                 std::span<const glm::vec2> profile_points, const InstanceBounds& b,
                 const glm::vec3& anchor_eye, uint32_t segments, float profile_tolerance) {
  std::vector<SmoothVertex>& vertices = batch.vertices;
  std::vector<glm::vec2>& kept = scratch.kept;
  std::vector<glm::vec2>& ring = scratch.ring;
  if (in.profile_count < 2 || in.profile_first > profile_points.size() ||
      in.profile_count > profile_points.size() - in.profile_first)
    return;
  const auto profile = profile_points.subspan(in.profile_first, in.profile_count);
  const glm::mat3 linear = instanceLinear(in);
  const float scale = std::max({glm::length(linear[0]), glm::length(linear[1]), glm::length(linear[2])});
  scratch.simplifier.simplify(profile, profile_tolerance / std::max(scale, 1e-30f), kept);
  const float sweep = in.params[0];
  const bool full = !(sweep < float(kTwoPi) * (1.0f - 1e-5f));
  const uint32_t steps =
      full ? segments
           : std::max(1u, uint32_t(std::ceil(double(segments) * double(sweep) / kTwoPi)));
  const uint32_t columns = full ? steps : steps + 1;
  ring.resize(columns);
  for (uint32_t c = 0; c < columns; ++c) {
    const double a = (full ? kTwoPi : double(sweep)) * c / steps;
    ring[c] = {static_cast<float>(std::cos(a)), static_cast<float>(std::sin(a))};
  }
  const glm::vec3 origin = anchor_eye + b.origin;
  std::vector<uint32_t>& out = batch.indices[kTwoSided];
  uint32_t previous_first = 0;
  bool previous_on_axis = false;
  for (size_t j = 0; j < kept.size(); ++j) {
    const glm::vec2 q = kept[j];
    const bool on_axis = q.x == 0.0f;
    const uint32_t first = static_cast<uint32_t>(vertices.size());
    if (on_axis) {
      vertices.push_back({origin + linear * glm::vec3(0.0f, 0.0f, q.y), in.object, 0u});
    } else {
      for (const glm::vec2& cs : ring)
        vertices.push_back({origin + linear * glm::vec3(q.x * cs.x, q.x * cs.y, q.y), in.object, 0u});
    }
    if (j > 0 && !(previous_on_axis && on_axis)) {
      for (uint32_t c = 0; c < steps; ++c) {
        const uint32_t c1 = full ? (c + 1) % columns : c + 1;
        const uint32_t a = previous_first + (previous_on_axis ? 0 : c);
        const uint32_t b1 = previous_first + (previous_on_axis ? 0 : c1);
        const uint32_t c2 = first + (on_axis ? 0 : c1), d = first + (on_axis ? 0 : c);
        if (!previous_on_axis) out.insert(out.end(), {a, b1, c2});
        if (!on_axis) out.insert(out.end(), {a, c2, d});
      }
    }
    previous_first = first;
    previous_on_axis = on_axis;
  }
}

// Its two triangles cover the pixel centres the full-resolution tube would, where a one-pixel
// line covered a whole pixel row along a tube a fifth of a pixel thick.
void appendTubeRibbon(InstanceBatch& batch, const pkg::InstanceRecord& in, const InstanceBounds& b,
                      const glm::vec3& anchor_eye, uint32_t segments) {
  std::vector<SmoothVertex>& vertices = batch.vertices;
  const glm::mat3 linear = instanceLinear(in);
  const glm::vec3 origin = anchor_eye + b.origin;
  const float* p = in.params;
  const auto type = static_cast<pkg::PrimitiveType>(in.type);
  // One cross-section: its centre, the axis direction there and the circle's two radii
  // (canonical frame).
  auto section = [&](const glm::vec3& centre, const glm::vec3& along, const glm::vec3& u,
                     const glm::vec3& w, float radius) {
    const glm::vec3 at = origin + linear * centre;
    const glm::vec3 tangent = glm::normalize(linear * along);
    const glm::vec3 to_eye = -at / std::max(glm::length(at), 1e-30f);
    glm::vec3 side = glm::cross(tangent, to_eye);
    if (glm::length(side) < 1e-6f)  // seen along its axis: a dot, any side will do
      side = glm::cross(tangent, std::abs(tangent.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0));
    side = glm::normalize(side);
    // The circle radius * (cos t * u + sin t * w), mapped, reaches this far along `side`.
    const float half = radius * std::hypot(glm::dot(linear * u, side), glm::dot(linear * w, side));
    const glm::vec3 facing = to_eye - glm::dot(to_eye, tangent) * tangent;
    const float facing_length = glm::length(facing);
    const uint32_t normal = packNormal(facing_length > 1e-6f ? facing / facing_length : to_eye);
    vertices.push_back({at - half * side, in.object, normal});
    vertices.push_back({at + half * side, in.object, normal});
  };
  const uint32_t base = static_cast<uint32_t>(vertices.size());
  uint32_t steps = 1;
  if (type == pkg::PrimitiveType::TorusSegment) {
    // Centre circle of radius p[0] in the canonical xy plane, swept p[2] radians in `segments`
    // chords that straddle the circle, as the rings do.
    const float sweep = p[2];
    steps = std::max(segments, 1u);
    const float centre_radius = p[0] * 2.0f / (1.0f + std::cos(0.5f * sweep / float(steps)));
    for (uint32_t k = 0; k <= steps; ++k) {
      const float a = sweep * float(k) / float(steps);
      const glm::vec3 radial(std::cos(a), std::sin(a), 0.0f);
      section(centre_radius * radial, {-radial.y, radial.x, 0.0f}, radial, {0.0f, 0.0f, 1.0f}, p[1]);
    }
  } else {  // cylinder (radius p[0], height p[1]) or cone (radii p[0], p[1], height p[2])
    const bool cone = type == pkg::PrimitiveType::Cone;
    const float height = cone ? p[2] : p[1];
    section({0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f}, {1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, p[0]);
    section({0.0f, 0.0f, height}, {0.0f, 0.0f, 1.0f}, {1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f},
            cone ? p[1] : p[0]);
  }
  std::vector<uint32_t>& out = batch.indices[kTwoSided];
  for (uint32_t k = 0; k < steps; ++k) {
    const uint32_t a = base + 2 * k;
    out.insert(out.end(), {a, a + 1, a + 3, a, a + 3, a + 2});
  }
}

// The fragments choose the face (parametricBeamFragmentShader). Two triangles show what the
// box's six to twelve would, but for its end faces; two bands of two, one a face, made the 50M
// plant's orbit 20 % slower (commit 1e7cbea against cff378c, 2026-11-27).
void appendBeamRibbon(InstanceBatch& batch, const pkg::InstanceRecord& in, const InstanceBounds& b,
                      const glm::vec3& anchor_eye, int axis, uint32_t members) {
  const glm::mat3 linear = instanceLinear(in);
  // The canonical box's half sizes mapped: b.size holds them in metres (half times the column's
  // length), so each column is scaled to that length.
  glm::vec3 axes[3];
  for (int k = 0; k < 3; ++k) {
    const float length = glm::length(linear[k]);
    axes[k] = length > 0.0f ? linear[k] * (b.size[k] / length) : glm::vec3(0.0f);
  }
  const glm::vec3 along = axes[axis];
  glm::vec3 u = axes[(axis + 1) % 3], w = axes[(axis + 2) % 3];
  const float along_length = glm::length(along);
  if (!(along_length > 0.0f)) return;
  const glm::vec3 tangent = along / along_length;
  const glm::vec3 centre = anchor_eye + b.centre;
  // Outward unit normals of the long faces at +u and at +w (the axes need not be orthogonal);
  // then u and w turned toward the eye, so the faces at +u and +w are the ones it sees.
  auto outward = [](const glm::vec3& n, const glm::vec3& toward) {
    const float length = glm::length(n);
    if (!(length > 0.0f)) return glm::vec3(0.0f);
    return (glm::dot(n, toward) < 0.0f ? -n : n) / length;
  };
  glm::vec3 n_u = outward(glm::cross(along, w), u), n_w = outward(glm::cross(along, u), w);
  if (glm::dot(n_u, -centre) < 0.0f) {
    u = -u;
    n_u = -n_u;
  }
  if (glm::dot(n_w, -centre) < 0.0f) {
    w = -w;
    n_w = -n_w;
  }
  const uint32_t packed_u = packNormal(n_u), packed_w = packNormal(n_w);
  std::vector<BeamVertex>& vertices = batch.beam_vertices;
  // One cross-section: across `side`, the face at +u spans the edges u - w and u + w, the face
  // at +w the edges u + w and w - u; the outer edges are the silhouette, and `across` is zero
  // at the shared edge u + w.
  const uint32_t last = std::max(members, 1u) - 1;
  auto section = [&](const glm::vec3& at, float members_before) {
    const glm::vec3 to_eye = -at / std::max(glm::length(at), 1e-30f);
    glm::vec3 side = glm::cross(tangent, to_eye);
    if (glm::length(side) < 1e-6f)  // seen along its axis: any side will do
      side = glm::cross(tangent, std::abs(tangent.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0));
    side = glm::normalize(side);
    const float shared = glm::dot(u + w, side);
    const float u_outer = glm::dot(u - w, side), w_outer = glm::dot(w - u, side);
    vertices.push_back({at + u_outer * side, in.object, packed_u, packed_w,
                        -std::abs(shared - u_outer), members_before, last});
    vertices.push_back({at + w_outer * side, in.object, packed_u, packed_w,
                        std::abs(w_outer - shared), members_before, last});
  };
  const auto base = static_cast<uint32_t>(vertices.size());
  section(centre - along, 0.0f);
  section(centre + along, float(last + 1));
  // Outer edge of the first face at each end (base, base + 2), of the second (base + 1, + 3).
  batch.indices[kBeams].insert(batch.indices[kBeams].end(),
                               {base, base + 1, base + 3, base, base + 3, base + 2});
}

void appendPoint(InstanceBatch& batch, uint32_t object, const glm::vec3& at) {
  batch.indices[kPoints].push_back(static_cast<uint32_t>(batch.vertices.size()));
  batch.vertices.push_back({at, object, 0u});
}

}  // namespace tw::instance_forms
