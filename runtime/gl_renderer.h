// The GL 4.5 core renderer shared by the headless (EGL) and windowed (GLFW) paths.
//
// Renders into its own framebuffer: RGBA8 colour, R32UI object ids (object index + 1, 0 = no
// geometry), 32-bit float depth, reversed Z (camera.h). Mesh clusters come from the GeometryPool
// and are drawn with glMultiDrawElementsIndirect: per-draw data (eye-relative offset of the
// cluster's grid origin, cell size, first triangle in the object pool) sits in an SSBO indexed by
// gl_DrawIDARB; the vertex shader finds each triangle's object through the vertex's tag
// (vertex_object_tags.h; the fragments of the rare untagged triangle through gl_PrimitiveID),
// with the colour setObjectColors gave that object (grey when 0 or absent), and the fragment
// shader lights it with a directional plus hemispheric term using a face normal from
// screen-space derivatives (the package stores no normals).
// GPU time is measured with one GL_TIME_ELAPSED query per frame, from beginFrame to endFrame (so
// no other GL_TIME_ELAPSED query may be active in between), read back without waiting by
// endFrame or with waiting by waitForGpuMs. Back faces are culled for items marked cull_back, or
// for all when asked (setCullBackfaces); otherwise CAD shells, often open, show both sides.
// draw() and beginFrame() set the GL state they need each time (framebuffer, viewport, clip
// control, depth test, culling) and leave reversed-Z clip control set. Needs a current GL 4.5
// context for the renderer's whole life.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "geometry_pool.h"
#include "object_states.h"
#include "section_planes.h"

namespace tw {

// One cluster to draw, prepared by the frame loop in double precision.
struct DrawItem {
  GpuCluster placement;
  glm::vec3 offset_eye{0.0f};  // (grid_origin * cell_m) + origin - eye, world metres, in double then rounded
  float push_m = 0.0f;  // drawDepth only: metres each vertex moves away from the eye (>= 0)
  // draw only: no back face of the cluster can show (closed solids seen from outside), so its
  // clockwise triangles are culled. drawDepth draws both sides whatever this says.
  bool cull_back = false;
};

// The item for a resident cluster's placement seen from `eye` (package frame, metres): the grid
// origin's offset from the eye is computed in double, then rounded.
inline DrawItem makeDrawItem(const GpuCluster& placement, const glm::dvec3& eye) {
  DrawItem item;
  item.placement = placement;
  item.offset_eye = glm::vec3(glm::dvec3(placement.grid_origin) * placement.cell_m - eye);
  return item;
}

struct RendererOptions {
  int width = 1280;
  int height = 720;
  glm::vec3 background{0.72f, 0.80f, 0.90f};
  // Off by default: CAD parts are often open shells, and their inside must stay visible.
  bool cull_backfaces = false;  // counter-clockwise front faces
};

struct RenderStats {
  uint32_t draws = 0;
  uint64_t triangles = 0;
  uint64_t two_sided_triangles = 0;  // of triangles: drawn without back-face culling
  double gpu_ms = 0.0;  // of the last finished frame's draw (timer query); 0 before the first
};

class GlRenderer {
 public:
  // Throws std::runtime_error when GL set-up fails, std::invalid_argument for a size <= 0.
  explicit GlRenderer(const RendererOptions& options);
  ~GlRenderer();
  GlRenderer(const GlRenderer&) = delete;
  GlRenderer& operator=(const GlRenderer&) = delete;

  int width() const;
  int height() const;
  void resize(int width, int height);  // recreates the targets; same exceptions as the constructor

  // Colour per object index (0xAABBGGRR), resolved from the object and layer tables; objects
  // beyond the table draw grey.
  void setObjectColors(std::span<const uint32_t> rgba);
  // Per-object state (object_states.h) for the objects setObjectColors gave, in one upload;
  // entries past them are ignored. setObjectColors resets every state to none.
  void setObjectStates(std::span<const GpuObjectState> states);

  // The surface pass the following draws belong to (object_states.h). In SurfacePass::Xray,
  // draw() and other surface passes (bindSurfaceState) blend the ghost colour over the frame at
  // kXrayAlpha, test depth against it without writing depth, and write no ids. Setting Opaque
  // again restores the opaque state (colour, ids and depth written, no blending).
  void setSurfacePass(SurfacePass pass);
  SurfacePass surfacePass() const;
  // The section planes (section_planes.h, package frame) every surface pass clips by from now
  // on, seen from `eye` (package frame; call again when the eye moves); empty: none. While any is
  // active nothing is back-face culled (the cut shows insides) and the inside of a cut solid is
  // filled in the section colour. Throws std::invalid_argument for more than
  // kMaxSectionPlanes.
  void setSections(std::span<const SectionPlane> planes, const glm::dvec3& eye);
  bool sectionsActive() const;
  static constexpr float kXrayAlpha = 0.22f;
  // The GL state of a surface draw of the current pass into `framebuffer` (the renderer's own
  // targets, or one of the same size and attachments): target, viewport, reversed-Z clip
  // control, depth test, masks and blending, and the pass, object colour and object state
  // buffers bound. Every program that includes gl_shaders.h's objectColorGlsl draws under it.
  void bindSurfaceState() const;
  void bindSurfaceState(unsigned framebuffer) const;
  // Outlines the selected objects (object_states.h) on the frame's colour from its ids: call
  // after the frame's surface passes, before endFrame.
  void drawSelectionOutlines();

  // Clears colour, ids and depth, and sets the camera (rotation and projection; positions come
  // eye-relative through DrawItem::offset_eye).
  void beginFrame(const glm::mat4& view_rotation, const glm::mat4& projection);
  // Multi-draws over the pool, one per combination of culling (cull_back or not) and program
  // (placement.object_per_triangle or not), items in their order within each; may be called
  // several times per frame. Items with no triangles are skipped. Throws std::out_of_range,
  // drawing nothing, when an item's ranges lie outside the pool's layout.
  void draw(const GeometryPool& pool, std::span<const DrawItem> items);
  // Depth only, for occlusion: draws `items` into `framebuffer` (which must have a 32-bit float
  // depth attachment of the renderer's size, and may have no colour) with the camera of the last
  // beginFrame, depth test GL_GREATER and depth writes on, each vertex pushed away from the eye by
  // its item's push_m. Counts nothing into the frame's draws or triangles; returns the triangles
  // drawn. Same checks and exceptions as draw().
  uint64_t drawDepth(const GeometryPool& pool, std::span<const DrawItem> items,
                     unsigned framebuffer);
  // Ends the frame (timer query) and waits for nothing: gpu_ms is that of the newest frame whose
  // query has finished (usually one or two frames old), 0 before any has.
  RenderStats endFrame();
  // Blocks until the last ended frame's timer query is available and returns its GPU ms (for
  // headless runs that read every frame back anyway); 0 when no frame was ended yet.
  double waitForGpuMs();
  void setCullBackfaces(bool cull);

  // Reads back the last frame (blocks on the GPU). Rows bottom-up as GL gives them when
  // flip_y is false; top-down (image order) when true.
  void readColor(std::vector<uint8_t>& rgba, bool flip_y = true) const;
  void readObjectIds(std::vector<uint32_t>& ids, bool flip_y = true) const;
  // Reversed-Z depth (1 near, 0 far and background), same row order rules.
  void readDepth(std::vector<float>& depth, bool flip_y = true) const;
  // Copies the colour to the default framebuffer (windowed mode) at its size, and leaves the
  // default framebuffer bound with a viewport of that size, for overlays drawn after it.
  void blitToScreen(int screen_width, int screen_height) const;

  // GL names, for passes that render into or read the same targets (e.g. occlusion, overlays).
  unsigned framebuffer() const;
  unsigned depthTexture() const;  // GL_DEPTH_COMPONENT32F, reversed Z (1 near, 0 far/empty)
  // For other surface passes that colour objects the same way (parametric_renderer.h): the
  // object colour SSBO (uint 0xAABBGGRR per object, bind at gl_shaders.h kObjectColorBinding),
  // its entry count, and projection * view rotation of the last beginFrame.
  unsigned objectColorBuffer() const;
  unsigned objectStateBuffer() const;  // GpuObjectState per object, at kObjectStateBinding
  uint32_t objectColorCount() const;
  const glm::mat4& viewProjection() const;

 private:
  uint64_t prepareDraws(const GeometryPool& pool, std::span<const DrawItem> items);
  void drawBatch(const GeometryPool& pool, std::span<const DrawItem> items, bool cull_back,
                 bool object_per_triangle);

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tw
