// The one lockstep run loop (run_loop.hpp, issue #38): its order of calls, its ends, and that it
// drives the vehicle exactly as the loop each caller used to write by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "asg_sim/renderer.hpp"
#include "asg_sim/run_loop.hpp"
#include "test_util.hpp"

using namespace asg_sim;

namespace {

Command scripted(const ScenarioRunner& r) {  // a weave, so that every tick's command matters
  Command c;
  c.throttle = 0.6;
  c.steering = 0.4 * std::sin(r.time());
  return c;
}

struct Recorder : LoopStack {
  ScenarioRunner* runner;
  std::vector<std::string> calls;
  int fail_at_control = -1, fail_after_step = -1, keep_from = -1, controls = 0, steps = 0;
  bool every_tick = false;
  explicit Recorder(ScenarioRunner* r) : runner(r) {}
  bool stateEveryTick() const override { return every_tick; }
  void onState(double t) override { calls.push_back("state " + std::to_string(int(t * 60 + 0.5))); }
  void onCamera(double t) override { calls.push_back("camera " + std::to_string(int(t * 60 + 0.5))); }
  bool onControl(double t, Command* cmd, bool* apply, std::string* error) override {
    calls.push_back("control " + std::to_string(int(t * 60 + 0.5)));
    if (controls++ == fail_at_control) {
      *error = "no answer";
      return false;
    }
    *cmd = scripted(*runner);
    *apply = keep_from < 0 || controls <= keep_from;
    return true;
  }
  bool afterStep(std::string* error) override {
    calls.push_back("step");
    if (steps++ == fail_after_step) {
      *error = "cancelled";
      return false;
    }
    return true;
  }
};

}  // namespace

TEST(RunLoop, StateCameraControlThenPhysicsAtEachTick) {
  ScenarioRunner r(&sharedRenderer());
  r.reset(emptyScene());
  Recorder s(&r);
  s.fail_after_step = 12;  // thirteen ticks are enough to see the pattern
  const LoopEnd end = runLoop(&r, &s);
  EXPECT_EQ(end.termination, Termination::kError);
  EXPECT_EQ(end.error, "cancelled");
  std::vector<std::string> want;
  for (int k = 0; k <= 12; ++k) {
    const bool cam = k % r.config().camera_every == 0, ctl = k % r.config().control_every == 0;
    if (cam || ctl) want.push_back("state " + std::to_string(k));
    if (cam) want.push_back("camera " + std::to_string(k));
    if (ctl) want.push_back("control " + std::to_string(k));
    want.push_back("step");
  }
  EXPECT_EQ(s.calls, want);
}

TEST(RunLoop, StateEveryTickWhenAsked) {
  ScenarioRunner r(nullptr);  // no camera
  r.reset(emptyScene());
  Recorder s(&r);
  s.every_tick = true;
  s.fail_after_step = 5;
  runLoop(&r, &s);
  int states = 0;
  for (const auto& c : s.calls) states += c.rfind("state", 0) == 0;
  EXPECT_EQ(states, 6);
}

TEST(RunLoop, AFailedControlEndsTheRunBeforeItsPhysicsTick) {
  ScenarioRunner r(nullptr);
  r.reset(emptyScene());
  Recorder s(&r);
  s.fail_at_control = 2;  // the third control tick: tick 6
  const LoopEnd end = runLoop(&r, &s);
  EXPECT_EQ(end.termination, Termination::kError);
  EXPECT_EQ(end.error, "no answer");
  EXPECT_EQ(s.calls.back(), "control 6");
  EXPECT_EQ(r.tick(), 6u);  // no step after the unanswered tick
}

TEST(RunLoop, DrivesExactlyAsTheHandWrittenLoop) {
  // The loop the closed-loop tool and the benchmark wrote by hand before issue #38.
  SceneSpec spec = emptyScene();
  addObstacle(&spec, "barberry", 60.0, 52.0);
  ScenarioRunner a(nullptr), b(nullptr);
  a.reset(spec);
  Termination term = Termination::kNone;
  while (term == Termination::kNone) {
    if (a.controlDue()) a.applyCommand(scripted(a));
    term = a.step();
  }
  b.reset(spec);
  Recorder s(&b);
  const LoopEnd end = runLoop(&b, &s);
  EXPECT_EQ(end.termination, term);
  ASSERT_EQ(a.trajectory().size(), b.trajectory().size());
  for (size_t i = 0; i < a.trajectory().size(); ++i) {
    ASSERT_EQ(a.trajectory()[i].state.position, b.trajectory()[i].state.position) << i;  // bit for bit
    ASSERT_EQ(a.trajectory()[i].state.linear, b.trajectory()[i].state.linear) << i;
  }
  EXPECT_EQ(a.commandsReceived(), b.commandsReceived());
}

TEST(RunLoop, AnUnappliedCommandLeavesTheLastOneInForce) {
  ScenarioRunner r(nullptr);
  r.reset(emptyScene());
  Recorder s(&r);
  s.keep_from = 3;  // commands applied at the first three control ticks only
  s.fail_after_step = 30;
  runLoop(&r, &s);
  EXPECT_EQ(r.commandsReceived(), 3u);
}
