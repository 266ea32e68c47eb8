// Frame comparison (PSNR, colour and id mismatch within a pixel neighbourhood) and PNG I/O.
//
// This translation unit holds the one definition of stb_image and stb_image_write for tw_runtime:
// other files include the headers without the *_IMPLEMENTATION macros.
#include "image_compare.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <system_error>

#include "format_error.h"

// stb is third-party C: keep its warnings out of ours.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wall"
#pragma GCC diagnostic ignored "-Wextra"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wunused-but-set-variable"
#pragma GCC diagnostic ignored "-Wsign-compare"
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb_image.h>
#include <stb_image_write.h>
#pragma GCC diagnostic pop

namespace tw {
namespace {

inline int absDiff(uint8_t a, uint8_t b) { return a > b ? a - b : b - a; }

inline bool colourClose(const uint8_t* p, const uint8_t* q, int threshold) {
  return absDiff(p[0], q[0]) <= threshold && absDiff(p[1], q[1]) <= threshold &&
         absDiff(p[2], q[2]) <= threshold;
}

// The neighbourhood of one pixel, clipped to the image (inclusive bounds).
struct Window {
  int x0, x1, y0, y1;
};

// True when `other` (RGBA8 rows of `width` pixels) has a pixel inside `w` close to `pixel`.
inline bool colourFound(const uint8_t* pixel, const uint8_t* other, size_t width, const Window& w,
                        int threshold) {
  for (int y = w.y0; y <= w.y1; ++y) {
    const uint8_t* row = other + size_t(y) * width * 4;
    for (int x = w.x0; x <= w.x1; ++x)
      if (colourClose(pixel, row + size_t(x) * 4, threshold)) return true;
  }
  return false;
}

inline bool idFound(uint32_t id, const uint32_t* other, size_t width, const Window& w) {
  for (int y = w.y0; y <= w.y1; ++y) {
    const uint32_t* row = other + size_t(y) * width;
    for (int x = w.x0; x <= w.x1; ++x)
      if (row[x] == id) return true;
  }
  return false;
}

// The background of the diff image: the reference's luminance, dimmed so that red and magenta
// stand out, opaque.
inline void writeDimmed(const uint8_t* reference, uint8_t* out) {
  const int luminance = (54 * reference[0] + 183 * reference[1] + 19 * reference[2]) >> 8;
  const auto grey = static_cast<uint8_t>(32 + luminance * 3 / 8);
  out[0] = out[1] = out[2] = grey;
  out[3] = 255;
}

inline void writeColour(uint8_t* out, uint8_t r, uint8_t g, uint8_t b) {
  out[0] = r;
  out[1] = g;
  out[2] = b;
  out[3] = 255;
}

}  // namespace

ImageCompareResult compareImages(int width, int height, std::span<const uint8_t> rgba_a,
                                 std::span<const uint8_t> rgba_b, std::span<const uint32_t> ids_a,
                                 std::span<const uint32_t> ids_b,
                                 const ImageCompareOptions& options,
                                 std::vector<uint8_t>* diff_rgba) {
  if (width < 0 || height < 0)
    throw std::invalid_argument("compareImages: negative image size " + std::to_string(width) +
                                "x" + std::to_string(height));
  const size_t pixels = size_t(width) * size_t(height);
  if (rgba_a.size() != pixels * 4 || rgba_b.size() != pixels * 4)
    throw std::invalid_argument("compareImages: colour buffers of " +
                                std::to_string(rgba_a.size()) + " and " +
                                std::to_string(rgba_b.size()) + " bytes for a " +
                                std::to_string(width) + "x" + std::to_string(height) + " image");
  const bool with_ids = !ids_a.empty() || !ids_b.empty();
  if (with_ids && (ids_a.size() != pixels || ids_b.size() != pixels))
    throw std::invalid_argument("compareImages: id buffers of " + std::to_string(ids_a.size()) +
                                " and " + std::to_string(ids_b.size()) + " pixels for a " +
                                std::to_string(width) + "x" + std::to_string(height) + " image");
  if (options.neighbourhood_px < 0)
    throw std::invalid_argument("compareImages: negative neighbourhood_px");
  if (options.colour_threshold < 0 || options.colour_threshold > 255)
    throw std::invalid_argument("compareImages: colour_threshold outside 0..255");

  ImageCompareResult result;
  result.width = width;
  result.height = height;
  if (diff_rgba) diff_rgba->resize(pixels * 4);
  if (pixels == 0) {
    result.psnr_db = kIdenticalPsnrDb;
    result.match_share = 1.0;
    return result;
  }

  const uint8_t* a = rgba_a.data();
  const uint8_t* b = rgba_b.data();
  uint8_t* diff = diff_rgba ? diff_rgba->data() : nullptr;
  const int r = options.neighbourhood_px;
  const int threshold = options.colour_threshold;
  uint64_t squared_error = 0;
  uint64_t colour_bad = 0, id_bad = 0, any_bad = 0;

  for (int y = 0; y < height; ++y) {
    const int y0 = std::max(0, y - r), y1 = std::min(height - 1, y + r);
    for (int x = 0; x < width; ++x) {
      const size_t i = size_t(y) * size_t(width) + size_t(x);
      const uint8_t* pa = a + i * 4;
      const uint8_t* pb = b + i * 4;
      const int dr = pa[0] - pb[0], dg = pa[1] - pb[1], db = pa[2] - pb[2];
      squared_error += uint64_t(dr * dr + dg * dg + db * db);

      // The pixel at the same place is in both neighbourhoods and closeness is symmetric, so
      // when it matches both directions do; only the rare others pay for the window search.
      const Window window{std::max(0, x - r), std::min(width - 1, x + r), y0, y1};
      bool colour_mismatch = false;
      if (!colourClose(pa, pb, threshold))
        colour_mismatch = !colourFound(pa, b, size_t(width), window, threshold) ||
                          !colourFound(pb, a, size_t(width), window, threshold);
      bool id_mismatch = false;
      if (with_ids && ids_a[i] != ids_b[i])
        id_mismatch = !idFound(ids_a[i], ids_b.data(), size_t(width), window) ||
                      !idFound(ids_b[i], ids_a.data(), size_t(width), window);

      colour_bad += colour_mismatch;
      id_bad += id_mismatch;
      any_bad += colour_mismatch || id_mismatch;
      if (diff) {
        uint8_t* out = diff + i * 4;
        if (id_mismatch) writeColour(out, 255, 0, 255);
        else if (colour_mismatch) writeColour(out, 255, 0, 0);
        else writeDimmed(pa, out);
      }
    }
  }

  const double n = double(pixels);
  if (squared_error == 0) {
    result.psnr_db = kIdenticalPsnrDb;
  } else {
    const double mse = double(squared_error) / (3.0 * n);
    result.psnr_db = 10.0 * std::log10(255.0 * 255.0 / mse);
  }
  result.colour_mismatch_share = double(colour_bad) / n;
  result.id_mismatch_share = double(id_bad) / n;
  result.match_share = 1.0 - double(any_bad) / n;
  return result;
}

RgbaImage readPngRgba(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw FormatError(name, "no such file");
  const uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) throw FormatError(name, "cannot read: " + ec.message());
  // stb takes an int length; no sane frame comes near it.
  if (size > uintmax_t(1) << 30) throw FormatError(name, "file too large for a PNG frame");

  std::vector<uint8_t> bytes(static_cast<size_t>(size));
  {
    std::ifstream in(path, std::ios::binary);
    if (!in || !in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(bytes.size())))
      throw FormatError(name, "cannot read");
  }
  return decodePngRgba(bytes, name);
}

RgbaImage decodePngRgba(std::span<const uint8_t> bytes, const std::string& name) {
  static constexpr uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (bytes.size() < sizeof kSignature || std::memcmp(bytes.data(), kSignature, 8) != 0)
    throw FormatError::atByte(name, 0, "not a PNG file (bad signature)");
  if (bytes.size() > size_t(1) << 30) throw FormatError(name, "too large for a PNG frame");

  const int length = static_cast<int>(bytes.size());
  int w = 0, h = 0, channels = 0;
  if (!stbi_info_from_memory(bytes.data(), length, &w, &h, &channels))
    throw FormatError(name, std::string("corrupt PNG: ") + stbi_failure_reason());
  if (w <= 0 || h <= 0 || uint64_t(w) * uint64_t(h) > kMaxPngPixels)
    throw FormatError(name, "PNG size " + std::to_string(w) + "x" + std::to_string(h) +
                                " is outside 1.." + std::to_string(kMaxPngPixels) + " pixels");

  stbi_uc* pixels = stbi_load_from_memory(bytes.data(), length, &w, &h, &channels, 4);
  if (!pixels) throw FormatError(name, std::string("corrupt PNG: ") + stbi_failure_reason());
  RgbaImage image;
  image.width = w;
  image.height = h;
  image.rgba.assign(pixels, pixels + size_t(w) * size_t(h) * 4);
  stbi_image_free(pixels);
  return image;
}

void writePngRgba(const std::filesystem::path& path, int width, int height,
                  std::span<const uint8_t> rgba) {
  if (width <= 0 || height <= 0 || rgba.size() != size_t(width) * size_t(height) * 4)
    throw std::invalid_argument("writePngRgba: " + std::to_string(rgba.size()) + " bytes for a " +
                                std::to_string(width) + "x" + std::to_string(height) + " image");
  if (!stbi_write_png(path.string().c_str(), width, height, 4, rgba.data(), width * 4))
    throw std::runtime_error(path.string() + ": cannot write PNG");
}

std::vector<uint8_t> encodePngRgba(int width, int height, std::span<const uint8_t> rgba) {
  if (width <= 0 || height <= 0 || rgba.size() != size_t(width) * size_t(height) * 4)
    throw std::invalid_argument("encodePngRgba: " + std::to_string(rgba.size()) + " bytes for a " +
                                std::to_string(width) + "x" + std::to_string(height) + " image");
  std::vector<uint8_t> png;
  const auto append = [](void* context, void* data, int size) {
    auto* out = static_cast<std::vector<uint8_t>*>(context);
    const auto* bytes = static_cast<const uint8_t*>(data);
    out->insert(out->end(), bytes, bytes + size);
  };
  if (!stbi_write_png_to_func(append, &png, width, height, 4, rgba.data(), width * 4))
    throw std::runtime_error("cannot encode a PNG");
  return png;
}

IdCensus censusOf(std::span<const uint32_t> ids) {
  std::vector<uint32_t> shown;
  shown.reserve(ids.size());
  for (uint32_t id : ids)
    if (id != 0) shown.push_back(id);
  IdCensus census;
  census.covered_pixels = shown.size();
  std::sort(shown.begin(), shown.end());
  census.visible_objects = uint64_t(std::unique(shown.begin(), shown.end()) - shown.begin());
  return census;
}

std::vector<uint32_t> idsFromRgba(std::span<const uint8_t> rgba) {
  if (rgba.size() % 4 != 0)
    throw std::invalid_argument("idsFromRgba: " + std::to_string(rgba.size()) +
                                " bytes is not a whole number of RGBA pixels");
  std::vector<uint32_t> ids(rgba.size() / 4);
  for (size_t i = 0; i < ids.size(); ++i) {
    const uint8_t* p = rgba.data() + i * 4;
    ids[i] = uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
  }
  return ids;
}

std::vector<uint8_t> idsToRgba(std::span<const uint32_t> ids) {
  std::vector<uint8_t> rgba(ids.size() * 4);
  for (size_t i = 0; i < ids.size(); ++i) {
    rgba[i * 4 + 0] = uint8_t(ids[i]);
    rgba[i * 4 + 1] = uint8_t(ids[i] >> 8);
    rgba[i * 4 + 2] = uint8_t(ids[i] >> 16);
    rgba[i * 4 + 3] = uint8_t(ids[i] >> 24);
  }
  return rgba;
}

}  // namespace tw
