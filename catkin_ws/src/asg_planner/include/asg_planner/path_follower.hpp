#pragma once
/// @file path_follower.hpp
/// Pure-pursuit-style look-ahead with PD steering on the heading error, and a PI speed
/// controller that outputs throttle and brake. Time comes from the caller (message stamps).
///
/// Steering is computed as a front-wheel angle, with the gains in the reference's units
/// (degrees of wheel per radian of heading error), and only then divided by the steering lock
/// to give the command in [-1, 1]. The conversion happens once, in the constructor.

#include <Eigen/Core>
#include <vector>

namespace asg_planner {

struct FollowerParams {
  double lookahead = 5.0;   ///< [m] distance of the look-ahead point
  /// Which crossing of the look-ahead circle: false, the furthest along the path beyond the
  /// closest path point; true, the first one after it (the reference's). They differ only when
  /// the path leaves the circle and comes back into it (a hairpin within `lookahead`).
  bool first_crossing = false;
  double kp = 10.0;         ///< [deg/rad] front-wheel angle per radian of heading error
  double kd = 5.0;          ///< [deg s/rad] front-wheel angle per rad/s of heading-error rate
  double steering_lock = 0.6;   ///< [rad] front-wheel angle at steering command 1 (the vehicle's)
  double derivative_tau = 0.0;  ///< [s] low-pass time constant of the error rate (0: unfiltered)
  double speed_kp = 0.5;    ///< [1/(m/s)] throttle per m/s of speed error
  double speed_ki = 0.1;    ///< [1/m] throttle per metre of integrated speed error
  double brake_gain = 0.5;  ///< [1/(m/s)] brake per m/s above the target speed (beyond 0.3 m/s)
};

/// The planar vehicle state the follower needs.
struct VehicleState2D {
  double x = 0, y = 0;  ///< [m] map
  double yaw = 0;       ///< [rad]
  double speed = 0;     ///< [m/s] forward
};

struct ControlCommand {
  double throttle = 0, steering = 0, brake = 0;  ///< [-] 0..1, -1..1 (left +), 0..1
  double target_speed = 0;                       ///< [m/s]
};

class PathFollower {
 public:
  explicit PathFollower(const FollowerParams& params = FollowerParams());
  void setPath(const std::vector<Eigen::Vector2d>& path);
  /// Forgets the derivative and integral state.
  void reset();
  /// Control at time t [s] towards the path at target speed [m/s].
  ControlCommand update(double t, const VehicleState2D& s, double target_speed);
  /// The look-ahead point of the last update [m].
  const Eigen::Vector2d& lookaheadPoint() const { return lookahead_; }
  double headingError() const { return last_error_; }
  const FollowerParams& params() const { return params_; }
  /// The gains as steering command (fraction of lock) per rad and per rad/s: kp, kd converted.
  double kpCommand() const { return kp_cmd_; }
  double kdCommand() const { return kd_cmd_; }

  /// Look-ahead point for a vehicle at p: the furthest-along (or, with first, the first)
  /// intersection of the circle of radius L around p with the path beyond the path point
  /// closest to p; the path end when it lies within L; otherwise the closest point of the path.
  static Eigen::Vector2d lookahead(const std::vector<Eigen::Vector2d>& path,
                                   const Eigen::Vector2d& p, double L, bool first = false);

 private:
  FollowerParams params_;
  double kp_cmd_, kd_cmd_;  // [1/rad], [s/rad] of steering command
  std::vector<Eigen::Vector2d> path_;
  Eigen::Vector2d lookahead_ = Eigen::Vector2d::Zero();
  bool have_last_ = false;
  double last_t_ = 0, last_error_ = 0, integral_ = 0, rate_ = 0;
};

}  // namespace asg_planner
