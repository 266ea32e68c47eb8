// Image comparison for `terawalk compare`: how far an LOD render is from the brute-force
// reference, frame by frame, by colour (PSNR) and by object id, with a 1-pixel neighbourhood
// tolerance (a pixel matches when some pixel within one pixel of it in the other image matches;
// LOD silhouettes move by up to a pixel by design).
//
// Also the runtime's PNG reading and writing (stb_image / stb_image_write are compiled into
// image_compare.cpp, the one place in tw_runtime that defines their implementations).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

namespace tw {

struct ImageCompareOptions {
  int neighbourhood_px = 1;     // tolerance radius (Chebyshev), >= 0
  int colour_threshold = 24;    // max per-channel difference (0..255) for a colour match
};

struct ImageCompareResult {
  int width = 0, height = 0;
  double psnr_db = 0.0;                // of RGB, +inf for identical images (stored as 999)
  double colour_mismatch_share = 0.0;  // pixels with no colour match in the neighbourhood
  double id_mismatch_share = 0.0;      // pixels with no id match in the neighbourhood (ids given)
  double match_share = 0.0;            // pixels matching in colour and (when given) id
};

// PSNR reported for identical images (whose true PSNR is +inf), so that JSON and CSV stay finite.
inline constexpr double kIdenticalPsnrDb = 999.0;

// rgba: width*height*4 bytes each, same size; ids: width*height each or both empty.
// diff_rgba (optional, resized): mismatching pixels in red (colour) / magenta (id), the rest as
// a dimmed grey of the reference.
//
// Details of the contract:
// - Colour compares R, G and B (alpha is ignored: frames are opaque). Two pixels match in colour
//   when every one of R, G, B differs by at most colour_threshold.
// - A pixel is mismatched when A's pixel has no match among B's pixels within neighbourhood_px
//   (Chebyshev, clipped at the image border) or B's pixel has none among A's: the test is
//   symmetric, so a thin feature missing from either image is caught. Ids match by equality.
// - PSNR is over R, G, B of every pixel, without tolerance: 10 log10(255^2 / MSE).
// - match_share = 1 - share of pixels mismatched in colour or id. An empty image (0 pixels) is
//   identical: PSNR kIdenticalPsnrDb, match_share 1.
// - The diff image is RGBA8, width*height*4, opaque; A is taken as the reference. An id mismatch
//   is magenta whether or not the colour also differs (a different object is the worse error); a
//   colour-only mismatch is red.
// Throws std::invalid_argument when the spans do not have the sizes above, when width or height
// is negative, or when an option is out of range. Allocates nothing but the diff image.
ImageCompareResult compareImages(int width, int height, std::span<const uint8_t> rgba_a,
                                 std::span<const uint8_t> rgba_b, std::span<const uint32_t> ids_a,
                                 std::span<const uint32_t> ids_b, const ImageCompareOptions& options,
                                 std::vector<uint8_t>* diff_rgba = nullptr);

// What a frame shows, read off its id image (0 = background): the pixels some object covers and
// how many distinct objects those are. A renderer whose cost follows its output should take
// about as long for two views with the same census, however large the model behind them; the
// bench reports the reference's census beside the frame times (docs/compare.md).
struct IdCensus {
  uint64_t covered_pixels = 0;
  uint64_t visible_objects = 0;
};
IdCensus censusOf(std::span<const uint32_t> ids);

// An 8-bit RGBA image: rows top to bottom, 4 bytes a pixel.
struct RgbaImage {
  int width = 0, height = 0;
  std::vector<uint8_t> rgba;
};

// Largest image readPngRgba accepts (64 Mpixel, 256 MiB decoded): a damaged header must not make
// the reader allocate gigabytes.
inline constexpr uint64_t kMaxPngPixels = uint64_t(1) << 26;

// Reads a PNG file (any bit depth and channel count) as RGBA8. Only PNG: the signature is checked
// first, so a damaged file is never guessed to be another format. Throws FormatError naming the
// file for a missing, unreadable, non-PNG, corrupt or oversized file.
RgbaImage readPngRgba(const std::filesystem::path& path);

// The same from bytes in memory (a BCF snapshot); `name` is what errors call them.
RgbaImage decodePngRgba(std::span<const uint8_t> bytes, const std::string& name);

// Writes width*height RGBA8 pixels as a PNG. Throws std::runtime_error naming the file when the
// file cannot be written, std::invalid_argument when rgba has the wrong size.
void writePngRgba(const std::filesystem::path& path, int width, int height,
                  std::span<const uint8_t> rgba);

// The same PNG, in memory (a BCF snapshot). Throws as writePngRgba.
std::vector<uint8_t> encodePngRgba(int width, int height, std::span<const uint8_t> rgba);

// Object-id images store each pixel's uint32 (object index + 1, 0 = background) little-endian in
// the R, G, B, A bytes of an RGBA8 image. idsFromRgba takes rgba.size()/4 pixels (rgba.size() must
// be a multiple of 4, else std::invalid_argument).
std::vector<uint32_t> idsFromRgba(std::span<const uint8_t> rgba);
std::vector<uint8_t> idsToRgba(std::span<const uint32_t> ids);

}  // namespace tw
