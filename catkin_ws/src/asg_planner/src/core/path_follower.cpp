#include "asg_planner/path_follower.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace asg_planner {

namespace {
constexpr double kRadPerDeg = M_PI / 180.0;
}

PathFollower::PathFollower(const FollowerParams& params)
    : params_(params),
      kp_cmd_(params.kp * kRadPerDeg / params.steering_lock),
      kd_cmd_(params.kd * kRadPerDeg / params.steering_lock) {}

void PathFollower::setPath(const std::vector<Eigen::Vector2d>& path) { path_ = path; }

void PathFollower::reset() {
  path_.clear();
  have_last_ = false;
  last_error_ = integral_ = rate_ = 0;
}

Eigen::Vector2d PathFollower::lookahead(const std::vector<Eigen::Vector2d>& path,
                                        const Eigen::Vector2d& p, double L, bool first) {
  if (path.empty()) return p;
  if (path.size() == 1) return path[0];
  // Closest point on the path, by segment.
  size_t best_seg = 0;
  double best_d = std::numeric_limits<double>::infinity(), best_u = 0;
  for (size_t i = 0; i + 1 < path.size(); ++i) {
    const Eigen::Vector2d d = path[i + 1] - path[i];
    const double len2 = d.squaredNorm();
    const double u = len2 > 0 ? std::clamp((p - path[i]).dot(d) / len2, 0.0, 1.0) : 0.0;
    const double dist = (path[i] + u * d - p).norm();
    if (dist < best_d) {
      best_d = dist;
      best_seg = i;
      best_u = u;
    }
  }
  if ((path.back() - p).norm() <= L) return path.back();
  // Furthest-along (or first) circle intersection from the closest point onwards.
  bool found = false;
  Eigen::Vector2d result = Eigen::Vector2d::Zero();
  for (size_t i = best_seg; i + 1 < path.size() && !(first && found); ++i) {
    const Eigen::Vector2d a = path[i], d = path[i + 1] - path[i];
    const Eigen::Vector2d f = a - p;
    const double A = d.squaredNorm(), B = 2 * f.dot(d), C = f.squaredNorm() - L * L;
    const double disc = B * B - 4 * A * C;
    if (A <= 0 || disc < 0) continue;
    const double sq = std::sqrt(disc);
    for (double u : {(-B - sq) / (2 * A), (-B + sq) / (2 * A)}) {
      if (u < 0 || u > 1 || (i == best_seg && u < best_u)) continue;
      result = a + u * d;
      found = true;
      if (first) break;
    }
  }
  if (found) return result;
  const Eigen::Vector2d d = path[best_seg + 1] - path[best_seg];
  return path[best_seg] + best_u * d;
}

ControlCommand PathFollower::update(double t, const VehicleState2D& s, double target_speed) {
  ControlCommand c;
  c.target_speed = target_speed;
  if (path_.empty()) {
    c.brake = 1.0;
    c.target_speed = 0.0;
    return c;
  }
  const Eigen::Vector2d p(s.x, s.y);
  lookahead_ = lookahead(path_, p, params_.lookahead, params_.first_crossing);
  const Eigen::Vector2d to = lookahead_ - p;
  double e = to.norm() > 1e-6 ? std::atan2(to.y(), to.x()) - s.yaw : 0.0;
  e = std::atan2(std::sin(e), std::cos(e));
  double de = 0.0;
  const double dt = have_last_ ? t - last_t_ : 0.0;
  if (have_last_ && dt > 0) {
    double diff = e - last_error_;
    diff = std::atan2(std::sin(diff), std::cos(diff));
    const double raw = diff / dt;
    const double a = params_.derivative_tau > 0 ? dt / (params_.derivative_tau + dt) : 1.0;
    rate_ += a * (raw - rate_);
    de = rate_;
  }
  c.steering = std::clamp(kp_cmd_ * e + kd_cmd_ * de, -1.0, 1.0);
  const double err = target_speed - s.speed;
  if (dt > 0) integral_ = std::clamp(integral_ + err * dt, -5.0, 5.0);
  c.throttle = std::clamp(params_.speed_kp * err + params_.speed_ki * integral_, 0.0, 1.0);
  c.brake = err < -0.3 ? std::clamp(-params_.brake_gain * err, 0.0, 1.0) : 0.0;
  if (c.brake > 0) c.throttle = 0.0;
  last_t_ = t;
  last_error_ = e;
  have_last_ = true;
  return c;
}

}  // namespace asg_planner
