#include "asg_planner/frame_sync.hpp"

#include <cmath>
#include <cstdio>

namespace asg_planner {

double seconds(Nanos d) {
  // ros::Duration: sec and nsec (nsec in [0, 1e9)), then sec + 1e-9 * nsec.
  Nanos sec = d / 1000000000, nsec = d % 1000000000;
  if (nsec < 0) {
    nsec += 1000000000;
    --sec;
  }
  return double(sec) + 1e-9 * double(nsec);
}

bool gridFits(double size, double spacing, std::string* why) {
  const double cells = size / spacing;
  if (cells <= kMaxVehicleCellsPerSide) return true;
  char buf[200];
  std::snprintf(buf, sizeof(buf), "landscape of %.0f m is %.0f vehicle-grid cells per side at %.2f m spacing (at most %d)",
                size, cells, spacing, kMaxVehicleCellsPerSide);
  *why = buf;
  return false;
}

bool frameValid(const ImageIn& d, const ImageIn& l, std::string* why) {
  if (d.encoding != "32FC1") *why = "depth encoding '" + d.encoding + "' (expected 32FC1)";
  else if (l.encoding != "mono8" && l.encoding != "8UC1") *why = "labels encoding '" + l.encoding + "' (expected mono8)";
  else if (d.width != l.width || d.height != l.height) *why = "depth and labels differ in size";
  else if (d.step != d.width * 4 || d.size != size_t(d.step) * d.height) *why = "depth step/size inconsistent";
  else if (l.step != l.width || l.size != size_t(l.step) * l.height) *why = "labels step/size inconsistent";
  else return true;
  return false;
}

bool FrameSync::announce(uint32_t scenario_id, uint32_t run, Nanos base) {
  if (!protocol_.announce(scenario_id, run, base)) return false;
  depth_.clear();
  labels_.clear();
  odom_.clear();
  ticks_.clear();
  frames_done_ = 0;
  return true;
}

void FrameSync::setMount(const Eigen::Isometry3d& T_base_optical) {
  T_base_optical_ = T_base_optical;
  have_mount_ = true;
}

bool FrameSync::addDepth(Nanos stamp, ImageIn image) {
  if (!protocol_.current(stamp)) return false;
  depth_[stamp] = std::move(image);
  return true;
}

bool FrameSync::addLabels(Nanos stamp, ImageIn image) {
  if (!protocol_.current(stamp)) return false;
  labels_[stamp] = std::move(image);
  return true;
}

bool FrameSync::addOdom(Nanos stamp, const OdomIn& odom) {
  if (!protocol_.current(stamp)) return false;
  odom_[stamp] = odom;
  return true;
}

bool FrameSync::addTick(uint32_t scenario_id, Nanos stamp, uint32_t camera_frames) {
  if (!protocol_.tick(scenario_id, stamp)) return false;
  ticks_.push_back({stamp, camera_frames});
  return true;
}

std::optional<SyncedFrame> FrameSync::nextFrame(std::string* error) {
  if (!protocol_.active() || !have_mount_ || !have_info_) return std::nullopt;
  for (auto it = depth_.begin(); it != depth_.end(); ++it) {
    auto lit = labels_.find(it->first);
    auto oit = odom_.find(it->first);
    if (lit == labels_.end() || oit == odom_.end()) continue;
    SyncedFrame f;
    f.stamp = it->first;
    f.t = seconds(f.stamp - protocol_.base());
    std::string why;
    if (!frameValid(it->second, lit->second, &why)) {
      char buf[64];
      std::snprintf(buf, sizeof(buf), "cannot use the frame at t = %.3f s: ", f.t);
      *error = buf + why;
      return std::nullopt;
    }
    f.T_map_optical = oit->second.pose * T_base_optical_;
    f.depth = std::move(it->second);
    f.labels = std::move(lit->second);
    depth_.erase(it);
    labels_.erase(lit);
    ++frames_done_;
    return f;
  }
  return std::nullopt;
}

std::optional<SyncedTick> FrameSync::nextTick() {
  if (!protocol_.active() || ticks_.empty()) return std::nullopt;
  const Tick tick = ticks_.front();
  if (frames_done_ < tick.camera_frames) return std::nullopt;
  auto oit = odom_.find(tick.stamp);
  if (oit == odom_.end()) return std::nullopt;
  SyncedTick out{tick.stamp, seconds(tick.stamp - protocol_.base()), oit->second.state};
  ticks_.pop_front();
  const Nanos keep = 1000000000;  // [ns] odometry kept behind the newest tick
  const Nanos cut = tick.stamp > keep ? tick.stamp - keep : 0;
  while (!odom_.empty() && odom_.begin()->first < cut) odom_.erase(odom_.begin());
  return out;
}

}  // namespace asg_planner
