#include "asg_planner/projection.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace asg_planner {

void GroundMap::add(double x, double y, double z) {
  const int64_t i = int64_t(std::floor(x / cell_)), j = int64_t(std::floor(y / cell_));
  auto it = low_.find(key(i, j));
  if (it == low_.end()) low_.emplace(key(i, j), float(z));
  else if (z < it->second) it->second = float(z);
}

double GroundMap::lowNear(double x, double y) const {
  const int64_t i = int64_t(std::floor(x / cell_)), j = int64_t(std::floor(y / cell_));
  double low = INFINITY;
  for (int64_t di = -1; di <= 1; ++di)
    for (int64_t dj = -1; dj <= 1; ++dj) {
      auto it = low_.find(key(i + di, j + dj));
      if (it != low_.end()) low = std::min(low, double(it->second));
    }
  return low;
}

size_t castVotes(const float* depth, const uint8_t* labels, int width, int height,
                 const Intrinsics& K, const Eigen::Isometry3d& T, const ProjectionParams& p,
                 VoteGrid* grid, GroundMap* ground) {
  // Per-frame tally first, then one tree update per vertex: the octree walk is the costly part.
  std::unordered_map<int64_t, uint32_t> tally;
  const Eigen::Matrix3d R = T.rotation();
  const Eigen::Vector3d t = T.translation();
  const int stride = std::max(1, p.stride);
  const bool above_ground = p.height_above_ground && ground;
  if (above_ground) {
    // Every return of the frame (labelled pixels with a depth: the ground, obstacles; the sky
    // has none) lowers its cell's estimate; every 2nd pixel in u and v is plenty for 2 m cells.
    const int gs = 2 * stride;
    for (int v = 0; v < height; v += gs) {
      const double ry = (v - K.cy) / K.fy;
      for (int u = 0; u < width; u += gs) {
        const float d = depth[size_t(v) * width + u];
        if (!std::isfinite(d) || d <= 0.0f || (p.max_range > 0 && d > p.max_range)) continue;
        const Eigen::Vector3d pw = R * Eigen::Vector3d((u - K.cx) / K.fx * d, ry * d, d) + t;
        ground->add(pw.x(), pw.y(), pw.z());
      }
    }
  }
  size_t voted = 0;
  for (int v = 0; v < height; v += stride) {
    const double ry = (v - K.cy) / K.fy;
    for (int u = 0; u < width; u += stride) {
      const size_t i = size_t(v) * width + u;
      if (labels[i] != p.obstacle_label) continue;
      const float d = depth[i];
      if (!std::isfinite(d) || d <= 0.0f || (p.max_range > 0 && d > p.max_range)) continue;
      const Eigen::Vector3d pc((u - K.cx) / K.fx * d, ry * d, d);
      const Eigen::Vector3d pw = R * pc + t;
      if (above_ground ? pw.z() - ground->lowNear(pw.x(), pw.y()) >= p.max_height : pw.z() >= p.max_height)
        continue;
      const Vertex vx = grid->nearest(pw.x(), pw.y());
      ++tally[(int64_t(vx.i) << 32) ^ uint32_t(vx.j)];
      ++voted;
    }
  }
  for (const auto& [key, n] : tally) grid->add({int(key >> 32), int(int32_t(uint32_t(key)))}, n);
  return voted;
}

}  // namespace asg_planner
