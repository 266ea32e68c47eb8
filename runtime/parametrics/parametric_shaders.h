// GLSL of the parametric passes: the ray-cast impostors (cylinder, cone/frustum, sphere, torus
// segment), the rasterized box, and the triangle pass of tessellated parametrics. Embedded as C++
// raw strings like gl_shaders.h; the instance structs come from parametric_gpu.h (pasted after
// #version through the generated kParametricGpuGlsl), the colour and lighting from
// gl::shadingGlsl(), so an impostor is coloured and lit exactly as a mesh of the same object.
//
// Impostor pass, per instance (one instanced draw of a 14-vertex strip per cluster, 36 vertices for
// boxes, gl_BaseInstanceARB
// = the cluster's first instance, gl_DrawIDARB selects the cluster's eye-relative anchor):
//  - vertex: the canonical-frame proxy box (tight per type; grown by half a pixel for thin
//    things), placed eye-relative. Back faces are culled, except when the eye is inside the proxy:
//    then the winding is reversed so the far faces rasterize and the ray starts at the near plane.
//    An instance whose conservative bounding sphere projects below min_feature_px is culled by
//    emitting a degenerate position.
//  - fragment: the ray from the eye through the proxy point, in the canonical frame, starting at
//    the proxy point (small numbers, so float keeps its precision), is intersected with the
//    primitive; the nearest hit beyond the near plane wins. Depth is the hit's reversed-Z window
//    depth, written to gl_FragDepth, so impostors and meshes intersect exactly.
// Small on screen: the tube radius (cylinder, cone, torus minor radius) and the sphere radius are
// raised to thin_radius_px (half a pixel by default) at the fragment's depth, so a pipe thinner
// than a pixel stays a continuous one-pixel line instead of breaking into dots
// (docs/parametrics.md has the flicker this saves).
#pragma once

#include <string>

#include "gl_shaders.h"
#include "parametric_gpu.h"
#include "parametric_gpu_glsl.h"

namespace tw::gl {

// Uniform locations of the parametric programs (0 and 1 as in gl_shaders.h).
inline constexpr int kParamViewForwardNearLocation = 2;  // vec4: unit view forward (world), near_m
inline constexpr int kParamMetresPerPxLocation = 3;      // float: metres per pixel at 1 m depth
inline constexpr int kParamMinFeaturePxLocation = 4;     // float: instances below are culled
inline constexpr int kParamDrawBaseLocation = 5;         // uint: first GpuParametricDraw of the call
inline constexpr int kParamMeshAnchorLocation = 6;       // vec3: tessellated pass, anchor - eye
inline constexpr int kParamThinRadiusPxLocation = 7;     // float: thin things grow to this radius
inline constexpr int kParamProxyPassLocation = 8;        // int: kProxyPass*
// Impostor calls are split by where the eye is, so the common case keeps early depth rejection:
// with the eye outside the proxy, the hit is never nearer than the rasterized front face, which
// the fragment shader declares (layout(depth_less), reversed Z); with the eye inside, the far
// faces are rasterized and that promise would be false, so those few instances go through a
// program without it.
inline constexpr int kProxyPassAll = 0;
inline constexpr int kProxyPassOutside = 1;
inline constexpr int kProxyPassInside = 2;

// Everything both impostor stages declare. `type` is the pkg::PrimitiveType the program draws.
inline std::string parametricPreamble(unsigned type) {
  return std::string("#version 450 core\n#extension GL_ARB_shader_draw_parameters : require\n") +
         "#define PRIM_TYPE " + std::to_string(type) + "\n" + gpu::kParametricGpuGlsl + R"(
layout(std430, binding = kInstanceBinding) readonly buffer Instances { GpuInstance instances[]; };
layout(std430, binding = kParametricDrawBinding) readonly buffer Draws { GpuParametricDraw draws[]; };
layout(location = 0) uniform mat4 view_projection;
layout(location = 2) uniform vec4 view_forward_near;
layout(location = 3) uniform float metres_per_px;
layout(location = 4) uniform float min_feature_px;
layout(location = 5) uniform uint draw_base;
layout(location = 7) uniform float thin_radius_px;
layout(location = 8) uniform int proxy_pass;  // kProxyPass*: which instances this call draws
)";
}

inline std::string impostorVertexShader(unsigned type) {
  return parametricPreamble(type) + R"(
// Box corners (bit 0: x, bit 1: y, bit 2: z), counter-clockwise seen from outside, two triangles
// per face in the order -X, +X, -Y, +Y, -Z, +Z.
const int kCorners[36] = int[36](0, 6, 2, 0, 4, 6, 1, 7, 5, 1, 3, 7, 0, 5, 4, 0, 1, 5,
                                 2, 7, 3, 2, 6, 7, 0, 3, 1, 0, 2, 3, 4, 7, 6, 4, 5, 7);
const vec3 kFaceNormals[6] = vec3[6](vec3(-1, 0, 0), vec3(1, 0, 0), vec3(0, -1, 0),
                                     vec3(0, 1, 0), vec3(0, 0, -1), vec3(0, 0, 1));
// The same box as one 14-vertex triangle strip, every triangle outward and counter-clockwise
// with the strip's alternation: the ray-cast proxies use it (2.6x fewer vertices than the list;
// llvmpipe shades vertices on one thread). Mirroring x (corner ^ 1) reverses every winding.
const int kStrip[14] = int[14](0, 1, 4, 5, 7, 1, 3, 0, 2, 4, 6, 7, 2, 3);
out vec3 v_pos_eye;           // proxy point relative to the eye
out vec3 v_local;             // the same point in the canonical frame
flat out uint v_instance;
flat out vec3 v_eye_local;    // the eye in the canonical frame
flat out mat3 v_normal_matrix;  // canonical normals -> world: transpose(inverse(linear))
flat out float v_px_scale;    // canonical units per pixel per metre of view depth
flat out vec3 v_box_min;      // the (grown) proxy box, canonical frame
flat out vec3 v_box_max;
flat out vec3 v_face_normal;  // box pass: the face's canonical normal

void main() {
  v_instance = gl_BaseInstanceARB + uint(gl_InstanceID);
  GpuInstance g = instances[v_instance];
  vec3 origin_eye = draws[draw_base + uint(gl_DrawIDARB)].anchor_eye + g.origin_m;
  mat3 linear = mat3(g.axis_x.xyz, g.axis_y.xyz, g.axis_z.xyz);
  mat3 inverse_linear = inverse(linear);
  v_normal_matrix = transpose(inverse_linear);
  vec3 lo = g.local_min, hi = g.local_max;
  vec3 scale = vec3(length(linear[0]), length(linear[1]), length(linear[2]));
  vec3 half_size = 0.5 * (hi - lo);
  float radius = dot(scale, half_size);  // conservative for any linear map
  vec3 forward = view_forward_near.xyz;
  float near_m = view_forward_near.w;
  float depth = dot(origin_eye + linear * (0.5 * (lo + hi)), forward);
  float nearest = max(depth - radius, near_m), farthest = max(depth + radius, near_m);
  if (2.0 * radius < min_feature_px * metres_per_px * nearest) {
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);  // small-feature culling: outside the clip volume
    return;
  }
#if PRIM_TYPE == 2
  float cross_scale = min(min(scale.x, scale.y), scale.z);
#else
  float cross_scale = min(scale.x, scale.y);
#endif
  v_px_scale = metres_per_px / max(cross_scale, 1e-30);
#if PRIM_TYPE != 4
  vec3 grow = vec3(thin_radius_px * v_px_scale * farthest);
  lo -= grow;
  hi += grow;
#endif
  v_box_min = lo;
  v_box_max = hi;
  v_eye_local = inverse_linear * (-origin_eye);
  vec3 margin = vec3(2.0 * near_m / max(min(cross_scale, scale.z), 1e-30));
  bool inside = all(greaterThan(v_eye_local, lo - margin)) && all(lessThan(v_eye_local, hi + margin));
  if ((proxy_pass == 1 && inside) || (proxy_pass == 2 && !inside)) {
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);  // the other call draws this instance
    return;
  }
  bool flip = inside != (determinant(linear) < 0.0);
#if PRIM_TYPE == 4
  int v = gl_VertexID;
  if (flip) v = v - v % 3 + 2 - v % 3;
  int corner = kCorners[v];
  v_face_normal = kFaceNormals[gl_VertexID / 6];
#else
  int corner = kStrip[gl_VertexID] ^ (flip ? 1 : 0);
  v_face_normal = vec3(0.0);
#endif
  v_local = mix(lo, hi, vec3(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1));
  v_pos_eye = origin_eye + linear * v_local;
  gl_Position = view_projection * vec4(v_pos_eye, 1.0);
}
)";
}

// The box is its own proxy: rasterized with a flat face normal and no gl_FragDepth (early depth
// test stays on). Drawn without face culling, so a box seen from inside shows, like a mesh.
inline std::string boxFragmentShader() {
  return parametricPreamble(4) + R"(
in vec3 v_pos_eye;
flat in uint v_instance;
flat in mat3 v_normal_matrix;
flat in vec3 v_face_normal;
layout(location = 0) out vec4 out_color;
layout(location = 1) out uint out_id;
)" + shadingGlsl() + R"(
void main() {
  GpuInstance g = instances[v_instance];
  if (sectionClipped(v_pos_eye)) discard;
  vec3 n = normalize(v_normal_matrix * v_face_normal);
  out_color = sectionCap(dot(n, v_pos_eye) > 0.0) ? kSectionCap
                                                  : shadeSurface(objectBaseColor(g.object), n, v_pos_eye);
  if (objectSkipped(g.object)) discard;
  out_id = g.object + 1u;
}
)";
}

// The ray-cast impostors. The ray is p(s) = v_local + s * d in the canonical frame, d unit, s
// the canonical distance from the proxy point; the hit's eye-relative position is
// (1 + s / |v_local - eye_local|) * v_pos_eye.
inline std::string impostorFragmentShader(unsigned type, bool eye_outside) {
  return parametricPreamble(type) +
         (eye_outside ? "#define TW_EYE_OUTSIDE 1\nlayout(depth_less) out float gl_FragDepth;\n" : "") + R"(
in vec3 v_pos_eye;
in vec3 v_local;
flat in uint v_instance;
flat in vec3 v_eye_local;
flat in mat3 v_normal_matrix;
flat in float v_px_scale;
flat in vec3 v_box_min;
flat in vec3 v_box_max;
layout(location = 0) out vec4 out_color;
layout(location = 1) out uint out_id;
)" + shadingGlsl() + R"(
const float kNoHit = 3.0e38;
const float kTwoPi = 6.28318530718;

// The ray's eye-relative point at canonical distance s (set by main before any hit test).
vec3 ray_pos_eye;
float ray_len;
vec3 hitEye(float s) { return (1.0 + s / ray_len) * ray_pos_eye; }

// Keeps the nearest hit at or beyond s_min that no section plane removes (behind a removed hit
// the ray goes on to the surface's far side: the inside of the cut solid).
void keep(float s, float s_min, vec3 n, inout float best, inout vec3 best_n) {
  if (s >= s_min && s < best && !sectionClipped(hitEye(s))) { best = s; best_n = n; }
}

// Cylinder (rb == rt) or cone/frustum about +Z from z = 0 (radius rb) to z = h (radius rt); the
// discs at the ends when capped (only where the true radius is > 0).
void hitCone(vec3 o, vec3 d, float rb, float rt, float h, bool cap_bottom, bool cap_top,
             float s_min, inout float best, inout vec3 best_n) {
  float k = (rt - rb) / h;
  float m = rb + k * o.z;
  float kd = k * d.z;
  float a = d.x * d.x + d.y * d.y - kd * kd;
  float b = o.x * d.x + o.y * d.y - m * kd;
  float c = o.x * o.x + o.y * o.y - m * m;
  float disc = b * b - a * c;
  if (disc >= 0.0 && abs(a) > 1e-12) {
    float q = sqrt(disc);
    for (int i = 0; i < 2; ++i) {
      float s = (-b + (i == 0 ? -q : q)) / a;
      vec3 p = o + s * d;
      if (p.z >= 0.0 && p.z <= h) keep(s, s_min, vec3(p.xy, -k * (rb + k * p.z)), best, best_n);
    }
  }
  if (abs(d.z) > 0.0) {
    if (cap_bottom) {
      float s = -o.z / d.z;
      vec3 p = o + s * d;
      if (dot(p.xy, p.xy) <= rb * rb) keep(s, s_min, vec3(0.0, 0.0, -1.0), best, best_n);
    }
    if (cap_top) {
      float s = (h - o.z) / d.z;
      vec3 p = o + s * d;
      if (dot(p.xy, p.xy) <= rt * rt) keep(s, s_min, vec3(0.0, 0.0, 1.0), best, best_n);
    }
  }
}

void hitSphere(vec3 o, vec3 d, float r, float s_min, inout float best, inout vec3 best_n) {
  float b = dot(o, d);
  float disc = b * b - (dot(o, o) - r * r);
  if (disc < 0.0) return;
  float q = sqrt(disc);
  keep(-b - q, s_min, o + (-b - q) * d, best, best_n);
  keep(-b + q, s_min, o + (-b + q) * d, best, best_n);
}

float torusDistance(vec3 p, float major_r, float minor_r) {
  return length(vec2(length(p.xy) - major_r, p.z)) - minor_r;
}

bool inSweep(vec3 p, float sweep) {
  if (sweep >= kTwoPi) return true;
  float a = atan(p.y, p.x);
  if (a < 0.0) a += kTwoPi;
  return a <= sweep;
}

// Torus segment: sphere tracing on the exact distance to the whole torus (steps never cross the
// surface, so no hit is skipped), inside the proxy box; a surface point outside the sweep is
// stepped over and the march goes on (the inside of the tube shows through the open ends).
void hitTorus(vec3 o, vec3 d, float major_r, float minor_r, float sweep, float s_min, float px,
              inout float best, inout vec3 best_n) {
  vec3 inv = 1.0 / d;
  vec3 t0 = (v_box_min - o) * inv, t1 = (v_box_max - o) * inv;
  vec3 tn = min(t0, t1), tf = max(t0, t1);
  float s = max(max(max(tn.x, tn.y), tn.z), s_min);
  float s_end = min(min(tf.x, tf.y), tf.z);
  float eps = max(0.05 * px, 1e-5 * major_r);
  for (int i = 0; i < 160 && s <= s_end; ++i) {
    vec3 p = o + s * d;
    float dist = abs(torusDistance(p, major_r, minor_r));
    if (dist < eps) {
      if (inSweep(p, sweep) && !sectionClipped(hitEye(s))) {
        // The march stops up to eps short of the surface; Newton steps on the signed distance
        // along the ray land on it, so depth is exact, not eps too near.
        for (int k = 0; k < 3; ++k) {
          vec3 g = p - vec3(major_r * normalize(p.xy), 0.0);
          float slope = dot(normalize(g), d);
          if (abs(slope) < 0.05) break;
          s -= torusDistance(p, major_r, minor_r) / slope;
          p = o + s * d;
        }
        vec2 c = major_r * normalize(p.xy);
        keep(s, s_min, p - vec3(c, 0.0), best, best_n);
        return;
      }
      s += 2.0 * eps;
    } else {
      s += dist;
    }
  }
}

void main() {
  GpuInstance g = instances[v_instance];
  vec3 o = v_local;
  vec3 dv = v_local - v_eye_local;
  float len_d = length(dv);
  vec3 d = dv / len_d;
  ray_pos_eye = v_pos_eye;
  ray_len = len_d;
  float view_depth = max(dot(v_pos_eye, view_forward_near.xyz), 1e-30);
  float s_min = (view_forward_near.w / view_depth - 1.0) * len_d;  // the near plane
  float px = v_px_scale * view_depth;  // canonical units per pixel around the proxy point
  // A thin tube's grown radius reaches the pixel centres half a pixel away with 5 % to spare:
  // px is taken at the proxy point, which lies nearer than the tube by up to about a pixel's
  // worth of metres, so without it a pipe lying exactly between two pixel rows (every centre of
  // both on its grown silhouette) would miss them all and vanish.
  float min_r = thin_radius_px * px * 1.05;
  vec3 p0 = vec3(g.axis_x.w, g.axis_y.w, g.axis_z.w);
  bool capped = (g.flags & kGpuCapped) != 0u;
  float best = kNoHit;
  vec3 n = vec3(0.0, 0.0, 1.0);
#if PRIM_TYPE == 0
  float r = max(p0.x, min_r);
  hitCone(o, d, r, r, p0.y, capped, capped, s_min, best, n);
#elif PRIM_TYPE == 1
  // Only a cone thin as a whole grows (both radii scaled), so an apex stays an apex.
  float grow = max(min_r / max(max(p0.x, p0.y), 1e-30), 1.0);
  hitCone(o, d, p0.x * grow, p0.y * grow, p0.z, capped && p0.x > 0.0, capped && p0.y > 0.0,
          s_min, best, n);
#elif PRIM_TYPE == 2
  hitSphere(o, d, max(p0.x, min_r), s_min, best, n);
#elif PRIM_TYPE == 3
  hitTorus(o, d, p0.x, max(p0.y, min_r), p0.z, s_min, px, best, n);
#endif
  if (best == kNoHit) discard;
  vec3 hit_eye = (1.0 + best / len_d) * v_pos_eye;
  vec4 clip = view_projection * vec4(hit_eye, 1.0);
  gl_FragDepth = clip.z / clip.w;
#ifdef TW_EYE_OUTSIDE
  gl_FragDepth = min(gl_FragDepth, gl_FragCoord.z);  // keep the depth_less promise to the rounding
#endif
  vec3 n_eye = normalize(v_normal_matrix * n);
  out_color = sectionCap(dot(n_eye, hit_eye) > 0.0)
                  ? kSectionCap
                  : shadeSurface(objectBaseColor(g.object), n_eye, hit_eye);
  if (objectSkipped(g.object)) discard;
  out_id = g.object + 1u;
}
)";
}

// Tessellated parametrics (parametric_meshes.h): float positions relative to the cluster's
// anchor, one object index and one normal (the surface's own) per vertex; shaded by
// parametricSmoothFragmentShader like the instances below.
inline std::string parametricMeshVertexShader() {
  return std::string(R"(#version 450 core
layout(location = 0) in vec3 position;  // metres from the cluster anchor
layout(location = 1) in uint object;
layout(location = 2) in vec3 normal;    // world, unit or zero
layout(location = 0) uniform mat4 view_projection;
layout(location = 6) uniform vec3 anchor_eye;
out vec3 pos_eye;
out vec3 v_normal;
flat out uint v_object;
flat out vec4 v_base;
)") + objectColorGlsl() + R"(
void main() {
  pos_eye = anchor_eye + position;
  v_normal = normal;
  v_object = object;
  v_base = objectBaseColor(object);
  gl_Position = view_projection * vec4(pos_eye, 1.0);
}
)";
}

// Tessellated parametrics drawn per instance (parametric_instance_meshes.h): eye-relative float
// positions, one object index and one normal per vertex (signed 10-bit, normalized). Curved
// surfaces carry their true normal, so a coarse tessellation shades like the smooth surface;
// flat faces (caps, boxes), lines and points carry a zero normal and are faceted like the mesh
// pass (derivative normals; a line faces the eye).
inline std::string parametricSmoothVertexShader() {
  return std::string(R"(#version 450 core
layout(location = 0) in vec3 position;  // metres from the eye
layout(location = 1) in uint object;
layout(location = 2) in vec3 normal;    // world, unit or zero
layout(location = 0) uniform mat4 view_projection;
out vec3 pos_eye;
out vec3 v_normal;
flat out uint v_object;
flat out vec4 v_base;
)") + objectColorGlsl() + R"(
void main() {
  pos_eye = position;
  v_normal = normal;
  v_object = object;
  v_base = objectBaseColor(object);
  gl_Position = view_projection * vec4(pos_eye, 1.0);
}
)";
}

inline std::string parametricSmoothFragmentShader() {
  return std::string(R"(#version 450 core
in vec3 pos_eye;
in vec3 v_normal;
flat in uint v_object;
flat in vec4 v_base;  // the object's colour, looked up once per vertex
layout(location = 0) out vec4 out_color;
layout(location = 1) out uint out_id;
)") + shadingGlsl() + R"(
void main() {
  // The side seen is the facet's side toward the eye. The interpolated normal is turned to that
  // side (the inside of an open tube) but not to the eye: on a coarse ring it leans away from
  // the eye near a silhouette, and flipping it there would shade a pixel of the lit side as if
  // it were the far side, a dark speck inside the pipe.
  if (sectionClipped(pos_eye)) discard;
  vec3 facet = facetNormal(pos_eye);
  if (dot(facet, pos_eye) > 0.0) facet = -facet;
  float len = length(v_normal);
  vec3 n = facet;
  if (len > 0.25) n = dot(v_normal, facet) < 0.0 ? -v_normal / len : v_normal / len;
  // The surface's own normal facing away (or, for flat faces that carry none, the triangle's
  // back: instances are wound outward): the inside of a solid the section cut open.
  bool back = len > 0.25 ? dot(v_normal, pos_eye) > 0.0 : !gl_FrontFacing;
  out_color = sectionCap(back) ? kSectionCap : shadeSeenSide(v_base, n, pos_eye);
  if (objectSkipped(v_object)) discard;
  out_id = v_object + 1u;
}
)";
}

// The points of far instances thin in every direction (appendPoint): shaded once, in the vertex
// stage. A point's inputs do not vary across it, so its derivative normal is the one facing the
// eye and parametricSmoothFragmentShader would compute this same colour for each fragment; here
// llvmpipe sets up and shades no interpolated inputs (the 50M plant's orbit draws some 22,000).
inline std::string parametricPointVertexShader() {
  return std::string(R"(#version 450 core
layout(location = 0) in vec3 position;  // metres from the eye
layout(location = 1) in uint object;
layout(location = 0) uniform mat4 view_projection;
flat out vec4 v_color;
flat out uint v_object;
)") + objectColorGlsl() + lightingGlsl() + R"(
void main() {
  v_object = object;
  v_color = shadeSeenSide(objectBaseColor(object), normalize(-position), position);
  gl_Position = view_projection * vec4(position, 1.0);
  // A point of an object this pass skips goes outside the clip volume: nothing of it is drawn.
  if (objectSkipped(object) || sectionClipped(position)) gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
}
)";
}

inline std::string parametricPointFragmentShader() {
  return R"(#version 450 core
flat in vec4 v_color;
flat in uint v_object;
layout(location = 0) out vec4 out_color;
layout(location = 1) out uint out_id;
void main() {
  out_color = v_color;
  out_id = v_object + 1u;
}
)";
}

// Rows of boxes drawn as one box each (appendBoxRow): a fragment's object is the member it falls
// on, and its colour that object's, so the row shades and reads back as its boxes drawn one by
// one (flat faces: derivative normals, as parametricSmoothFragmentShader shades a box).
inline std::string parametricRowVertexShader() {
  return R"(#version 450 core
layout(location = 0) in vec3 position;  // metres from the eye
layout(location = 1) in uint object;    // the row's first member's
layout(location = 2) in float along;    // members from the row's start face
layout(location = 3) in uint last;      // the member count less one
layout(location = 0) uniform mat4 view_projection;
out vec3 pos_eye;
out float v_along;
flat out uint v_object;
flat out uint v_last;
void main() {
  pos_eye = position;
  v_along = along;
  v_object = object;
  v_last = last;
  gl_Position = view_projection * vec4(pos_eye, 1.0);
}
)";
}

inline std::string parametricRowFragmentShader() {
  return std::string(R"(#version 450 core
in vec3 pos_eye;
in float v_along;
flat in uint v_object;
flat in uint v_last;
layout(location = 0) out vec4 out_color;
layout(location = 1) out uint out_id;
)") + shadingGlsl() + R"(
void main() {
  if (sectionClipped(pos_eye)) discard;
  uint object = v_object + min(uint(max(v_along, 0.0)), v_last);
  vec3 facet = facetNormal(pos_eye);
  if (dot(facet, pos_eye) > 0.0) facet = -facet;
  // Row boxes are wound outward like every box: a back face is the inside of a cut one.
  out_color = sectionCap(!gl_FrontFacing) ? kSectionCap
                                          : shadeSeenSide(objectBaseColor(object), facet, pos_eye);
  if (objectSkipped(object)) discard;
  out_id = object + 1u;
}
)";
}

// Thin beams drawn per instance as their silhouette (appendBeamRibbon in
// parametric_instance_expansion.h): one band of two triangles facing the eye, across the two long
// faces the eye sees. Each vertex carries both faces' normals and `across`, negative on the first
// face's side of the edge where the faces meet and positive on the second's, so the fragments on
// either side of that edge are shaded with their own face's normal, as two bands of two triangles
// each would be.
inline std::string parametricBeamVertexShader() {
  return std::string(R"(#version 450 core
layout(location = 0) in vec3 position;  // metres from the eye
layout(location = 1) in uint object;
layout(location = 2) in vec3 normal_u;  // world, unit: the first face's
layout(location = 3) in vec3 normal_w;  // and the second's
layout(location = 4) in float across;   // < 0 over the first face, > 0 over the second
layout(location = 5) in float along;    // members from the band's start (a row of beams)
layout(location = 6) in uint last;      // the member count less one
layout(location = 0) uniform mat4 view_projection;
out vec3 pos_eye;
out float v_across;
out float v_along;
flat out uint v_object;
flat out uint v_last;
flat out vec4 v_base;
flat out vec3 v_normal_u;
flat out vec3 v_normal_w;
)") + objectColorGlsl() + R"(
void main() {
  pos_eye = position;
  v_across = across;
  v_along = along;
  v_object = object;
  v_last = last;
  v_base = objectBaseColor(object);
  v_normal_u = normal_u;
  v_normal_w = normal_w;
  gl_Position = view_projection * vec4(pos_eye, 1.0);
}
)";
}

inline std::string parametricBeamFragmentShader() {
  return std::string(R"(#version 450 core
in vec3 pos_eye;
in float v_across;
in float v_along;
flat in uint v_object;
flat in uint v_last;
flat in vec4 v_base;  // the first member's colour
flat in vec3 v_normal_u;
flat in vec3 v_normal_w;
layout(location = 0) out vec4 out_color;
layout(location = 1) out uint out_id;
)") + shadingGlsl() + R"(
void main() {
  if (sectionClipped(pos_eye)) discard;
  // As parametricSmoothFragmentShader with a face's normal: turned to the side seen.
  vec3 facet = facetNormal(pos_eye);
  if (dot(facet, pos_eye) > 0.0) facet = -facet;
  vec3 face = v_across < 0.0 ? v_normal_u : v_normal_w;
  float len = max(length(face), 1e-30);
  vec3 n = dot(face, facet) < 0.0 ? -face / len : face / len;
  // A row of beams: the member under the fragment, and its colour unless it is the first's.
  uint object = v_object + min(uint(max(v_along, 0.0)), v_last);
  vec4 base = v_base;
  if (object != v_object) base = objectBaseColor(object);
  out_color = shadeSeenSide(base, n, pos_eye);
  if (objectSkipped(object)) discard;
  out_id = object + 1u;
}
)";
}

}  // namespace tw::gl
