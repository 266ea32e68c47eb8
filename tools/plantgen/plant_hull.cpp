// A ship-like FPSO hull as one closed NURBS patch set whose patches share their borders exactly.
//
// The shell is a cubic B-spline surface: closed around the cross-section (deck, sides, bilges,
// bottom) and open along the length, where it narrows to a transom at the stern and a raked,
// narrow transom bow. It is converted to bicubic Bezier patches on one global grid, so adjacent
// patches take their common border from the very same control points (bit-identical), which is
// what a crack-free tessellation needs. The port half is the exact mirror of the starboard half.
// Each end is closed by a 4 x 3 grid of Coons-filled patches whose outer border is the shell's
// end section, so the whole set is watertight.
#include <cmath>

#include "plant_parts.h"

namespace tw::plant {
namespace {

// Uniform cubic B-spline to Bezier: the four Bezier points of the span from c1 to c2.
// With `smooth` false the control polygon itself is the surface (a faceted, hard-chine hull).
template <typename T>
void spanToBezier(const T& c0, const T& c1, const T& c2, const T& c3, T out[4], bool smooth) {
  out[0] = smooth ? (c0 + 4.0f * c1 + c2) / 6.0f : c1;
  out[1] = (2.0f * c1 + c2) / 3.0f;
  out[2] = (c1 + 2.0f * c2) / 3.0f;
  out[3] = smooth ? (c1 + 4.0f * c2 + c3) / 6.0f : c2;
}

// Control polygon of the starboard half-section, from the deck centreline to the keel
// (y outboard, z up), for a unit half-beam and unit depth. Spans 0-1 are deck, 2-4 side (2 is
// the deck-edge corner), 5-6 bottom: the end caps rely on this split (2 + 3 + 2 per half).
constexpr int kHalfSection = 7;  // spans per half: the closed loop has 14 control points
const glm::vec2 kSection[kHalfSection + 1] = {{0.0f, 0.0f},   {0.5f, 0.0f},   {0.94f, 0.0f},
                                              {1.0f, -0.12f}, {1.0f, -0.85f}, {0.9f, -1.0f},
                                              {0.45f, -1.0f}, {0.0f, -1.0f}};
// Stations along the length, evenly spaced (a fraction x = index / 11 of the length), with
// breadth and depth factors. Even spacing keeps the Bezier points of the flat parallel body
// evenly spaced too, which is what lets the tessellator treat it as flat (cheap).
struct Station {
  float x, breadth, depth;
};
const Station kStationTable[] = {
    {0.0f / 11, 0.7f, 0.75f},  {1.0f / 11, 0.95f, 0.95f}, {2.0f / 11, 1.0f, 1.0f},
    {3.0f / 11, 1.0f, 1.0f},   {4.0f / 11, 1.0f, 1.0f},   {5.0f / 11, 1.0f, 1.0f},
    {6.0f / 11, 1.0f, 1.0f},   {7.0f / 11, 1.0f, 1.0f},   {8.0f / 11, 1.0f, 1.0f},
    {9.0f / 11, 0.95f, 0.97f}, {10.0f / 11, 0.75f, 0.85f}, {11.0f / 11, 0.3f, 0.7f}};
constexpr int kStations = static_cast<int>(std::size(kStationTable));

}  // namespace

SceneObject buildHull(uint32_t hull_index, const glm::dvec3& deck_origin, float length,
                      float beam, float depth, bool smooth) {
  const float half_beam = beam * 0.5f;
  constexpr int kLoop = 2 * kHalfSection;       // closed loop control points
  constexpr int kLoopBezier = 3 * kLoop;        // Bezier points around (index kLoopBezier == 0)
  constexpr int kRowsBezier = 3 * (kStations - 1) + 1;

  // B-spline control net: station rows x loop points (starboard half then mirrored port half).
  auto net = [&](int station, int loop_index) {
    int j = ((loop_index % kLoop) + kLoop) % kLoop;
    bool port = j > kHalfSection;
    const glm::vec2& s = kSection[port ? kLoop - j : j];
    const Station& st = kStationTable[station];
    float z = s.y * depth * st.depth;
    // A raked stem and a sheer rising toward the bow.
    float x = st.x * length + (st.x > 0.9f ? 0.3f * z * (st.x - 0.9f) * 10.0f : 0.0f);
    z += 0.015f * depth * st.x * st.x;
    return glm::vec3(x, (port ? -1.0f : 1.0f) * s.x * half_beam * st.breadth, z);
  };

  // Step 1: around the loop, per station row (starboard Bezier points 0..3*kHalfSection).
  std::vector<glm::vec3> rows(kStations * (3 * kHalfSection + 1));
  auto row_at = [&](int station, int k) -> glm::vec3& { return rows[station * (3 * kHalfSection + 1) + k]; };
  for (int q = 0; q < kStations; ++q) {
    for (int span = 0; span < kHalfSection; ++span) {
      glm::vec3 b[4];
      spanToBezier(net(q, span - 1), net(q, span), net(q, span + 1), net(q, span + 2), b, smooth);
      for (int k = 0; k < 3; ++k) row_at(q, 3 * span + k) = b[k];
      if (span == kHalfSection - 1) row_at(q, 3 * kHalfSection) = b[3];
    }
  }
  // Step 2: along the length, clamped by mirrored phantom rows so the end rows are the stem.
  std::vector<glm::vec3> grid(kRowsBezier * kLoopBezier);
  auto grid_at = [&](int r, int k) -> glm::vec3& { return grid[r * kLoopBezier + (k % kLoopBezier)]; };
  for (int k = 0; k <= 3 * kHalfSection; ++k) {
    auto c = [&](int q) {
      if (q < 0) return 2.0f * row_at(0, k) - row_at(1, k);
      if (q >= kStations) return 2.0f * row_at(kStations - 1, k) - row_at(kStations - 2, k);
      return row_at(q, k);
    };
    for (int span = 0; span < kStations - 1; ++span) {
      glm::vec3 b[4];
      spanToBezier(c(span - 1), c(span), c(span + 1), c(span + 2), b, smooth);
      for (int i = 0; i < 3; ++i) grid_at(3 * span + i, k) = b[i];
    }
    grid_at(0, k) = row_at(0, k);
    grid_at(kRowsBezier - 1, k) = row_at(kStations - 1, k);
    // Centreline points must have y exactly +0 so that both halves meet bit for bit.
    if (k == 0 || k == 3 * kHalfSection)
      for (int r = 0; r < kRowsBezier; ++r) grid_at(r, k).y = 0.0f;
  }
  for (int r = 0; r < kRowsBezier; ++r)
    for (int k = 1; k < 3 * kHalfSection; ++k) {
      glm::vec3 p = grid_at(r, k);
      p.y = p.y == 0.0f ? 0.0f : -p.y;
      grid_at(r, kLoopBezier - k) = p;
    }

  SceneObject hull;
  hull.info.name = format("hull H-%02u", hull_index + 1);
  hull.info.db_key = format("H-%02u", hull_index + 1);
  hull.info.layer = kLayerHull;
  hull.info.transform = translation(deck_origin);
  NurbsPatchSet set;
  const std::vector<float> knots = {0, 0, 0, 0, 1, 1, 1, 1};
  for (int pu = 0; pu < kStations - 1; ++pu) {
    for (int pv = 0; pv < kLoop; ++pv) {
      NurbsPatch patch;
      patch.knots_u = knots;
      patch.knots_v = knots;
      patch.control_points.reserve(16);
      // u runs around the section (fastest), v along the length.
      for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i)
          patch.control_points.push_back(glm::vec4(grid_at(3 * pu + j, 3 * pv + i), 1.0f));
      set.patches.push_back(std::move(patch));
    }
  }
  // End caps. Cap grid (i across from port to starboard, j down from deck to bottom) takes its
  // border from the end row of the shell; the interior is the bilinearly blended Coons grid.
  constexpr int kCapI = 12, kCapJ = 9;  // 4 x 3 patches
  std::vector<glm::vec3> cap((kCapI + 1) * (kCapJ + 1));
  for (int end = 0; end < 2; ++end) {
    const int row = end == 0 ? 0 : kRowsBezier - 1;
    auto loop = [&](int k) { return grid_at(row, ((k % kLoopBezier) + kLoopBezier) % kLoopBezier); };
    auto at = [&](int i, int j) -> glm::vec3& { return cap[j * (kCapI + 1) + i]; };
    for (int i = 0; i <= kCapI; ++i) {
      at(i, 0) = loop(36 + i);      // deck edge: port deck corner, centreline, starboard corner
      at(i, kCapJ) = loop(27 - i);  // bottom: port bilge, keel, starboard bilge
    }
    for (int j = 1; j < kCapJ; ++j) {
      at(0, j) = loop(36 - j);     // port side
      at(kCapI, j) = loop(6 + j);  // starboard side
    }
    for (int j = 1; j < kCapJ; ++j)
      for (int i = 1; i < kCapI; ++i) {
        float s = float(i) / kCapI, t = float(j) / kCapJ;
        at(i, j) = (1 - s) * at(0, j) + s * at(kCapI, j) + (1 - t) * at(i, 0) + t * at(i, kCapJ) -
                   ((1 - s) * (1 - t) * at(0, 0) + s * (1 - t) * at(kCapI, 0) +
                    (1 - s) * t * at(0, kCapJ) + s * t * at(kCapI, kCapJ));
      }
    // The two ends face opposite ways: mirror the parameterisation of one so every patch's
    // orientation agrees with the shell's.
    for (int pj = 0; pj < kCapJ / 3; ++pj)
      for (int pi = 0; pi < kCapI / 3; ++pi) {
        NurbsPatch patch;
        patch.knots_u = knots;
        patch.knots_v = knots;
        patch.control_points.reserve(16);
        for (int j = 0; j < 4; ++j)
          for (int i = 0; i < 4; ++i) {
            int ci = 3 * pi + (end == 0 ? 3 - i : i), cj = 3 * pj + j;
            patch.control_points.push_back(glm::vec4(at(ci, cj), 1.0f));
          }
        set.patches.push_back(std::move(patch));
      }
  }
  // The grids above run so that each patch's u x v points into the hull. Swapping u and v turns
  // every patch the same way, outward, so the closed shell faces out and renderers may cull its
  // back faces (preprocess/closed_surface.h).
  for (NurbsPatch& patch : set.patches)
    for (int j = 0; j < 4; ++j)
      for (int i = j + 1; i < 4; ++i) std::swap(patch.control_points[j * 4 + i], patch.control_points[i * 4 + j]);
  hull.geometry = std::move(set);
  return hull;
}

ProjectRecord hullRecord(uint32_t hull_index, float length, float beam, float depth) {
  ProjectRecord r;
  r.db_key = format("H-%02u", hull_index + 1);
  r.type = "hull";
  r.material = "steel EH36";
  r.description = format("FPSO hull %u, %.0f m x %.0f m x %.0f m", hull_index + 1, length, beam,
                         depth);
  return r;
}

}  // namespace tw::plant
