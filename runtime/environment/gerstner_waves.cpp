// Gerstner waves (gerstner_waves.h).
#include "gerstner_waves.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <glm/gtc/constants.hpp>

namespace tw {
namespace {

std::string waveName(size_t i) { return "wave " + std::to_string(i + 1); }

double smoothstep(double e0, double e1, double x) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

// Sums over the waves at x0: the displacement, and the two tangents' wave parts.
struct WaveSums {
  glm::dvec3 displacement{0.0};
  // d(displacement)/dx0 and /dy0.
  glm::dvec3 d_dx{0.0}, d_dy{0.0};
};

WaveSums sumWaves(const std::vector<WaveTerm>& terms, const glm::dvec2& x0, double t, double cell_m) {
  WaveSums s;
  for (const WaveTerm& w : terms) {
    const double fade = cell_m > 0.0 ? waveFade(w.wavelength, cell_m) : 1.0;
    if (fade == 0.0) continue;
    const double a = w.amplitude * fade;
    const double theta = w.k * glm::dot(w.direction, x0) - w.omega * t + w.phase;
    const double sn = std::sin(theta), cs = std::cos(theta);
    s.displacement += glm::dvec3(-w.q * a * w.direction * sn, a * cs);
    // d theta / dx0 = k D.x, / dy0 = k D.y.
    const double qka = w.q * w.k * a * cs;
    const double ka = w.k * a * sn;
    s.d_dx += glm::dvec3(-qka * w.direction.x * w.direction, -ka * w.direction.x);
    s.d_dy += glm::dvec3(-qka * w.direction.y * w.direction, -ka * w.direction.y);
  }
  return s;
}

}  // namespace

OceanWaves wavesForWind(double speed_mps, double direction_deg, int count) {
  if (count < 1 || count > kMaxOceanWaves)
    throw std::invalid_argument("the ocean takes 1 to " + std::to_string(kMaxOceanWaves) +
                                " waves, not " + std::to_string(count));
  if (!(speed_mps >= 0.5 && speed_mps <= 40.0))
    throw std::invalid_argument("a wind speed of " + std::to_string(speed_mps) +
                                " m/s: give 0.5 to 40 m/s");
  if (!std::isfinite(direction_deg)) throw std::invalid_argument("the wind direction is not a number");
  // A fully developed sea (Pierson-Moskowitz): peak angular frequency 0.877 g / U, significant
  // height 0.21 U^2 / g.
  const double peak_k = std::pow(0.877 * kGravity / speed_mps, 2.0) / kGravity;
  const double peak_wavelength = 2.0 * glm::pi<double>() / peak_k;
  const double significant_height = 0.21 * speed_mps * speed_mps / kGravity;
  OceanWaves sea;
  sea.wind_speed_mps = speed_mps;
  sea.wind_direction_deg = direction_deg;
  double sum_squares = 0.0;
  for (int i = 0; i < count; ++i) {
    GerstnerWave w;
    w.wavelength_m = peak_wavelength * 1.6 * std::pow(0.7, i);
    // Spread about the wind, deterministic: the golden angle folded into +-40 degrees.
    w.direction_deg = direction_deg + std::fmod(i * 137.508, 80.0) - 40.0 * (i > 0);
    w.phase_rad = std::fmod(i * 2.39996, 2.0 * glm::pi<double>());
    sum_squares += w.wavelength_m * w.wavelength_m;
    sea.waves.push_back(w);
  }
  // Amplitudes a fixed share of each wavelength, scaled so that 4 sigma = the significant height
  // (sigma^2 = sum A^2 / 2).
  const double share = significant_height / std::sqrt(8.0 * sum_squares);
  for (GerstnerWave& w : sea.waves) w.amplitude_m = share * w.wavelength_m;
  return sea;
}

void validateWaves(const OceanWaves& waves) {
  if (waves.waves.size() > size_t(kMaxOceanWaves))
    throw std::invalid_argument("the ocean takes at most " + std::to_string(kMaxOceanWaves) +
                                " waves, not " + std::to_string(waves.waves.size()));
  if (!(waves.steepness >= 0.0 && waves.steepness <= 1.0))
    throw std::invalid_argument("the waves' steepness must be 0 to 1");
  for (size_t i = 0; i < waves.waves.size(); ++i) {
    const GerstnerWave& w = waves.waves[i];
    if (!std::isfinite(w.amplitude_m) || w.amplitude_m < 0.0 || w.amplitude_m > 1000.0)
      throw std::invalid_argument(waveName(i) + ": amplitude must be 0 to 1000 m");
    if (!std::isfinite(w.wavelength_m) || w.wavelength_m <= 0.01 || w.wavelength_m > 1e5)
      throw std::invalid_argument(waveName(i) + ": wavelength must be 0.01 to 100000 m");
    if (!std::isfinite(w.direction_deg) || !std::isfinite(w.phase_rad))
      throw std::invalid_argument(waveName(i) + ": direction and phase must be numbers");
  }
}

std::vector<WaveTerm> waveTerms(const OceanWaves& waves) {
  std::vector<WaveTerm> terms;
  const double n = double(waves.waves.size());
  for (const GerstnerWave& w : waves.waves) {
    WaveTerm t;
    const double angle = glm::radians(w.direction_deg);
    t.direction = {std::cos(angle), std::sin(angle)};
    t.wavelength = w.wavelength_m;
    t.k = 2.0 * glm::pi<double>() / w.wavelength_m;
    t.omega = std::sqrt(kGravity * t.k);
    t.amplitude = w.amplitude_m;
    t.phase = w.phase_rad;
    // Q_i k_i A_i = steepness / n, so the sum is the steepness: no crest loops.
    const double ka = t.k * t.amplitude;
    t.q = ka > 0.0 ? std::min(1.0, waves.steepness / (ka * n)) : 0.0;
    terms.push_back(t);
  }
  return terms;
}

double waveFade(double wavelength_m, double cell_m) {
  return smoothstep(2.0, 4.0, wavelength_m / cell_m);
}

glm::dvec3 gerstnerDisplacement(const std::vector<WaveTerm>& terms, const glm::dvec2& x0, double t,
                                double cell_m) {
  return sumWaves(terms, x0, t, cell_m).displacement;
}

glm::dvec3 gerstnerNormal(const std::vector<WaveTerm>& terms, const glm::dvec2& x0, double t,
                          double cell_m) {
  const WaveSums s = sumWaves(terms, x0, t, cell_m);
  const glm::dvec3 tangent_x = glm::dvec3(1.0, 0.0, 0.0) + s.d_dx;
  const glm::dvec3 tangent_y = glm::dvec3(0.0, 1.0, 0.0) + s.d_dy;
  return glm::normalize(glm::cross(tangent_x, tangent_y));
}

}  // namespace tw
