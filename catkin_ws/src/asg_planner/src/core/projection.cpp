#include "asg_planner/projection.hpp"

#include <cmath>
#include <unordered_map>

namespace asg_planner {

size_t castVotes(const float* depth, const uint8_t* labels, int width, int height,
                 const Intrinsics& K, const Eigen::Isometry3d& T, const ProjectionParams& p,
                 VoteGrid* grid) {
  // Per-frame tally first, then one tree update per vertex: the octree walk is the costly part.
  std::unordered_map<int64_t, uint32_t> tally;
  const Eigen::Matrix3d R = T.rotation();
  const Eigen::Vector3d t = T.translation();
  const int stride = std::max(1, p.stride);
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
      if (pw.z() >= p.max_height) continue;
      const Vertex vx = grid->nearest(pw.x(), pw.y());
      ++tally[(int64_t(vx.i) << 32) ^ uint32_t(vx.j)];
      ++voted;
    }
  }
  for (const auto& [key, n] : tally) grid->add({int(key >> 32), int(int32_t(uint32_t(key)))}, n);
  return voted;
}

}  // namespace asg_planner
