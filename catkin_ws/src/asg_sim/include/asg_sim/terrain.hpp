#pragma once
/// @file terrain.hpp
/// The ground's shape (issue #27): a seeded rolling ground plus placed hills and ditches, as a
/// height function z = h(x, y) over the map frame with its analytic gradient (for normals). No
/// ROS. The same function feeds the rendered ground mesh, the Bullet heightfield, the obstacles'
/// and the vehicle's placement. A spec with amplitude 0 and no hill is the flat ground z = 0 of
/// every scene before terrain existed, exactly.

#include "asg_sim/scene_schema.hpp"
#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace asg_sim {

/// A raised-cosine bump: h = height * (1 + cos(pi r / radius)) / 2 within radius of (x, y).
struct Hill {
  double x = 0.0;         ///< [m] centre, within the landscape
  double y = 0.0;         ///< [m]
  double radius_m = 10.0; ///< [m] where the bump meets the ground around it, > 0
  double height_m = 1.0;  ///< [m] at the centre; negative: a ditch
};

/// structural.terrain of a scene (docs/scenario-format.md).
struct TerrainSpec {
  /// [m] largest height of the rolling ground, the mean of kTerrainWaves seeded plane waves
  /// cos(2 pi (d . p) / lambda + phase); 0: no rolling ground.
  double amplitude_m = schema::kTerrainAmplitudeM.default_value;
  /// [m] typical wavelength; each wave's is drawn in [lambda / sqrt 2, lambda sqrt 2].
  double wavelength_m = schema::kTerrainWavelengthM.default_value;
  /// [-] draws the waves' directions, wavelengths and phases
  uint32_t seed = static_cast<uint32_t>(schema::kTerrainSeed.default_value);
  std::vector<Hill> hills;
};

constexpr int kTerrainWaves = 3;          ///< [-] plane waves of the rolling ground
constexpr size_t kMaxHills = schema::kMaxHills;  ///< [-] hills and ditches in one scene
constexpr double kMaxTerrainAmplitude = schema::kTerrainAmplitudeM.hi;  ///< [m]
constexpr double kMaxHillHeight = schema::kHillHeightM.hi;  ///< [m] |height_m|
/// Steepness bounds (so roll and pitch limits, not the ground, decide what is drivable):
/// amplitude_m <= wavelength_m / 10 (rolling slopes below about 42 deg) and
/// |height_m| <= radius_m / 2 (hill flanks below about 38 deg).
constexpr double kMaxAmplitudePerWavelength = schema::kMaxAmplitudePerWavelength;
/// [-] cells per side of a shaped ground's mesh and heightfield, whatever `subdivisions` asks
/// (the scene budget: a shaped ground at the format's 2048 cells per side would be 4 million
/// vertices to shade every frame); a flat ground is drawn with 8 x 8 cells anyway.
constexpr int kMaxTerrainCellsPerSide = 512;
constexpr double kMaxHillHeightPerRadius = schema::kMaxHillHeightPerRadius;

class Terrain {
 public:
  Terrain() = default;  ///< flat
  explicit Terrain(const TerrainSpec& spec);

  /// [m] ground height at (x, y) [m].
  double height(double x, double y) const;
  /// [-] (dh/dx, dh/dy) at (x, y).
  Eigen::Vector2d gradient(double x, double y) const;
  /// Unit upward normal of the ground at (x, y).
  Eigen::Vector3d normal(double x, double y) const;
  /// True when the ground is the plane z = 0.
  bool flat() const { return waves_.empty() && hills_.empty(); }

 private:
  struct Wave {
    double kx, ky, phase;  // [rad/m], [rad/m], [rad]
  };
  double amplitude_ = 0.0;
  std::vector<Wave> waves_;
  std::vector<Hill> hills_;
};

}  // namespace asg_sim
