#pragma once
/// @file frame_sync.hpp
/// What the planner node decides about its inputs before the planner sees them, without ROS
/// (issue #38; costmap_2d keeps the same job in its ObservationBuffer): which run is current and
/// which messages belong to it (the lockstep protocol's stack side), which depth, labels and
/// odometry make one frame (the same stamp), whether a frame can be used, and when a control tick
/// may be answered (every camera frame up to it voted, its odometry here). The ROS adapter only
/// converts messages and forwards them; tests/test_frame_sync.cpp covers the orderings.

#include <Eigen/Geometry>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "asg_lockstep/stack_protocol.hpp"
#include "asg_planner/path_follower.hpp"

namespace asg_planner {

using Nanos = asg_lockstep::Nanos;  ///< [ns] a message stamp

/// [s] a stamp difference as ros::Duration::toSec() computes it (bit for bit: the planner's
/// times were always made this way).
double seconds(Nanos d);

/// The vehicle grid bounds A*'s memory: at most this many cells per side (16.8 M nodes).
constexpr int kMaxVehicleCellsPerSide = 4096;
/// Whether a landscape of `size` [m] fits the vehicle grid at `spacing` [m]; *why says why not.
bool gridFits(double size, double spacing, std::string* why);

/// An image as received: a view of its bytes; `keep` holds the message that owns them.
struct ImageIn {
  std::string encoding;
  uint32_t width = 0, height = 0, step = 0;
  const uint8_t* data = nullptr;
  size_t size = 0;  ///< [bytes]
  std::shared_ptr<const void> keep;
};
/// Whether a depth and a labels image make a usable frame; *why names the problem.
bool frameValid(const ImageIn& depth, const ImageIn& labels, std::string* why);

/// An odometry sample: the pose (map <- base_link) and the planar state the follower reads.
struct OdomIn {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  VehicleState2D state;
};

/// A frame ready to vote: depth and labels of one stamp, and the camera's pose then.
struct SyncedFrame {
  Nanos stamp = 0;
  double t = 0;  ///< [s] since the run's start
  ImageIn depth, labels;
  Eigen::Isometry3d T_map_optical = Eigen::Isometry3d::Identity();
};
/// A control tick ready to answer.
struct SyncedTick {
  Nanos stamp = 0;
  double t = 0;  ///< [s] since the run's start
  VehicleState2D state;
};

class FrameSync {
 public:
  explicit FrameSync(Nanos window) : protocol_(window) {}

  /// A run announcement; true when it is a new run: everything held is dropped.
  bool announce(uint32_t scenario_id, uint32_t run, Nanos base);
  /// The camera's mount (base_link <- optical) and whether intrinsics are known: frames wait
  /// for both.
  void setMount(const Eigen::Isometry3d& T_base_optical);
  void setIntrinsicsKnown(bool known) { have_info_ = known; }

  /// Inputs; each returns false (the message counted stale) when not of the current run.
  bool addDepth(Nanos stamp, ImageIn image);
  bool addLabels(Nanos stamp, ImageIn image);
  bool addOdom(Nanos stamp, const OdomIn& odom);
  bool addTick(uint32_t scenario_id, Nanos stamp, uint32_t camera_frames);

  /// The earliest frame whose depth, labels and odometry are all here (taken out), once mount and
  /// intrinsics are known; none when nothing is complete, or when the frame cannot be used
  /// (*error set: the run cannot go on).
  std::optional<SyncedFrame> nextFrame(std::string* error);
  /// The oldest pending tick, taken out, once every camera frame up to it is voted and its
  /// odometry is here; odometry more than 1 s older is dropped then.
  std::optional<SyncedTick> nextTick();

  /// The run's protocol state: active (announced, not failed), failed, scenario id, stale count.
  asg_lockstep::StackProtocol& protocol() { return protocol_; }
  const asg_lockstep::StackProtocol& protocol() const { return protocol_; }
  Nanos base() const { return protocol_.base(); }
  uint32_t framesDone() const { return frames_done_; }
  size_t held() const { return depth_.size() + labels_.size() + odom_.size() + ticks_.size(); }

 private:
  struct Tick {
    Nanos stamp;
    uint32_t camera_frames;
  };
  asg_lockstep::StackProtocol protocol_;
  bool have_mount_ = false, have_info_ = false;
  Eigen::Isometry3d T_base_optical_ = Eigen::Isometry3d::Identity();
  std::map<Nanos, ImageIn> depth_, labels_;
  std::map<Nanos, OdomIn> odom_;
  std::deque<Tick> ticks_;
  uint32_t frames_done_ = 0;
};

}  // namespace asg_planner
