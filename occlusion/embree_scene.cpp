// Embree 3 device/scene ownership, mesh upload and ray queries behind EmbreeScene.
#include "embree_scene.h"

#include <cstring>
#include <deque>
#include <mutex>
#include <stdexcept>
#include <string>

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace tw {

namespace {

const char* errorName(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_UNKNOWN: return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
  }
  return "unrecognised error";
}

void initRayHit(const Ray& ray, RTCRayHit& rh) {
  rh.ray.org_x = ray.origin.x;
  rh.ray.org_y = ray.origin.y;
  rh.ray.org_z = ray.origin.z;
  rh.ray.tnear = ray.t_near;
  rh.ray.dir_x = ray.direction.x;
  rh.ray.dir_y = ray.direction.y;
  rh.ray.dir_z = ray.direction.z;
  rh.ray.time = 0.0f;
  rh.ray.tfar = ray.t_far;
  rh.ray.mask = 0xffffffffu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

// Batches are cut into blocks of this many rays: large enough to amortise scheduling, small
// enough to balance two to a few dozen cores.
constexpr size_t kRayBlock = 256;

}  // namespace

struct EmbreeScene::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;

  // Embree reports errors through a callback that may run on any thread, in the middle of C
  // code; throwing there is not safe. The callback records the first error, and every API step
  // of ours checks it afterwards and throws from C++.
  mutable std::mutex error_mutex;
  std::string first_error;

  // Buffers Embree reads in place (moving addMesh overload). A deque never moves its elements,
  // and moving a vector keeps its data pointer, so the pointers Embree holds stay valid.
  std::deque<std::vector<glm::vec3>> owned_positions;
  std::deque<std::vector<uint32_t>> owned_indices;

  static void onError(void* user, RTCError code, const char* message) {
    auto* self = static_cast<Impl*>(user);
    std::lock_guard<std::mutex> lock(self->error_mutex);
    if (self->first_error.empty())
      self->first_error = std::string(errorName(code)) + (message ? std::string(": ") + message : "");
  }
};

EmbreeScene::EmbreeScene(const glm::dvec3& origin) : origin_(origin), impl_(std::make_unique<Impl>()) {
  // 1. The device: Embree's thread pool, memory and error reporting. One per scene keeps
  //    scenes independent; the cost is a few milliseconds.
  impl_->device = rtcNewDevice(nullptr);
  if (!impl_->device)
    throw std::runtime_error(std::string("Embree: cannot create device: ") +
                             errorName(rtcGetDeviceError(nullptr)));
  rtcSetDeviceErrorFunction(impl_->device, &Impl::onError, impl_.get());

  // 2. The scene: a flat list of triangle geometries under one BVH. Medium build quality is
  //    Embree's default SAH builder; static (no FLAG_DYNAMIC) since we build once.
  impl_->scene = rtcNewScene(impl_->device);
  if (!impl_->scene) {
    rtcReleaseDevice(impl_->device);
    throw std::runtime_error("Embree: cannot create scene");
  }
  rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_NONE);
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_MEDIUM);
}

EmbreeScene::~EmbreeScene() {
  if (impl_->scene) rtcReleaseScene(impl_->scene);
  if (impl_->device) rtcReleaseDevice(impl_->device);
}

void EmbreeScene::throwIfError(const char* what) const {
  std::lock_guard<std::mutex> lock(impl_->error_mutex);
  if (!impl_->first_error.empty())
    throw std::runtime_error(std::string("Embree error during ") + what + ": " + impl_->first_error);
}

static void validateMesh(size_t position_count, std::span<const uint32_t> indices) {
  if (indices.size() % 3 != 0)
    throw std::invalid_argument("EmbreeScene::addMesh: index count " + std::to_string(indices.size()) +
                                " is not a multiple of 3");
  if (position_count > 0xffffffffull)
    throw std::invalid_argument("EmbreeScene::addMesh: more than 2^32 vertices in one mesh");
  for (uint32_t i : indices)
    if (i >= position_count)
      throw std::invalid_argument("EmbreeScene::addMesh: index " + std::to_string(i) +
                                  " out of range (" + std::to_string(position_count) + " vertices)");
}

uint32_t EmbreeScene::attach(void* geometry_handle, uint64_t triangle_count, uint32_t user_id) {
  const auto id = static_cast<uint32_t>(user_ids_.size());
  user_ids_.push_back(user_id);
  if (geometry_handle) {
    auto geometry = static_cast<RTCGeometry>(geometry_handle);
    // 4. Commit the geometry, attach it under our own sequential id (so empty meshes, which
    //    are never attached, still get an id) and drop our reference: the scene keeps one.
    rtcCommitGeometry(geometry);
    rtcAttachGeometryByID(impl_->scene, geometry, id);
    rtcReleaseGeometry(geometry);
    triangles_ += triangle_count;
  }
  throwIfError("addMesh");
  return id;
}

uint32_t EmbreeScene::addMesh(std::span<const glm::vec3> positions_rel,
                              std::span<const uint32_t> indices, uint32_t user_id) {
  if (committed_) throw std::logic_error("EmbreeScene::addMesh after commit");
  validateMesh(positions_rel.size(), indices);
  if (indices.empty()) return attach(nullptr, 0, user_id);

  // 3. A triangle geometry with buffers Embree allocates (and pads for its SIMD loads); we
  //    copy our data into them.
  RTCGeometry geometry = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, sizeof(float) * 3, positions_rel.size()));
  auto* triangles = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, sizeof(uint32_t) * 3, indices.size() / 3));
  if (!vertices || !triangles) {
    rtcReleaseGeometry(geometry);
    throwIfError("addMesh");
    throw std::runtime_error("Embree: cannot allocate geometry buffers");
  }
  for (size_t i = 0; i < positions_rel.size(); ++i) {
    vertices[3 * i + 0] = positions_rel[i].x;
    vertices[3 * i + 1] = positions_rel[i].y;
    vertices[3 * i + 2] = positions_rel[i].z;
  }
  std::memcpy(triangles, indices.data(), indices.size_bytes());
  return attach(geometry, indices.size() / 3, user_id);
}

uint32_t EmbreeScene::addMesh(std::vector<glm::vec3>&& positions_rel, std::vector<uint32_t>&& indices,
                              uint32_t user_id) {
  if (committed_) throw std::logic_error("EmbreeScene::addMesh after commit");
  validateMesh(positions_rel.size(), indices);
  if (indices.empty()) return attach(nullptr, 0, user_id);

  // 3. A triangle geometry sharing our vectors. Embree reads vertices with 16-byte loads, so
  //    the last vertex needs 4 readable bytes after it: one padding vertex covers that.
  const size_t vertex_count = positions_rel.size();
  const size_t triangle_count = indices.size() / 3;
  positions_rel.emplace_back(0.0f);
  auto& positions = impl_->owned_positions.emplace_back(std::move(positions_rel));
  auto& triangles = impl_->owned_indices.emplace_back(std::move(indices));
  RTCGeometry geometry = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, positions.data(), 0,
                             sizeof(glm::vec3), vertex_count);
  rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, triangles.data(), 0,
                             sizeof(uint32_t) * 3, triangle_count);
  return attach(geometry, triangle_count, user_id);
}

void EmbreeScene::commit() {
  if (committed_) throw std::logic_error("EmbreeScene::commit called twice");
  // 5. Build the BVH over every attached geometry. Embree runs this on its TBB thread pool.
  rtcCommitScene(impl_->scene);
  throwIfError("commit");
  committed_ = true;
}

static EmbreeScene::Hit toHit(const RTCRayHit& rh, const std::vector<uint32_t>& user_ids) {
  EmbreeScene::Hit hit;
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
  hit.hit = true;
  hit.t = rh.ray.tfar;
  glm::vec3 ng(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
  float len = glm::length(ng);
  hit.normal = len > 0.0f ? ng / len : glm::vec3(0.0f, 0.0f, 1.0f);
  hit.u = rh.hit.u;
  hit.v = rh.hit.v;
  hit.geometry = rh.hit.geomID;
  hit.primitive = rh.hit.primID;
  hit.user_id = rh.hit.geomID < user_ids.size() ? user_ids[rh.hit.geomID] : 0;
  return hit;
}

// 6. Queries: one context per call; the coherent flag lets Embree use its stream-friendly
//    traversal for camera rays.
EmbreeScene::Hit EmbreeScene::intersect(const Ray& ray) const {
  if (!committed_) throw std::logic_error("EmbreeScene::intersect before commit");
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh;
  initRayHit(ray, rh);
  rtcIntersect1(impl_->scene, &context, &rh);
  return toHit(rh, user_ids_);
}

EmbreeScene::Hit EmbreeScene::intersectCoherent(const Ray& ray) const {
  if (!committed_) throw std::logic_error("EmbreeScene::intersect before commit");
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  RTCRayHit rh;
  initRayHit(ray, rh);
  rtcIntersect1(impl_->scene, &context, &rh);
  return toHit(rh, user_ids_);
}

bool EmbreeScene::occluded(const Ray& ray) const {
  if (!committed_) throw std::logic_error("EmbreeScene::occluded before commit");
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh;
  initRayHit(ray, rh);
  rtcOccluded1(impl_->scene, &context, &rh.ray);
  // Embree marks an occluded ray by setting tfar to -infinity.
  return rh.ray.tfar < 0.0f;
}

void EmbreeScene::intersect(std::span<const Ray> rays, std::span<Hit> hits, bool coherent) const {
  if (!committed_) throw std::logic_error("EmbreeScene::intersect before commit");
  if (hits.size() < rays.size()) throw std::invalid_argument("EmbreeScene::intersect: hits too short");
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), kRayBlock), [&](const auto& range) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    if (coherent) context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    for (size_t i = range.begin(); i != range.end(); ++i) {
      RTCRayHit rh;
      initRayHit(rays[i], rh);
      rtcIntersect1(impl_->scene, &context, &rh);
      hits[i] = toHit(rh, user_ids_);
    }
  });
}

void EmbreeScene::occluded(std::span<const Ray> rays, std::span<uint8_t> blocked, bool coherent) const {
  if (!committed_) throw std::logic_error("EmbreeScene::occluded before commit");
  if (blocked.size() < rays.size()) throw std::invalid_argument("EmbreeScene::occluded: output too short");
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), kRayBlock), [&](const auto& range) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    if (coherent) context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    for (size_t i = range.begin(); i != range.end(); ++i) {
      RTCRayHit rh;
      initRayHit(rays[i], rh);
      rtcOccluded1(impl_->scene, &context, &rh.ray);
      blocked[i] = rh.ray.tfar < 0.0f ? 1 : 0;
    }
  });
}

}  // namespace tw
