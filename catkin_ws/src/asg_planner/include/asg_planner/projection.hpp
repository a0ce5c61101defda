#pragma once
/// @file projection.hpp
/// Pixel to world: each pixel labelled non-traversable, with its planar depth and the camera
/// pose, becomes a map point; points lower than max_height vote for their nearest grid vertex.

#include <cmath>
#include <Eigen/Geometry>
#include <cstdint>
#include <unordered_map>

#include "asg_planner/vote_grid.hpp"

namespace asg_planner {

/// Pinhole intrinsics as in sensor_msgs/CameraInfo K.
struct Intrinsics {
  double fx = 128.0, fy = 128.0;  ///< [px]
  double cx = 127.5, cy = 127.5;  ///< [px]
};

struct ProjectionParams {
  double max_height = 2.0;         ///< [m] points this high or higher do not vote (see height_above_ground)
  /// false: max_height is a map z, the flat ground z = 0 of the paper; true: a height above the
  /// ground the stack estimates from its own depth returns (GroundMap), for scenes with terrain.
  bool height_above_ground = false;
  double ground_cell = 2.0;        ///< [m] cell of the ground estimate
  double max_range = -1.0;         ///< [m] planar depth limit, -1: none
  uint8_t obstacle_label = 1;      ///< label value of non-traversable pixels
  int stride = 1;                  ///< [px] use every stride-th pixel in u and v
};

/// The stack's own estimate of the ground's height: the lowest depth return seen so far in each
/// ground_cell x ground_cell cell of the map (every labelled pixel with a depth, ground or not),
/// and near a point the lowest of its cell and the 8 around it. It reads nothing of the scene.
class GroundMap {
 public:
  explicit GroundMap(double cell = 2.0) : cell_(cell) {}
  void clear() { low_.clear(); }
  void add(double x, double y, double z);
  /// [m] lowest return in the 3 x 3 cells around (x, y); +inf where none was seen.
  double lowNear(double x, double y) const;
  /// [m] lowNear(x, y) where the stack has seen ground near (x, y), else `fallback` (drawing).
  double heightOr(double x, double y, double fallback) const {
    const double z = lowNear(x, y);
    return std::isfinite(z) ? z : fallback;
  }
  size_t cells() const { return low_.size(); }

 private:
  int64_t key(int64_t i, int64_t j) const { return (i << 32) ^ (j & 0xffffffff); }
  double cell_;
  std::unordered_map<int64_t, float> low_;
};

/// Casts the votes of one frame (row-major depth [m], NaN = no return, and labels).
/// T_map_optical: camera optical frame (z forward, x right, y down) in the map.
/// With params.height_above_ground, the frame's returns first update *ground, and a point votes
/// only when lower than max_height above ground->lowNear at its position.
/// @return number of pixels that voted (before the per-vertex cap)
size_t castVotes(const float* depth, const uint8_t* labels, int width, int height,
                 const Intrinsics& K, const Eigen::Isometry3d& T_map_optical,
                 const ProjectionParams& params, VoteGrid* grid, GroundMap* ground = nullptr);

}  // namespace asg_planner
