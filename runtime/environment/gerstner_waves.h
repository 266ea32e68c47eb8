// The ocean's waves: a sum of Gerstner waves, evaluated in double on the CPU (the reference the
// tests check, and the wave phases handed to the GPU) and in GLSL by the ocean pass, the same way.
//
// Each wave i has an amplitude A, a wavenumber k = 2 pi / wavelength, a unit direction D in the
// XY plane, a phase p and the deep-water dispersion w = sqrt(g k). A still-water point x0 moves to
//   x = x0 - sum_i Q_i A_i D_i sin(theta_i),   z = waterline + sum_i A_i cos(theta_i),
//   theta_i = k_i (D_i . x0) - w_i t + p_i,
// where Q_i (0 to 1) is how far the water moves horizontally towards the crest (1: the circular
// orbits of the physical Gerstner wave). Crests loop over themselves when sum_i Q_i k_i A_i
// exceeds 1; the steepness s (0 to 1) sets Q_i = min(1, s / (k_i A_i n)) for the n waves, so
// that sum is at most s and never above 1.
//
// Waves shorter than about two mesh cells at a point cannot be drawn there (they alias into
// noise): each wave fades out with distance from the eye, smoothly, so nothing pops.
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

struct GerstnerWave {
  double amplitude_m = 0.5;
  double wavelength_m = 40.0;
  double direction_deg = 0.0;  // towards which the wave travels, counter-clockwise from +X
  double phase_rad = 0.0;
};

struct OceanWaves {
  std::vector<GerstnerWave> waves;
  double steepness = 0.6;  // 0: the water only rises and falls; 1: the sharpest crest that never loops
  double wind_speed_mps = 8.0;      // what wavesForWind made them from (the panel shows it)
  double wind_direction_deg = 30.0;
};

inline constexpr double kGravity = 9.81;
inline constexpr int kMaxOceanWaves = 16;  // the GPU's uniform array

// A set of `count` waves for a wind (speed at 10 m, direction it blows towards): wavelengths
// around the fully developed sea's peak (2 pi U^2 / g scaled by 0.6 ... 1.4), directions within
// 40 degrees of the wind, amplitudes a fixed share of each wavelength (a sea of moderate
// steepness), phases spread. Throws std::invalid_argument for count outside 1..kMaxOceanWaves or
// a wind not between 0.5 and 40 m/s.
OceanWaves wavesForWind(double speed_mps, double direction_deg, int count);

// Throws std::invalid_argument naming the wave and the value when a wave is not finite, has an
// amplitude below 0 or a wavelength not above 0, or there are more than kMaxOceanWaves.
void validateWaves(const OceanWaves& waves);

// One wave ready to evaluate: direction unit vector, wavenumber, angular frequency, Q_i.
struct WaveTerm {
  glm::dvec2 direction{1.0, 0.0};
  double k = 0.0;
  double omega = 0.0;
  double amplitude = 0.0;
  double q = 0.0;
  double phase = 0.0;
  double wavelength = 0.0;
};
std::vector<WaveTerm> waveTerms(const OceanWaves& waves);

// The factor (0..1) a wave of `wavelength_m` keeps where the mesh's cells measure `cell_m`: 1
// with at least 4 cells per wavelength, 0 with 2 or fewer, smooth in between.
double waveFade(double wavelength_m, double cell_m);

// Displacement of still-water point x0 (world XY) at time t: (dx, dy, dz), dz above the waterline.
// `cell_m` is the mesh's cell size there (each wave faded by waveFade); <= 0: every wave whole.
glm::dvec3 gerstnerDisplacement(const std::vector<WaveTerm>& terms, const glm::dvec2& x0, double t,
                                double cell_m = 0.0);

// The unit surface normal at x0 (analytic, from the two tangents of the displaced surface).
glm::dvec3 gerstnerNormal(const std::vector<WaveTerm>& terms, const glm::dvec2& x0, double t,
                          double cell_m = 0.0);

}  // namespace tw
