#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "asg_sim/scenario_runner.hpp"
#include "asg_sim/twist_controller.hpp"
#include "test_util.hpp"

using namespace asg_sim;

namespace {
const TwistControllerParams kVehicle = TwistControllerParams::forVehicle(VehicleParams());

// Drives the real vehicle model with one velocity command for `seconds`; returns the runner.
void drive(ScenarioRunner* r, TwistController* c, VelocityCommand cmd, double seconds) {
  const double dt = double(r->config().control_every) / r->config().tick_hz;
  const int ticks = int(seconds * r->config().tick_hz);
  for (int i = 0; i < ticks; ++i) {
    if (r->controlDue()) r->applyCommand(c->update(cmd, r->state().linear.x(), dt));
    ASSERT_EQ(r->step(), Termination::kNone) << "at t = " << r->time() << " s";
  }
}
}  // namespace

TEST(TwistController, SteeringFollowsTheBicycleModelAndItsSign) {
  TwistController c(kVehicle);
  // yaw rate 0.5 rad/s at 4 m/s: wheel angle atan(2.3 x 0.5 / 4) = 0.2801 rad.
  Command left = c.update({4.0, 0.5}, 4.0, 0.05);
  EXPECT_NEAR(c.wheelAngle(), std::atan(2.3 * 0.5 / 4.0), 1e-12);
  EXPECT_NEAR(left.steering, std::atan(2.3 * 0.5 / 4.0) / 0.6, 1e-12);
  Command right = c.update({4.0, -0.5}, 4.0, 0.05);
  EXPECT_LT(right.steering, 0.0);  // clockwise is right, steering -1 is full right
  EXPECT_EQ(c.update({4.0, 10.0}, 4.0, 0.05).steering, 1.0);  // beyond the lock: clamped
  // At a crawl the steering law uses the floor speed, not a near-zero divisor.
  EXPECT_NEAR(c.update({0.2, 0.1}, 0.2, 0.05).steering, std::atan(2.3 * 0.1 / 1.0) / 0.6, 1e-12);
}

TEST(TwistController, StopsOnZeroOrNonFiniteCommands) {
  TwistController c(kVehicle);
  for (double v : {0.0, 0.04, -0.04}) {
    const Command s = c.update({v, 0.0}, 3.0, 0.05);
    EXPECT_EQ(s.throttle, 0.0);
    EXPECT_EQ(s.brake, 1.0);
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Command n = c.update({nan, 0.0}, 3.0, 0.05);
  EXPECT_EQ(n.brake, 1.0);
  EXPECT_EQ(n.throttle, 0.0);
  EXPECT_EQ(c.update({3.0, nan}, 3.0, 0.05).brake, 1.0);
  EXPECT_EQ(c.update({99.0, 0.0}, 0.0, 0.05).target_speed, kVehicle.max_speed);
}

TEST(TwistController, BrakesAboveTheCommandedSpeedOnly) {
  TwistController c(kVehicle);
  const Command over = c.update({3.0, 0.0}, 4.0, 0.05);  // 1 m/s over: brake, no throttle
  EXPECT_GT(over.brake, 0.0);
  EXPECT_EQ(over.throttle, 0.0);
  c.reset();
  const Command slight = c.update({3.0, 0.0}, 3.2, 0.05);  // within the deadband: coast
  EXPECT_EQ(slight.brake, 0.0);
  const Command under = c.update({3.0, 0.0}, 1.0, 0.05);
  EXPECT_GT(under.throttle, 0.0);
  EXPECT_EQ(under.brake, 0.0);
}

TEST(TwistController, ReverseGearBelowZero) {
  // Issue #55: a negative speed is reverse, not a stop.
  TwistController c(kVehicle);
  const Command back = c.update({-2.0, 0.0}, 0.0, 0.05);
  EXPECT_LT(back.throttle, 0.0);
  EXPECT_EQ(back.brake, 0.0);
  EXPECT_EQ(back.target_speed, -2.0);
  c.reset();
  const Command rolling = c.update({-2.0, 0.0}, 3.0, 0.05);  // still rolling forward: brake first
  EXPECT_GT(rolling.brake, 0.0);
  EXPECT_EQ(rolling.throttle, 0.0);
  EXPECT_EQ(c.update({-99.0, 0.0}, 0.0, 0.05).target_speed, -kVehicle.max_reverse_speed);
  // Backwards, the same yaw rate turns the wheels the other way.
  c.update({-2.0, 0.3}, -2.0, 0.05);
  EXPECT_NEAR(c.wheelAngle(), std::atan(2.3 * 0.3 / -2.0), 1e-12);
  // Forward commands are what they were: the same numbers as before reverse existed.
  TwistController d(kVehicle);
  const Command fwd = d.update({4.0, 0.2}, 3.0, 0.05);
  EXPECT_NEAR(fwd.throttle, std::clamp(0.5 * 1.0 + 0.1 * 0.05, 0.0, 1.0), 1e-12);
}

TEST(TwistController, RejectsImpossibleParameters) {
  TwistControllerParams p = kVehicle;
  p.wheelbase = 0.0;
  EXPECT_THROW(TwistController{p}, std::invalid_argument);
  p = kVehicle;
  p.steering_lock = 2.0;
  EXPECT_THROW(TwistController{p}, std::invalid_argument);
}

// On the real vehicle model (Bullet raycast vehicle, steering slew): the speed and yaw rate a
// stack asks for are what it gets, near enough for a local planner to trust them.
TEST(TwistController, TracksSpeedAndYawRateOnTheVehicleModel) {
  struct Case {
    double speed, yaw_rate;
  };
  for (const Case k : {Case{4.0, 0.0}, Case{4.0, 0.25}, Case{3.0, -0.3}, Case{6.0, 0.15}, Case{-2.0, 0.0},
                       Case{-2.0, 0.2}}) {
    auto s = emptyScene();
    ScenarioRunner r(nullptr);
    r.reset(s);
    TwistController c(TwistControllerParams::forVehicle(VehicleParams()));
    drive(&r, &c, {k.speed, k.yaw_rate}, 8.0);
    if (HasFatalFailure()) return;
    // Averaged over the last second (60 ticks) of trajectory samples.
    const auto& traj = r.trajectory();
    double v = 0, w = 0;
    for (size_t i = traj.size() - 60; i < traj.size(); ++i) {
      v += traj[i].state.linear.x() / 60.0;
      w += traj[i].state.angular.z() / 60.0;
    }
    SCOPED_TRACE("speed " + std::to_string(k.speed) + " m/s, yaw rate " + std::to_string(k.yaw_rate));
    EXPECT_NEAR(v, k.speed, 0.1 * std::abs(k.speed));
    EXPECT_NEAR(w, k.yaw_rate, 0.03 + 0.15 * std::abs(k.yaw_rate));
  }
}

TEST(TwistController, StopCommandHaltsTheVehicle) {
  auto s = emptyScene();
  ScenarioRunner r(nullptr);
  r.reset(s);
  TwistController c(kVehicle);
  drive(&r, &c, {5.0, 0.0}, 6.0);
  if (HasFatalFailure()) return;
  drive(&r, &c, {0.0, 0.0}, 4.0);
  if (HasFatalFailure()) return;
  EXPECT_LT(r.state().speed(), 0.1);
}
