#pragma once
/// @file physics.hpp
/// Bullet world: static heightfield ground, cylinder collision shapes for obstacles, and a
/// Polaris MRZR-like utility vehicle (btRaycastVehicle) driven by throttle, steering and brake.
/// A fresh world per scenario and a fixed step make every run repeat bit for bit.

#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <vector>

#include "asg_sim/scene.hpp"

namespace asg_sim {

/// Vehicle figures (MRZR2-like; documented in docs/simulator.md).
struct VehicleParams {
  double mass = 880.0;               ///< [kg]
  double length = 2.9;               ///< [m] chassis box
  double width = 1.5;                ///< [m]
  double chassis_height = 0.5;       ///< [m]
  double com_height = 0.75;          ///< [m] centre of mass above the ground at rest
  double wheelbase = 2.3;            ///< [m]
  double track = 1.3;                ///< [m]
  double wheel_radius = 0.33;        ///< [m]
  double wheel_width = 0.25;         ///< [m]
  double suspension_rest = 0.25;     ///< [m]
  double suspension_stiffness = 30.0;
  double damping_compression = 4.4;
  double damping_relaxation = 2.3;
  double friction_slip = 1.5;
  double roll_influence = 0.1;
  double max_steer = 0.6;            ///< [rad] wheel angle at steering = 1
  double max_steer_rate = 1.2;       ///< [rad/s] steering actuator slew rate (lock to lock in 1 s)
  double max_engine_force = 3200.0;  ///< [N] total at throttle = 1 (four-wheel drive)
  double max_reverse_throttle = 0.5; ///< [-] share of max_engine_force backwards, at throttle = -1
  double max_brake = 60.0;           ///< Bullet brake impulse per wheel at brake = 1
  double rolling_brake = 2.0;        ///< brake applied when throttle and brake are 0 (engine drag)
  double linear_damping = 0.05;      ///< [-] chassis air drag
};

/// Drive-by-wire command.
struct Command {
  double throttle = 0.0;      ///< [-] -1..1; below 0: reverse gear (VehicleParams::max_reverse_throttle)
  double steering = 0.0;      ///< [-] -1 (right) .. 1 (left)
  double brake = 0.0;         ///< [-] 0..1
  double target_speed = 0.0;  ///< [m/s] what the stack asks for (idle/stuck detection)
};

/// base_link state: pose in map, velocities in base_link.
struct VehicleState {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();          ///< [m] map
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();            ///< [m/s] base_link
  Eigen::Vector3d angular = Eigen::Vector3d::Zero();           ///< [rad/s] base_link
  /// [m/s] ground speed (planar). Bullet leaves one substep of gravity in the vertical
  /// velocity of a resting raycast vehicle, so the vertical part is left out.
  double speed() const { return std::hypot(linear.x(), linear.y()); }
  double yaw() const;
  double roll() const;
  double pitch() const;
  Eigen::Isometry3d pose() const;
};

class PhysicsWorld {
 public:
  PhysicsWorld(const SceneSpec& spec, const std::vector<PlacedObstacle>& placed,
               const VehicleParams& vehicle = VehicleParams());
  ~PhysicsWorld();
  PhysicsWorld(const PhysicsWorld&) = delete;
  PhysicsWorld& operator=(const PhysicsWorld&) = delete;

  /// Applies a command (clamped to its ranges) until the next call.
  void setCommand(const Command& cmd);
  /// Advances by dt [s] in `substeps` equal fixed steps.
  void step(double dt, int substeps);
  VehicleState state() const;
  /// Id (PlacedObstacle::id) of an obstacle the chassis touches now, 0 if none.
  uint32_t contactObstacle() const;
  const VehicleParams& vehicle() const { return params_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  VehicleParams params_;
  double steer_target_ = 0.0;  // [rad] commanded wheel angle
  double steer_ = 0.0;         // [rad] actual wheel angle, slewing towards the target
};

}  // namespace asg_sim
