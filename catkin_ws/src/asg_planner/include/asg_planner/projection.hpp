#pragma once
/// @file projection.hpp
/// Pixel to world: each pixel labelled non-traversable, with its planar depth and the camera
/// pose, becomes a map point; points lower than max_height vote for their nearest grid vertex.

#include <Eigen/Geometry>
#include <cstdint>

#include "asg_planner/vote_grid.hpp"

namespace asg_planner {

/// Pinhole intrinsics as in sensor_msgs/CameraInfo K.
struct Intrinsics {
  double fx = 128.0, fy = 128.0;  ///< [px]
  double cx = 127.5, cy = 127.5;  ///< [px]
};

struct ProjectionParams {
  double max_height = 2.0;         ///< [m] map z; higher points do not vote
  double max_range = -1.0;         ///< [m] planar depth limit, -1: none
  uint8_t obstacle_label = 1;      ///< label value of non-traversable pixels
  int stride = 1;                  ///< [px] use every stride-th pixel in u and v
};

/// Casts the votes of one frame (row-major depth [m], NaN = no return, and labels).
/// T_map_optical: camera optical frame (z forward, x right, y down) in the map.
/// @return number of pixels that voted (before the per-vertex cap)
size_t castVotes(const float* depth, const uint8_t* labels, int width, int height,
                 const Intrinsics& K, const Eigen::Isometry3d& T_map_optical,
                 const ProjectionParams& params, VoteGrid* grid);

}  // namespace asg_planner
