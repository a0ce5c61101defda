#include "asg_sim/terrain.hpp"

#include <cmath>

namespace asg_sim {
namespace {

// splitmix64: the waves depend on the seed alone, the same on every machine and library.
uint64_t splitmix(uint64_t* s) {
  uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

double uniform01(uint64_t* s) { return double(splitmix(s) >> 11) * (1.0 / 9007199254740992.0); }

}  // namespace

Terrain::Terrain(const TerrainSpec& spec) : amplitude_(spec.amplitude_m), hills_(spec.hills) {
  if (amplitude_ > 0.0) {
    uint64_t s = 0x7E44A1Aull ^ (uint64_t(spec.seed) << 17);
    for (int k = 0; k < kTerrainWaves; ++k) {
      // Directions spread over the half circle (one per sector, jittered), so the ground rolls
      // in every direction rather than in ridges.
      const double theta = M_PI * (k + uniform01(&s)) / kTerrainWaves;
      const double lambda = spec.wavelength_m * std::pow(2.0, uniform01(&s) - 0.5);
      const double phase = 2.0 * M_PI * uniform01(&s);
      const double k_abs = 2.0 * M_PI / lambda;
      waves_.push_back({k_abs * std::cos(theta), k_abs * std::sin(theta), phase});
    }
  }
  for (auto it = hills_.begin(); it != hills_.end();)  // a zero-height hill changes nothing
    it = (it->height_m == 0.0 || !(it->radius_m > 0.0)) ? hills_.erase(it) : it + 1;
}

double Terrain::height(double x, double y) const {
  double h = 0.0;
  if (!waves_.empty()) {
    for (const auto& w : waves_) h += std::cos(w.kx * x + w.ky * y + w.phase);
    h *= amplitude_ / double(waves_.size());
  }
  for (const auto& b : hills_) {
    const double r = std::hypot(x - b.x, y - b.y);
    if (r < b.radius_m) h += b.height_m * 0.5 * (1.0 + std::cos(M_PI * r / b.radius_m));
  }
  return h;
}

Eigen::Vector2d Terrain::gradient(double x, double y) const {
  Eigen::Vector2d g(0.0, 0.0);
  if (!waves_.empty()) {
    const double a = amplitude_ / double(waves_.size());
    for (const auto& w : waves_) {
      const double s = -a * std::sin(w.kx * x + w.ky * y + w.phase);
      g += Eigen::Vector2d(s * w.kx, s * w.ky);
    }
  }
  for (const auto& b : hills_) {
    const double dx = x - b.x, dy = y - b.y, r = std::hypot(dx, dy);
    if (r <= 0.0 || r >= b.radius_m) continue;
    const double dhdr = -b.height_m * 0.5 * M_PI / b.radius_m * std::sin(M_PI * r / b.radius_m);
    g += Eigen::Vector2d(dhdr * dx / r, dhdr * dy / r);
  }
  return g;
}

Eigen::Vector3d Terrain::normal(double x, double y) const {
  const Eigen::Vector2d g = gradient(x, y);
  return Eigen::Vector3d(-g.x(), -g.y(), 1.0).normalized();
}

}  // namespace asg_sim
