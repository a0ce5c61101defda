#pragma once
/// @file twist_controller.hpp
/// From a velocity command (geometry_msgs/Twist semantics: forward speed and yaw rate, as a ROS
/// stack publishes on `cmd_vel`) to the vehicle's drive-by-wire command (throttle, steering,
/// brake), on the vehicle's own model:
///   - steering: the kinematic bicycle, wheel angle = atan(wheelbase x yaw rate / speed), divided
///     by the steering lock; the speed is the commanded one, at least `min_turn_speed`, so the
///     wheel angle a stack asks for does not swing with the measured speed;
///   - speed: PI on the speed error to throttle, brake above the commanded speed (the same law
///     as the paper's follower), full brake for a stop command at rest.
/// The steering actuator's slew rate is the simulator's (PhysicsWorld), not repeated here.
/// A negative speed drives backwards (reverse gear, issue #55), up to `max_reverse_speed`; the
/// steering law then turns the other way for the same yaw rate, as a car's does. No ROS; time
/// comes from the caller.

#include "asg_sim/physics.hpp"

namespace asg_sim {

struct TwistControllerParams {
  double wheelbase = 2.3;        ///< [m] (VehicleParams::wheelbase)
  double steering_lock = 0.6;    ///< [rad] wheel angle at steering = 1 (VehicleParams::max_steer)
  double min_turn_speed = 1.0;   ///< [m/s] speed floor of the steering law
  double speed_kp = 0.5;         ///< [1/(m/s)] throttle per m/s of speed error
  double speed_ki = 0.1;         ///< [1/m] throttle per metre of integrated speed error
  double integral_limit = 5.0;   ///< [m] anti-windup bound of the integrated speed error
  double brake_gain = 0.5;       ///< [1/(m/s)] brake per m/s above the commanded speed
  double brake_deadband = 0.3;   ///< [m/s] overspeed tolerated before braking
  double stop_speed = 0.05;      ///< [m/s] commanded speed below this is a stop: full brake
  double max_speed = 15.0;       ///< [m/s] commands above are clamped (bad input is not obeyed)
  double max_reverse_speed = 3.0;  ///< [m/s] backwards: commands below -this are clamped

  /// The vehicle's geometry taken from the simulator's model (one home for those figures).
  static TwistControllerParams forVehicle(const VehicleParams& v) {
    TwistControllerParams p;
    p.wheelbase = v.wheelbase;
    p.steering_lock = v.max_steer;
    return p;
  }
};

/// A velocity command: what geometry_msgs/Twist carries for a ground vehicle.
struct VelocityCommand {
  double speed = 0.0;     ///< [m/s] forward (linear.x); negative: backwards
  double yaw_rate = 0.0;  ///< [rad/s] counter-clockwise, left positive (angular.z)
};

class TwistController {
 public:
  explicit TwistController(const TwistControllerParams& params = TwistControllerParams());
  /// Forgets the integral (a new run).
  void reset();
  /// The command for one control period of `dt` [s] at measured forward speed `speed` [m/s].
  /// Non-finite inputs give a stop (full brake).
  Command update(const VelocityCommand& cmd, double speed, double dt);
  /// [rad] the wheel angle the last update asked for (before the lock's clamp).
  double wheelAngle() const { return wheel_angle_; }
  const TwistControllerParams& params() const { return params_; }

 private:
  TwistControllerParams params_;
  double integral_ = 0.0;     // [m]
  double wheel_angle_ = 0.0;  // [rad]
};

}  // namespace asg_sim
