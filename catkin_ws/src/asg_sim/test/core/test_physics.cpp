#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "asg_sim/scenario_runner.hpp"
#include "test_util.hpp"

using namespace asg_sim;

namespace {

using Driver = std::function<Command(const ScenarioRunner&)>;

Command cruise(const ScenarioRunner& r, double speed, double steering = 0.0) {
  Command c;
  c.target_speed = speed;
  c.steering = steering;
  const double v = r.state().linear.x();
  c.throttle = v < speed ? std::min(1.0, 0.6 * (speed - v) + 0.15) : 0.0;
  return c;
}

Termination run(ScenarioRunner* r, const Driver& driver, int max_ticks = 60 * 120) {
  for (int i = 0; i < max_ticks; ++i) {
    if (r->controlDue()) r->applyCommand(driver(*r));
    const Termination t = r->step();
    if (t != Termination::kNone) return t;
  }
  return Termination::kNone;
}

}  // namespace

TEST(Physics, VehicleRestsAtStartPose) {
  auto s = emptyScene();
  ScenarioRunner r(nullptr);
  r.reset(s);
  run(&r, [](const ScenarioRunner&) { return Command(); }, 120);
  EXPECT_NEAR(r.state().position.x(), 20.0, 0.05);
  EXPECT_NEAR(r.state().position.y(), 50.0, 0.05);
  EXPECT_NEAR(r.state().position.z(), 0.0, 0.1);
  EXPECT_LT(r.state().speed(), 0.05);
}

TEST(Physics, ReachesTrackingSpeedAndGoalSuccess) {
  auto s = emptyScene();
  ScenarioRunner r(nullptr);
  r.reset(s);
  EXPECT_EQ(run(&r, [](const ScenarioRunner& x) { return cruise(x, 5.0); }), Termination::kSuccess);
  EXPECT_LE(r.distanceToGoal(), 3.0);
  EXPECT_NEAR(r.state().linear.x(), 5.0, 0.6);
  EXPECT_NEAR(r.state().position.y(), 50.0, 0.5);  // straight ahead
  // 60 Hz samples, t = tick / 60.
  EXPECT_EQ(r.trajectory().size(), r.tick() + 1);
  EXPECT_DOUBLE_EQ(r.trajectory().back().t, r.tick() / 60.0);
}

TEST(Physics, PositiveSteeringTurnsLeft) {
  auto s = emptyScene();
  ScenarioRunner r(nullptr);
  r.reset(s);
  run(&r, [](const ScenarioRunner& x) { return cruise(x, 4.0, 0.5); }, 180);
  EXPECT_GT(r.state().yaw(), 0.3);
  EXPECT_GT(r.state().angular.z(), 0.1);
}

TEST(Physics, CollisionWithBush) {
  auto s = emptyScene();
  addObstacle(&s, "juniper", 80.0, 80.0);
  addObstacle(&s, "barberry", 35.0, 50.0);
  ScenarioRunner r(nullptr);
  r.reset(s);
  EXPECT_EQ(run(&r, [](const ScenarioRunner& x) { return cruise(x, 5.0); }), Termination::kCollision);
  EXPECT_EQ(r.collisionWith(), "1:0");
  EXPECT_NEAR(r.state().position.x(), 35.0 - 0.8 - 1.45, 0.5);
}

TEST(Physics, TraversableObstacleIsDrivenOver) {
  auto s = emptyScene();
  addObstacle(&s, "barberry", 35.0, 50.0, 0.15);
  ScenarioRunner r(nullptr);
  r.reset(s);
  EXPECT_EQ(run(&r, [](const ScenarioRunner& x) { return cruise(x, 5.0); }), Termination::kSuccess);
}

TEST(Physics, AllowedCollisionThenStuck) {
  auto s = emptyScene();
  addObstacle(&s, "juniper", 35.0, 50.0);
  s.operational.allow_collisions = true;
  s.operational.stuck_timeout = 2.0;
  ScenarioRunner r(nullptr);
  r.reset(s);
  EXPECT_EQ(run(&r, [](const ScenarioRunner& x) { return cruise(x, 5.0); }),
            Termination::kStuckTimeout);
  EXPECT_EQ(r.collisionWith(), "0:0");
}

TEST(Physics, FlippedBeyondRollLimit) {
  auto s = emptyScene();
  s.operational.max_roll_deg = 1.0;  // any hard turn exceeds it
  ScenarioRunner r(nullptr);
  r.reset(s);
  EXPECT_EQ(run(&r, [](const ScenarioRunner& x) {
              return cruise(x, 8.0, x.time() > 3.0 ? 1.0 : 0.0);
            }),
            Termination::kFlipped);
  EXPECT_GT(std::abs(r.state().roll()) * 180 / M_PI, 1.0);
}

TEST(Physics, SimTimeout) {
  auto s = emptyScene();
  s.operational.sim_timeout = 1.5;
  ScenarioRunner r(nullptr);
  r.reset(s);
  EXPECT_EQ(run(&r, [](const ScenarioRunner&) { return Command(); }), Termination::kSimTimeout);
  EXPECT_NEAR(r.time(), 1.5, 1.0 / 60);
}

TEST(Physics, IdlingTimeout) {
  auto s = emptyScene();
  s.operational.idle_timeout = 1.0;
  ScenarioRunner r(nullptr);
  r.reset(s);
  EXPECT_EQ(run(&r, [](const ScenarioRunner&) { return Command(); }), Termination::kIdlingTimeout);
  EXPECT_LT(r.time(), 1.6);
}

TEST(Physics, StuckTimeout) {
  auto s = emptyScene();
  s.operational.stuck_timeout = 1.0;
  ScenarioRunner r(nullptr);
  r.reset(s);
  // Asks for 5 m/s but holds the brake: stuck, not idle.
  EXPECT_EQ(run(&r, [](const ScenarioRunner&) {
              Command c;
              c.target_speed = 5.0;
              c.brake = 1.0;
              return c;
            }),
            Termination::kStuckTimeout);
}

TEST(Physics, OutOfBounds) {
  auto s = emptyScene();
  s.landscape.border = 5.0;
  s.operational.start_x = 90.0;
  s.operational.goal_x = 10.0;  // goal behind; drive east off the ground
  s.operational.goal_y = 10.0;
  ScenarioRunner r(nullptr);
  r.reset(s);
  EXPECT_EQ(run(&r, [](const ScenarioRunner& x) { return cruise(x, 5.0); }), Termination::kOutOfBounds);
  EXPECT_GT(r.state().position.x(), 105.0);
}

TEST(Physics, SameSceneSameTrajectoryBitForBit) {
  auto s = emptyScene();
  addObstacle(&s, "barberry", 50.0, 55.0);
  auto weave = [](const ScenarioRunner& x) { return cruise(x, 5.0, std::sin(x.time())); };
  ScenarioRunner a(nullptr), b(nullptr);
  a.reset(s);
  run(&a, weave, 600);
  b.reset(s);
  run(&b, weave, 600);
  ASSERT_EQ(a.trajectory().size(), b.trajectory().size());
  for (size_t i = 0; i < a.trajectory().size(); ++i) {
    ASSERT_EQ(a.trajectory()[i].state.position, b.trajectory()[i].state.position) << i;
    ASSERT_EQ(a.trajectory()[i].state.orientation.coeffs(), b.trajectory()[i].state.orientation.coeffs());
  }
  // A world rebuilt after another scenario is still the same world.
  auto other = emptyScene();
  a.reset(other);
  run(&a, weave, 100);
  a.reset(s);
  run(&a, weave, 600);
  EXPECT_EQ(a.trajectory().back().state.position, b.trajectory().back().state.position);
}

TEST(Physics, VehicleRestsOnTheTerrainTiltedWithIt) {
  // Issue #27: on the flank of a hill the vehicle starts on the ground, settles at the same
  // height above it as on flat ground, and pitches with the slope (it faces uphill).
  auto flat = emptyScene();
  ScenarioRunner r0(nullptr);
  r0.reset(flat);
  run(&r0, [](const ScenarioRunner&) { return Command(); }, 120);
  const double rest = r0.state().position.z();

  auto s = emptyScene();
  s.terrain.hills = {{30.0, 50.0, 16.0, 4.0}};  // the start (20, 50) is on its west flank
  s.operational.max_pitch_deg = 70.0;
  ScenarioRunner r(nullptr);
  r.reset(s);
  Command hold;
  hold.brake = 1.0;
  run(&r, [&](const ScenarioRunner&) { return hold; }, 120);
  const Terrain t(s.terrain);
  const auto p = r.state().position;
  EXPECT_NEAR(p.z() - t.height(p.x(), p.y()), rest, 0.15);
  const double slope = std::atan(t.gradient(20.0, 50.0).x());  // uphill towards +x
  EXPECT_GT(slope, 0.3);
  EXPECT_NEAR(-r.state().pitch(), slope, 0.06) << "pitch " << r.state().pitch();  // nose up
  EXPECT_NEAR(r.state().roll(), 0.0, 0.03);
}

TEST(Physics, SameTerrainSameTrajectoryBitForBit) {
  auto s = emptyScene();
  s.terrain = TerrainSpec{0.8, 25.0, 3, {{50.0, 52.0, 10.0, 2.0}}};
  std::vector<std::vector<double>> runs;
  for (int k = 0; k < 2; ++k) {
    ScenarioRunner r(nullptr);
    r.reset(s);
    run(&r, [](const ScenarioRunner& x) { return cruise(x, 5.0); }, 60 * 12);
    std::vector<double> xs;
    for (const auto& q : r.trajectory()) xs.insert(xs.end(), {q.state.position.x(), q.state.position.y(), q.state.position.z()});
    runs.push_back(xs);
  }
  EXPECT_EQ(runs[0], runs[1]);
  EXPECT_GT(runs[0].size(), 100u);
}
