// GLSL of the mesh pass and of the depth-only occluder pass, embedded as C++ raw strings, and the
// one GPU-visible struct they share with the C++ side.
//
// Why here and not in .glsl files: a header needs no build step, and the per-draw struct is
// written once (kDrawDataFields) and expanded both as a C++ struct and as GLSL text, so the two
// can never disagree. Binding points and uniform locations are constants used by both sides.
// Included only by gl_renderer.cpp (and tests that want the layout).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include <glm/glm.hpp>

#include "object_states.h"
#include "section_planes.h"

namespace tw::gl {

// Shader storage binding points.
inline constexpr unsigned kDrawDataBinding = 0;        // GpuDrawData[], indexed by gl_DrawIDARB
inline constexpr unsigned kTriangleObjectBinding = 1;  // uint object per pool triangle
inline constexpr unsigned kObjectColorBinding = 2;     // uint 0xAABBGGRR per object index
inline constexpr unsigned kObjectStateBinding = 5;     // GpuObjectState per object index
// Uniform buffer binding points.
// The SurfacePass being drawn and the section planes (SurfacePassBlock below).
inline constexpr unsigned kSurfacePassBinding = 0;
using tw::kMaxSectionPlanes;  // section planes clipping the surface passes at once
// Uniform locations.
inline constexpr int kViewProjectionLocation = 0;  // mat4: projection * view rotation
inline constexpr int kObjectColorCountLocation = 1;  // uint: entries in the colour buffer

// The per-draw record. std430: vec3 aligns to 16 and is followed by a float in the same 16 bytes;
// the array stride is 32, which the padding makes equal to sizeof on the C++ side. push_m is read
// by the depth-only occluder pass only (metres each vertex moves away from the eye).
#define TW_GPU_DRAW_DATA_FIELDS \
  vec3 offset_eye;              \
  float cell_m;                 \
  uint first_triangle;          \
  float push_m;                 \
  uint reserved1;               \
  uint reserved2;
#define TW_GL_STRINGIFY_(...) #__VA_ARGS__
#define TW_GL_STRINGIFY(...) TW_GL_STRINGIFY_(__VA_ARGS__)

namespace glsl_types {
using vec3 = glm::vec3;
using uint = uint32_t;
struct GpuDrawData {
  TW_GPU_DRAW_DATA_FIELDS
};
}  // namespace glsl_types
using GpuDrawData = glsl_types::GpuDrawData;
static_assert(sizeof(GpuDrawData) == 32 && offsetof(GpuDrawData, cell_m) == 12 &&
                  offsetof(GpuDrawData, first_triangle) == 16 &&
                  offsetof(GpuDrawData, push_m) == 20,
              "GpuDrawData must match the std430 layout of the GLSL struct");

// The surface passes' uniform block (std140, objectColorGlsl): the pass, then the section planes
// (xyz the unit normal toward the removed side, w the offset, all eye-relative).
struct SurfacePassBlock {
  uint32_t surface_pass;
  uint32_t section_count;
  uint32_t padding[2];
  glm::vec4 planes[kMaxSectionPlanes];
};
static_assert(offsetof(SurfacePassBlock, planes) == 16 &&
                  sizeof(SurfacePassBlock) == 16 + 16 * kMaxSectionPlanes,
              "SurfacePassBlock must match the std140 layout of the GLSL block");

// GL's indirect command for glMultiDrawElementsIndirect (fixed by the GL spec).
struct DrawElementsIndirectCommand {
  uint32_t count;
  uint32_t instance_count;
  uint32_t first_index;
  int32_t base_vertex;
  uint32_t base_instance;
};
static_assert(sizeof(DrawElementsIndirectCommand) == 20);

// The inputs every cluster vertex shader shares: 16-bit grid positions, the per-draw records
// (indexed by gl_DrawIDARB) and the view-projection.
inline std::string clusterVertexPreamble() {
  return std::string(R"(#version 450 core
#extension GL_ARB_shader_draw_parameters : require
layout(location = 0) in uvec3 q;
struct GpuDrawData {
)") + TW_GL_STRINGIFY(TW_GPU_DRAW_DATA_FIELDS) +
         R"(
};
layout(std430, binding = 0) readonly buffer DrawDataBuffer { GpuDrawData draws[]; };
layout(location = 0) uniform mat4 view_projection;
)";
}

// The colour and lighting every surface pass shares (meshes, parametric impostors and
// tessellated parametrics), so the same object looks the same whichever way it is drawn: colour
// from the object table (grey when absent), sky/ground hemispheric plus sun and head light,
// two-sided (the normal is turned toward the eye, because CAD surfaces are often open).
// The object colour part (objectColorGlsl) also serves vertex stages that hand the colour to
// the fragments flat.
// Per-object state (object_states.h): every fragment stage that outputs an object id discards
// the fragments of objects its surface pass does not draw (objectSkipped): in the opaque pass
// the hidden and the ghosted, in the X-ray pass all but the ghosted. Selected objects are
// tinted, recoloured ones take their override, and in the X-ray pass every object takes the
// ghost colour (the blending makes it translucent), through objectBaseColor. The pass is one
// uniform buffer shared by every program (GlRenderer::bindSurfaceState binds it).
// Sections (section_planes.h) live in the same buffer: eye-relative planes (normal, offset),
// each removing what lies on its normal's side. Every surface fragment stage discards what a
// plane removes (sectionClipped) and paints the inside of a cut solid, which it sees as a back
// face, in the section colour (sectionCap: the back-face method of capping).
inline std::string objectColorGlsl() {
  static_assert(kObjectColorBinding == 2, "the GLSL below binds the colours at 2");
  static_assert(uint8_t(SurfacePass::Opaque) == 0 && uint8_t(SurfacePass::Xray) == 1);
  return R"(
layout(std430, binding = 2) readonly buffer ObjectColors { uint object_colors[]; };
struct ObjectState { uint flags; uint color_rgba; };
layout(std430, binding = )" + std::to_string(kObjectStateBinding) +
         R"() readonly buffer ObjectStates { ObjectState object_states[]; };
layout(std140, binding = )" + std::to_string(kSurfacePassBinding) +
         R"() uniform SurfacePassBlock {
  uint surface_pass;
  uint section_count;
  vec4 section_planes[)" + std::to_string(kMaxSectionPlanes) + R"(];
};
layout(location = 1) uniform uint object_color_count;
const vec4 kGrey = vec4(0.62, 0.62, 0.62, 1.0);
const vec4 kSelectedTint = vec4(1.0, 0.55, 0.05, 1.0);
const vec4 kGhost = vec4(0.34, 0.46, 0.66, 1.0);
const uint kObjectHidden = )" + std::to_string(tw::kObjectHidden) +
         "u, kObjectSelected = " + std::to_string(tw::kObjectSelected) +
         "u, kObjectXray = " + std::to_string(tw::kObjectXray) +
         "u, kObjectRecolored = " + std::to_string(tw::kObjectRecolored) +
         "u, kObjectMoved = " + std::to_string(tw::kObjectMoved) + R"(u;
uint objectFlags(uint object) {
  return object < object_color_count ? object_states[object].flags : 0u;
}
// As objectLook (object_states.h): whether the object is drawn ghosted, or not at all.
bool objectSkipped(uint object) {
  uint flags = objectFlags(object);
  if ((flags & (kObjectHidden | kObjectMoved)) != 0u) return true;
  bool ghosted = (flags & kObjectXray) != 0u && (flags & kObjectSelected) == 0u;
  return ghosted != (surface_pass == 1u);
}
bool sectionClipped(vec3 pos_eye) {
  for (uint i = 0u; i < section_count; ++i)
    if (dot(section_planes[i].xyz, pos_eye) + section_planes[i].w > 0.0) return true;
  return false;
}
const vec4 kSectionCap = vec4(0.78, 0.22, 0.18, 1.0);
// Whether a fragment facing away from the eye is the inside of a cut solid (any plane active).
bool sectionCap(bool back_facing) { return back_facing && section_count > 0u; }
vec4 objectBaseColor(uint object) {
  if (surface_pass == 1u) return kGhost;
  uint rgba = object < object_color_count ? object_colors[object] : 0u;
  vec4 base = rgba == 0u ? kGrey : unpackUnorm4x8(rgba);
  uint flags = objectFlags(object);
  if ((flags & kObjectRecolored) != 0u) base = unpackUnorm4x8(object_states[object].color_rgba);
  if ((flags & kObjectSelected) != 0u) base = mix(base, kSelectedTint, 0.6);
  return base;
}
)";
}

// The lighting alone, for a vertex stage that shades a point once for all its fragments.
inline std::string lightingGlsl() {
  return R"(
const vec3 kSunDir = normalize(vec3(0.35, 0.25, 0.90));  // world (eye-relative axes are world axes)
const vec3 kSky = vec3(0.80, 0.86, 0.95);
const vec3 kGround = vec3(0.30, 0.27, 0.24);
// n: unit normal of the side seen (it may lean a little away from the eye at a silhouette),
// pos_eye: the shaded point relative to the eye.
vec4 shadeSeenSide(vec4 base, vec3 n, vec3 pos_eye) {
  vec3 v = normalize(-pos_eye);
  vec3 light = mix(kGround, kSky, 0.5 + 0.5 * n.z) * 0.55
             + vec3(0.50) * max(dot(n, kSunDir), 0.0)
             + vec3(0.22) * max(dot(n, v), 0.0);
  return vec4(min(base.rgb * light, vec3(1.0)), 1.0);
}
// n: unit normal, either side; the side facing the eye is shaded.
vec4 shadeSurface(vec4 base, vec3 n, vec3 pos_eye) {
  return shadeSeenSide(base, dot(n, pos_eye) > 0.0 ? -n : n, pos_eye);
}
)";
}

inline std::string shadingGlsl() {
  return objectColorGlsl() + R"(
// The face normal of the triangle under the fragment, from screen-space derivatives of its
// eye-relative position (facing the eye where they vanish: lines, points, slivers).
vec3 facetNormal(vec3 pos_eye) {
  vec3 n = cross(dFdx(pos_eye), dFdy(pos_eye));
  float len = length(n);
  return len > 1e-30 ? n / len : normalize(-pos_eye);
}
)" + lightingGlsl();
}

// The per-triangle object table of the pool, read by the mesh pass's two stages.
inline constexpr const char* kTriangleObjectsGlsl = R"(
layout(std430, binding = 1) readonly buffer TriangleObjects { uint tri_objects[]; };
)";

inline std::string meshVertexShader() {
  return clusterVertexPreamble() + kTriangleObjectsGlsl + objectColorGlsl() + R"(
// Positions arrive as 16-bit grid units; the cluster's eye-relative origin and cell size come
// from the per-draw record, so everything here stays small and float-safe far from the origin.
// The tag names a triangle of this vertex's object (vertex_object_tags.h): its object and colour
// go to the fragments flat, from each triangle's last vertex. 0xffff: the vertex is shared by
// objects, and the fragments look their triangle up themselves (object_plus_one = 0).
layout(location = 1) in uint tag;
out vec3 pos_eye;
flat out uint first_triangle;
flat out uint object_plus_one;
flat out vec4 base_color;
void main() {
  GpuDrawData d = draws[gl_DrawIDARB];
  pos_eye = d.offset_eye + vec3(q) * d.cell_m;
  first_triangle = d.first_triangle;
  object_plus_one = 0u;
  base_color = vec4(0.0);
  if (tag != 0xffffu) {
    uint object = tri_objects[d.first_triangle + tag];
    object_plus_one = object + 1u;
    base_color = objectBaseColor(object);
  }
  gl_Position = view_projection * vec4(pos_eye, 1.0);
  // Only triangles of this vertex's object use it: when this pass skips that object they all go
  // (their fragments would be discarded), so the vertex leaves the clip volume and a triangle
  // of skipped corners only is rejected before any fragment.
  if (object_plus_one != 0u && objectSkipped(object_plus_one - 1u))
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
}
)";
}

// per_triangle: the variant for clusters with a triangle that has no corner of its own object
// (GpuCluster::object_per_triangle); the other takes object and colour flat, with no table read.
inline std::string meshFragmentShader(bool per_triangle) {
  return std::string(R"(#version 450 core
// Object and colour flat from the vertex stage, or, for a triangle whose corners are all shared
// by objects, from the per-triangle pool (gl_PrimitiveID restarts at 0 for every draw of a
// multi-draw); a face normal from screen-space derivatives (the package stores none).
)") + (per_triangle ? "#define TW_OBJECT_PER_TRIANGLE 1\n" : "") + R"(
in vec3 pos_eye;
flat in uint first_triangle;
flat in uint object_plus_one;
flat in vec4 base_color;
layout(location = 0) out vec4 out_color;
layout(location = 1) out uint out_id;
)" + kTriangleObjectsGlsl + shadingGlsl() + R"(
void main() {
  uint id = object_plus_one;
  vec4 base = base_color;
#ifdef TW_OBJECT_PER_TRIANGLE
  if (id == 0u) {
    uint object = tri_objects[first_triangle + uint(gl_PrimitiveID)];
    id = object + 1u;
    base = objectBaseColor(object);
  }
#endif
  if (id != 0u && objectSkipped(id - 1u)) discard;
  if (sectionClipped(pos_eye)) discard;
  // Closed pieces are wound outward (the preprocessor's winding pass), so a back face is the
  // inside of a solid the section cut open.
  out_color = sectionCap(!gl_FrontFacing) ? kSectionCap
                                          : shadeSurface(base, facetNormal(pos_eye), pos_eye);
  out_id = id;
}
)";
}

// The selection outline, drawn over the finished frame: a pixel that shows no selected object
// but has one within two pixels takes the outline colour; it reads the frame's id target, so it
// outlines what the id buffer holds at whatever level of detail the object was drawn. One
// triangle covers the screen (its corners from gl_VertexID).
inline std::string outlineVertexShader() {
  return R"(#version 450 core
void main() {
  vec2 corner = vec2(float((gl_VertexID & 1) << 2), float((gl_VertexID & 2) << 1)) - 1.0;
  gl_Position = vec4(corner, 0.0, 1.0);
}
)";
}

inline std::string outlineFragmentShader() {
  return R"(#version 450 core
layout(binding = 0) uniform usampler2D frame_ids;
struct ObjectState { uint flags; uint color_rgba; };
layout(std430, binding = )" + std::to_string(kObjectStateBinding) +
         R"() readonly buffer ObjectStates { ObjectState object_states[]; };
layout(location = 1) uniform uint object_color_count;
layout(location = 0) out vec4 out_color;
const uint kObjectHidden = )" + std::to_string(tw::kObjectHidden) +
         "u, kObjectSelected = " + std::to_string(tw::kObjectSelected) + R"(u;
const vec4 kOutline = vec4(1.0, 0.86, 0.0, 1.0);
bool selectedAt(ivec2 p) {
  uint id = texelFetch(frame_ids, clamp(p, ivec2(0), textureSize(frame_ids, 0) - 1), 0).r;
  if (id == 0u || id > object_color_count) return false;
  uint flags = object_states[id - 1u].flags;
  return (flags & kObjectSelected) != 0u && (flags & kObjectHidden) == 0u;
}
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  if (selectedAt(p)) discard;
  for (int dy = -2; dy <= 2; ++dy)
    for (int dx = -2; dx <= 2; ++dx)
      if (dx * dx + dy * dy <= 5 && selectedAt(p + ivec2(dx, dy))) {
        out_color = kOutline;
        return;
      }
  discard;
}
)";
}

// The occluder pass: depth only, each vertex pushed away from the eye by its draw's push_m, so a
// coarse occluder lies behind the true surface it stands for (the push is the cluster's
// object-space error plus its quantization error). A vertex at the eye is left where it is.
inline std::string occluderVertexShader() {
  return clusterVertexPreamble() + R"(
void main() {
  GpuDrawData d = draws[gl_DrawIDARB];
  vec3 p = d.offset_eye + vec3(q) * d.cell_m;
  float len = length(p);
  if (len > 0.0) p += p * (d.push_m / len);
  gl_Position = view_projection * vec4(p, 1.0);
}
)";
}

// Depth only: no colour attachments are written; the fragment stage just lets depth through.
inline std::string occluderFragmentShader() {
  return R"(#version 450 core
void main() {}
)";
}

}  // namespace tw::gl
