// Primary rays, shading and PNG writing for snapshots.
#include "snapshot_render.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <string>
#include <system_error>

#include <stb_image_write.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace tw {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr uint32_t kMaxImageSide = 16384;

// Lighting weights (linear). Ambient is a hemisphere term so that faces turned up read lighter
// than faces turned down even in shadow; the headlight keeps faces facing the viewer visible.
constexpr float kAmbient = 0.30f;
constexpr float kHeadlight = 0.35f;
constexpr float kSun = 0.60f;
constexpr float kHazeStrength = 0.25f;  // how far the farthest geometry fades towards the haze

float srgbToLinear(float c) { return std::pow(c, 2.2f); }
uint8_t linearToSrgb8(float c) {
  c = std::clamp(c, 0.0f, 1.0f);
  return static_cast<uint8_t>(std::lround(std::pow(c, 1.0f / 2.2f) * 255.0f));
}

glm::vec3 rgbaToLinear(uint32_t rgba) {
  return {srgbToLinear(float(rgba & 0xffu) / 255.0f), srgbToLinear(float((rgba >> 8) & 0xffu) / 255.0f),
          srgbToLinear(float((rgba >> 16) & 0xffu) / 255.0f)};
}

// Distinct, soft colours for ids: golden-ratio hue steps at fixed saturation and value.
glm::vec3 objectPastel(uint32_t id) {
  uint32_t h = id * 0x9e3779b9u;
  h ^= h >> 16;
  float hue = float(h & 0xffffu) / 65536.0f * 6.0f;
  float s = 0.35f, v = 0.88f;
  int sector = static_cast<int>(hue) % 6;
  float f = hue - std::floor(hue);
  float p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  glm::vec3 rgb;
  switch (sector) {
    case 0: rgb = {v, t, p}; break;
    case 1: rgb = {q, v, p}; break;
    case 2: rgb = {p, v, t}; break;
    case 3: rgb = {p, q, v}; break;
    case 4: rgb = {t, p, v}; break;
    default: rgb = {v, p, q}; break;
  }
  return {srgbToLinear(rgb.r), srgbToLinear(rgb.g), srgbToLinear(rgb.b)};
}

}  // namespace

glm::vec3 snapshotSkyColor(double row_fraction) {
  // Deeper blue at the top to a pale haze at the bottom.
  const glm::vec3 top = {srgbToLinear(0.42f), srgbToLinear(0.58f), srgbToLinear(0.80f)};
  const glm::vec3 bottom = {srgbToLinear(0.90f), srgbToLinear(0.92f), srgbToLinear(0.95f)};
  float f = static_cast<float>(std::clamp(row_fraction, 0.0, 1.0));
  return glm::mix(top, bottom, std::sqrt(f));
}

SnapshotRenderResult renderSnapshot(const SnapshotScene& scene, const SnapshotCamera& camera,
                                    const SnapshotRenderOptions& options, Progress* progress) {
  if (!scene.rt || !scene.rt->committed()) throw std::logic_error("renderSnapshot: scene not committed");
  if (options.width == 0 || options.height == 0 || options.width > kMaxImageSide || options.height > kMaxImageSide)
    throw std::invalid_argument("snapshot image size must be 1.." + std::to_string(kMaxImageSide) + " pixels a side");
  const uint32_t width = options.width, height = options.height;
  const uint32_t samples = std::clamp(options.samples, 1u, 8u);
  const EmbreeScene& rt = *scene.rt;

  const bool by_object = options.color_by == SnapshotColorBy::Object ||
                         (options.color_by == SnapshotColorBy::Auto && scene.distinct_colors <= 1 && scene.objects > 1);

  // Camera in the scene's float frame: the eye relative to the scene origin, directions as is.
  const CameraFrame frame = cameraFrame(camera);
  const glm::vec3 eye = rt.toScene(camera.eye);
  const glm::vec3 forward(frame.forward), right(frame.right), image_up(frame.up);
  const double tan_y = std::tan(std::clamp(camera.fov_y_deg, 1.0, 170.0) * kPi / 360.0);
  const float tan_half_y = static_cast<float>(tan_y);
  const float tan_half_x = static_cast<float>(tan_y * double(width) / double(height));

  // Sun from above, front-left of the model's conventional front; fixed in the world so that
  // turning the camera does not move the shadows.
  const glm::dvec3 world_up = glm::normalize(camera.up);
  const glm::dvec3 front = frontFor(world_up);
  const glm::dvec3 side = glm::cross(world_up, front);
  const double sun_el = 50.0 * kPi / 180.0, sun_az = -40.0 * kPi / 180.0;
  const glm::vec3 sun(glm::normalize(std::cos(sun_el) * (std::cos(sun_az) * front + std::sin(sun_az) * side) +
                                     std::sin(sun_el) * world_up));
  const glm::vec3 up_f(world_up);

  // Haze runs from the nearest to the farthest point of the model's bounding sphere.
  double radius = 0.5 * glm::length(scene.bounds.extent());
  double centre_distance = scene.bounds.empty() ? 1.0 : glm::length(scene.bounds.center() - camera.eye);
  const float haze_near = static_cast<float>(std::max(0.0, centre_distance - radius));
  const float haze_range = static_cast<float>(std::max(2.0 * radius, 1e-9));
  // Shadow rays start this far off the surface, above float noise at the model's scale.
  const float shadow_offset = static_cast<float>(std::max(1e-5 * 2.0 * radius, 1e-7));

  SnapshotRenderResult result;
  result.image.width = width;
  result.image.height = height;
  result.image.rgb.assign(size_t(width) * height * 3, 0);
  std::atomic<uint64_t> hit_pixels{0}, rays{0};

  auto shadePixel = [&](uint32_t x, uint32_t y, const glm::vec3& sky, bool& any_hit, uint64_t& ray_count) {
    glm::vec3 sum(0.0f);
    for (uint32_t sy = 0; sy < samples; ++sy) {
      for (uint32_t sx = 0; sx < samples; ++sx) {
        float px = (float(x) + (float(sx) + 0.5f) / float(samples)) / float(width) * 2.0f - 1.0f;
        float py = 1.0f - (float(y) + (float(sy) + 0.5f) / float(samples)) / float(height) * 2.0f;
        Ray ray;
        ray.origin = eye;
        ray.direction = glm::normalize(forward + px * tan_half_x * right + py * tan_half_y * image_up);
        EmbreeScene::Hit hit = rt.intersectCoherent(ray);
        ++ray_count;
        if (!hit.hit) {
          sum += sky;
          continue;
        }
        any_hit = true;
        const SnapshotScene::Slot& slot = scene.slotOf(hit);
        glm::vec3 base = by_object ? objectPastel(slot.object_id) : rgbaToLinear(slot.color_rgba);
        glm::vec3 n = glm::dot(hit.normal, ray.direction) > 0.0f ? -hit.normal : hit.normal;

        float ambient = kAmbient * (0.65f + 0.35f * glm::dot(n, up_f));
        float headlight = kHeadlight * std::max(0.0f, -glm::dot(n, ray.direction));
        float sun_light = kSun * std::max(0.0f, glm::dot(n, sun));
        if (options.shadows && sun_light > 0.0f) {
          Ray shadow;
          shadow.origin = ray.origin + hit.t * ray.direction + n * shadow_offset;
          shadow.direction = sun;
          ++ray_count;
          if (rt.occluded(shadow)) sun_light = 0.0f;
        }
        glm::vec3 c = base * (ambient + headlight + sun_light);
        float haze = kHazeStrength * std::clamp((hit.t - haze_near) / haze_range, 0.0f, 1.0f);
        sum += glm::mix(c, sky, haze);
      }
    }
    return sum / float(samples * samples);
  };

  // Bands of rows: parallel inside a band, progress and cancellation between bands (Progress
  // is not required to be thread-safe).
  beginStage(progress, "render", height);
  const uint32_t band = std::max(1u, std::min(height, 32u));
  for (uint32_t y0 = 0; y0 < height; y0 += band) {
    if (progress && progress->cancelled()) {
      endStage(progress);
      throw std::runtime_error("cancelled");
    }
    const uint32_t y1 = std::min(height, y0 + band);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(y0, y1, 1), [&](const tbb::blocked_range<uint32_t>& rows) {
      uint64_t local_hits = 0, local_rays = 0;
      for (uint32_t y = rows.begin(); y != rows.end(); ++y) {
        const glm::vec3 sky = snapshotSkyColor((double(y) + 0.5) / double(height));
        uint8_t* out = &result.image.rgb[size_t(y) * width * 3];
        for (uint32_t x = 0; x < width; ++x) {
          bool any_hit = false;
          glm::vec3 c = shadePixel(x, y, sky, any_hit, local_rays);
          local_hits += any_hit ? 1 : 0;
          out[3 * x + 0] = linearToSrgb8(c.r);
          out[3 * x + 1] = linearToSrgb8(c.g);
          out[3 * x + 2] = linearToSrgb8(c.b);
        }
      }
      hit_pixels += local_hits;
      rays += local_rays;
    });
    updateProgress(progress, y1);
  }
  endStage(progress);
  result.hit_pixels = hit_pixels.load();
  result.rays = rays.load();
  return result;
}

void writePng(const SnapshotImage& image, const std::filesystem::path& path) {
  if (image.width == 0 || image.height == 0 || image.rgb.size() != size_t(image.width) * image.height * 3)
    throw std::invalid_argument("writePng: image buffer does not match its size");
  std::filesystem::path temp = path;
  temp += ".tmp";
  int ok = stbi_write_png(temp.string().c_str(), static_cast<int>(image.width), static_cast<int>(image.height), 3,
                          image.rgb.data(), static_cast<int>(image.width * 3));
  if (!ok) {
    std::error_code ignored;
    std::filesystem::remove(temp, ignored);
    throw std::runtime_error("cannot write PNG '" + path.string() + "'");
  }
  std::error_code ec;
  std::filesystem::rename(temp, path, ec);
  if (ec) {
    std::filesystem::remove(temp, ec);
    throw std::runtime_error("cannot write PNG '" + path.string() + "': " + ec.message());
  }
}

}  // namespace tw
