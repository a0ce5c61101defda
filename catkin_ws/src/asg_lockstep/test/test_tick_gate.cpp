// The C++ input gate (tick_gate.hpp): the same cases as the Python twin's tests (test_gate.py).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "asg_lockstep/tick_gate.hpp"

using namespace asg_lockstep;

namespace {
constexpr Nanos kWindow = 4096LL * 1000000000LL;
constexpr Nanos kBase = 8192LL * 1000000000LL;
constexpr Nanos kMs = 1000000;

struct Fixture {
  TickGate gate{kWindow};
  std::vector<std::string> got;
  int goal, points, odom;
  Fixture() {
    goal = gate.add("goal", InputKind::kRun);
    points = gate.add("points", InputKind::kCamera);
    odom = gate.add("odom", InputKind::kState);
    gate.begin(kBase);
  }
  bool offer(int topic, Nanos stamp, const std::string& what) {
    return gate.offer(topic, stamp, [this, what] { got.push_back(what); });
  }
  std::vector<std::string> release() {
    got.clear();
    for (auto& d : gate.release()) d();
    return got;
  }
};
using Names = std::vector<std::string>;
}  // namespace

TEST(TickGate, WaitsForEveryInputThenDeliversInStampOrder) {
  Fixture f;
  f.offer(f.odom, kBase + 50 * kMs, "odom@50");
  f.offer(f.points, kBase, "points@0");
  f.offer(f.odom, kBase, "odom@0");
  ASSERT_TRUE(f.gate.tick(kBase + 50 * kMs, kBase, 1));
  EXPECT_EQ(f.gate.missing(), Names{"goal"});
  f.offer(f.goal, kBase, "goal");
  EXPECT_TRUE(f.gate.missing().empty());
  EXPECT_EQ(f.release(), (Names{"goal", "points@0", "odom@0", "odom@50"}));
  EXPECT_TRUE(f.release().empty());
}

TEST(TickGate, TheCameraFrameOfTheTickMustBeHere) {
  Fixture f;
  f.offer(f.goal, kBase, "goal");
  f.offer(f.odom, kBase + 100 * kMs, "odom@100");
  f.gate.tick(kBase + 100 * kMs, kBase + 66 * kMs, 2);
  EXPECT_EQ(f.gate.missing(), Names{"points"});
  f.offer(f.points, kBase, "points@0");
  EXPECT_EQ(f.gate.missing(), Names{"points"});  // an older frame is not the tick's
  f.offer(f.points, kBase + 66 * kMs, "points@66");
  EXPECT_TRUE(f.gate.missing().empty());
  EXPECT_EQ(f.release(), (Names{"goal", "points@0", "points@66", "odom@100"}));
}

TEST(TickGate, MessagesAfterTheTickStayHeldForTheNext) {
  Fixture f;
  f.offer(f.goal, kBase, "goal");
  f.offer(f.odom, kBase + 50 * kMs, "odom@50");
  f.offer(f.odom, kBase + 100 * kMs, "odom@100");
  f.gate.tick(kBase + 50 * kMs, 0, 0);
  EXPECT_EQ(f.release(), (Names{"goal", "odom@50"}));
  f.gate.tick(kBase + 100 * kMs, 0, 0);
  EXPECT_EQ(f.release(), Names{"odom@100"});
}

TEST(TickGate, LateFramesOfAnEarlierRunAreDroppedAndCounted) {
  Fixture f;
  EXPECT_FALSE(f.offer(f.odom, kBase - 1, "old"));
  EXPECT_EQ(f.gate.stale(), 1u);
  EXPECT_FALSE(f.gate.tick(kBase - 1, 0, 0));
  f.offer(f.odom, kBase + 10 * kMs, "held");
  f.gate.begin(kBase + kWindow);
  EXPECT_EQ(f.gate.stale(), 3u);
  f.gate.tick(kBase + kWindow, 0, 0);
  EXPECT_EQ(f.gate.missing(), (Names{"goal", "odom"}));
  EXPECT_THROW(f.offer(7, kBase + kWindow, "?"), std::out_of_range);
}

TEST(TickGate, TheGoalPublishedBeforeItsRunIsAnnouncedIsKept) {
  Fixture f;
  f.offer(f.goal, kBase + kWindow, "next goal");
  f.offer(f.odom, kBase + 10 * kMs, "odom of this run");
  f.gate.tick(kBase + 10 * kMs, 0, 0);
  EXPECT_EQ(f.gate.missing(), Names{"goal"});
  EXPECT_EQ(f.release(), Names{"odom of this run"});
  f.gate.begin(kBase + kWindow);
  f.offer(f.odom, kBase + kWindow, "odom@0");
  f.gate.tick(kBase + kWindow, 0, 0);
  EXPECT_TRUE(f.gate.missing().empty());
  EXPECT_EQ(f.release(), (Names{"next goal", "odom@0"}));
}
