#pragma once
/// @file image.hpp
/// Plain image buffers (row 0 at the top, as in sensor_msgs/Image).

#include <cstdint>
#include <vector>

namespace asg_sim {

/// Labels of the ground-truth segmentation: the U-Net's three classes, plus kUnderCanopy for
/// ground seen beneath a non-traversable obstacle's canopy (visible ground the vehicle cannot
/// reach: "void", ignored in training and evaluation, never voted on by the planner).
enum Label : uint8_t { kTraversable = 0, kNonTraversable = 1, kSky = 2, kUnderCanopy = 3 };

template <class T, int C>
struct Image {
  int width = 0;
  int height = 0;
  std::vector<T> data;  ///< row-major, C channels interleaved
  void resize(int w, int h) {
    width = w;
    height = h;
    data.assign(size_t(w) * h * C, T{});
  }
  T& at(int u, int v, int c = 0) { return data[(size_t(v) * width + u) * C + c]; }
  const T& at(int u, int v, int c = 0) const { return data[(size_t(v) * width + u) * C + c]; }
};

using RgbImage = Image<uint8_t, 3>;
using DepthImage = Image<float, 1>;     ///< planar depth [m], NaN where nothing (sky)
using LabelImage = Image<uint8_t, 1>;   ///< Label values
using InstanceImage = Image<uint16_t, 1>;  ///< PlacedObstacle::id, 0 = none

}  // namespace asg_sim
