#include "asg_sim/twist_controller.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace asg_sim {

TwistController::TwistController(const TwistControllerParams& p) : params_(p) {
  if (!(p.wheelbase > 0)) throw std::invalid_argument("twist controller: wheelbase must be > 0 m");
  if (!(p.steering_lock > 0 && p.steering_lock < M_PI / 2))
    throw std::invalid_argument("twist controller: steering_lock must be in (0, pi/2) rad");
  if (!(p.min_turn_speed > 0)) throw std::invalid_argument("twist controller: min_turn_speed must be > 0 m/s");
  if (!(p.max_speed > 0)) throw std::invalid_argument("twist controller: max_speed must be > 0 m/s");
  if (!(p.max_reverse_speed >= 0)) throw std::invalid_argument("twist controller: max_reverse_speed must be >= 0 m/s");
  if (p.speed_kp < 0 || p.speed_ki < 0 || p.brake_gain < 0 || p.integral_limit < 0 || p.brake_deadband < 0)
    throw std::invalid_argument("twist controller: gains, limits and deadband must be >= 0");
}

void TwistController::reset() {
  integral_ = 0.0;
  wheel_angle_ = 0.0;
}

Command TwistController::update(const VelocityCommand& in, double speed, double dt) {
  Command c;
  if (!std::isfinite(in.speed) || !std::isfinite(in.yaw_rate) || !std::isfinite(speed) ||
      !std::isfinite(dt)) {
    c.brake = 1.0;
    integral_ = 0.0;
    return c;
  }
  const double v = std::clamp(in.speed, -params_.max_reverse_speed, params_.max_speed);
  c.target_speed = v;
  // Kinematic bicycle: yaw rate = v tan(wheel angle) / wheelbase; backwards (v < 0) the same yaw
  // rate needs the wheels turned the other way.
  const double v_turn = v >= 0.0 ? std::max(v, params_.min_turn_speed) : std::min(v, -params_.min_turn_speed);
  wheel_angle_ = std::atan(params_.wheelbase * in.yaw_rate / v_turn);
  c.steering = std::clamp(wheel_angle_ / params_.steering_lock, -1.0, 1.0);
  if (std::abs(v) < params_.stop_speed) {
    c.brake = 1.0;
    integral_ = 0.0;
    return c;
  }
  const double err = v - speed;
  if (dt > 0) integral_ = std::clamp(integral_ + err * dt, -params_.integral_limit, params_.integral_limit);
  const double u = params_.speed_kp * err + params_.speed_ki * integral_;
  if (v > 0.0) {  // forward: throttle up to the speed, brake beyond it
    c.throttle = std::clamp(u, 0.0, 1.0);
    c.brake = err < -params_.brake_deadband ? std::clamp(-params_.brake_gain * err, 0.0, 1.0) : 0.0;
  } else {  // reverse gear (throttle < 0); brake while still rolling forward, or backwards too fast
    c.throttle = std::clamp(u, -1.0, 0.0);
    const double over = std::max(err, speed);  // [m/s] too fast backwards, or forward at all
    c.brake = over > params_.brake_deadband ? std::clamp(params_.brake_gain * over, 0.0, 1.0) : 0.0;
  }
  if (c.brake > 0) c.throttle = 0.0;
  return c;
}

}  // namespace asg_sim
