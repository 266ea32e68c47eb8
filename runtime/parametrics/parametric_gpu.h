// The GPU-visible records of the parametric impostor renderer, declared once for C++ and GLSL.
//
// Why one file for both: the instance table is read by the shaders in place (std430), so the C++
// struct and the GLSL struct must agree to the byte. This file is written in the subset both
// languages accept (structs of vec3/vec4/uint/float, constants through TW_GPU_CONST); C++ includes
// it directly, and runtime/CMakeLists.txt embeds its text as a raw string (generated header
// parametric_gpu_glsl.h, kParametricGpuGlsl) that parametric_shaders.h pastes after #version.
// The static_asserts at the end pin the std430 offsets on the C++ side.
#ifdef __cplusplus
#pragma once
#include <cstddef>
#include <cstdint>

#include <glm/glm.hpp>

namespace tw::gpu {
using vec3 = glm::vec3;
using vec4 = glm::vec4;
using uint = uint32_t;
#define TW_GPU_CONST(type, name, value) inline constexpr type name = value
#else
#define TW_GPU_CONST(type, name, value) const type name = value
#endif

// Shader storage bindings of the parametric passes (the mesh pass uses 0..2; 2, the object
// colour table, and 5, the object states, are shared: gl_shaders.h).
TW_GPU_CONST(int, kInstanceBinding, 3);        // GpuInstance[], the package's whole table
TW_GPU_CONST(int, kParametricDrawBinding, 4);  // GpuParametricDraw[], one per cluster drawn
TW_GPU_CONST(int, kSharedObjectColorBinding, 2);

// Primitive types (pkg::PrimitiveType values).
TW_GPU_CONST(uint, kGpuCylinder, 0u);
TW_GPU_CONST(uint, kGpuCone, 1u);
TW_GPU_CONST(uint, kGpuSphere, 2u);
TW_GPU_CONST(uint, kGpuTorusSegment, 3u);
TW_GPU_CONST(uint, kGpuBox, 4u);
TW_GPU_CONST(uint, kGpuCapped, 1u);  // flags: pkg::kInstanceCapped

// One instance, in its canonical frame (scene.h) placed by origin + linear. 96 bytes.
//   params by type: Cylinder (radius, height, -), Cone (radius_bottom, radius_top, height),
//   Sphere (radius, -, -), Torus (major_radius, minor_radius, sweep_rad), Box (half extents).
struct GpuInstance {
  vec3 origin_m;   // relative to the anchor of the instance's cluster (its bounding-sphere centre)
  uint object;     // object index (the id buffer gets object + 1)
  vec4 axis_x;     // xyz: column 0 of the linear map; w: params[0]
  vec4 axis_y;     // xyz: column 1; w: params[1]
  vec4 axis_z;     // xyz: column 2; w: params[2]
  vec3 local_min;  // proxy box in the canonical frame (tight for the torus segment's sweep)
  uint type;       // kGpuCylinder ..
  vec3 local_max;
  uint flags;      // kGpuCapped
};

// One cluster drawn this frame; indexed by draw_base + gl_DrawIDARB. 16 bytes.
struct GpuParametricDraw {
  vec3 anchor_eye;  // cluster anchor - eye, package frame metres (subtracted in double on the CPU)
  uint cluster;     // cluster index (debugging)
};

#ifdef __cplusplus
static_assert(sizeof(GpuInstance) == 96 && offsetof(GpuInstance, object) == 12 &&
                  offsetof(GpuInstance, axis_x) == 16 && offsetof(GpuInstance, axis_z) == 48 &&
                  offsetof(GpuInstance, local_min) == 64 && offsetof(GpuInstance, type) == 76 &&
                  offsetof(GpuInstance, local_max) == 80 && offsetof(GpuInstance, flags) == 92,
              "GpuInstance must match its std430 layout");
static_assert(sizeof(GpuParametricDraw) == 16 && offsetof(GpuParametricDraw, cluster) == 12,
              "GpuParametricDraw must match its std430 layout");
}  // namespace tw::gpu
#endif
