// The orderings of the lockstep protocol that matter (issue #26), on the worker's side: late,
// duplicated, out-of-window and missing messages.
#include <gtest/gtest.h>

#include "asg_lockstep/stack_protocol.hpp"
#include "asg_lockstep/worker_protocol.hpp"

using asg_lockstep::Nanos;
using asg_lockstep::RunWindow;
using asg_lockstep::WorkerProtocol;

namespace {
constexpr Nanos kS = 1000000000;  // 1 s
constexpr Nanos kWindow = 100000 * kS;

WorkerProtocol makeProtocol(bool lockstep = true) {
  return WorkerProtocol({{"segmenter", "planner"}, "segmenter", lockstep});
}
RunWindow windowOf(uint32_t run) { return {Nanos(run + 1) * kWindow, kWindow}; }
}  // namespace

TEST(WorkerProtocol, EveryStackNodeMustAcknowledgeThisRun) {
  auto p = makeProtocol();
  p.begin(7, 3, windowOf(3));
  EXPECT_FALSE(p.acknowledged());
  EXPECT_EQ(p.missingAcks(), "segmenter, planner");
  EXPECT_FALSE(p.ack(7, 2, "planner"));   // late: the previous run of the same scenario
  EXPECT_FALSE(p.ack(6, 3, "planner"));   // another scenario
  EXPECT_TRUE(p.ack(7, 3, "planner"));
  EXPECT_TRUE(p.ack(7, 3, "planner"));    // duplicated (the announcement is repeated): counts once
  EXPECT_EQ(p.missingAcks(), "segmenter");
  EXPECT_FALSE(p.acknowledged());
  EXPECT_TRUE(p.ack(7, 3, "segmenter"));
  EXPECT_TRUE(p.acknowledged());
  EXPECT_EQ(p.missingAcks(), "");
  p.begin(7, 4, windowOf(4));  // the next run forgets them
  EXPECT_FALSE(p.acknowledged());
}

TEST(WorkerProtocol, OnlyTheAwaitedTickIsAnswered) {
  auto p = makeProtocol();
  const RunWindow w = windowOf(5);
  p.begin(9, 5, w);
  const Nanos tick = w.base + 2 * kS;
  p.await(tick);
  EXPECT_FALSE(p.command(9, tick - kS / 10));       // an older tick's answer, arriving late
  EXPECT_FALSE(p.command(9, windowOf(4).base + 2 * kS));  // the same tick of the previous run
  EXPECT_FALSE(p.command(8, tick));                 // another scenario's
  EXPECT_FALSE(p.answered());
  EXPECT_TRUE(p.command(9, tick));
  EXPECT_TRUE(p.answered());
  EXPECT_TRUE(p.command(9, tick));                  // duplicated: still the answer
  p.consume();
  EXPECT_FALSE(p.answered());
  p.await(tick + kS / 10);
  EXPECT_FALSE(p.command(9, tick));                 // the previous tick's duplicate, late
  EXPECT_FALSE(p.answered());
}

TEST(WorkerProtocol, AnAnswerToTheAwaitedTickSurvivesAwaitingItAgain) {
  auto p = makeProtocol();
  const RunWindow w = windowOf(1);
  p.begin(2, 1, w);
  p.await(w.base);
  ASSERT_TRUE(p.command(2, w.base));
  p.await(w.base);  // the same stamp: the answer stands
  EXPECT_TRUE(p.answered());
  p.await(w.base + kS);
  EXPECT_FALSE(p.answered());
}

TEST(WorkerProtocol, FreeRunningTakesAnyCommandOfTheRun) {
  auto p = makeProtocol(false);
  const RunWindow w = windowOf(2);
  p.begin(4, 2, w);
  p.await(w.base + kS);
  EXPECT_TRUE(p.command(4, w.base + kS / 2));
  EXPECT_FALSE(p.command(4, w.base + kWindow));  // just outside the window
  EXPECT_FALSE(p.command(4, w.base - 1));
}

TEST(WorkerProtocol, BetweenRunsEverythingIsDropped) {
  auto p = makeProtocol();
  const RunWindow w = windowOf(1);
  p.begin(3, 1, w);
  p.end();
  EXPECT_FALSE(p.running());
  EXPECT_FALSE(p.ack(3, 1, "planner"));
  EXPECT_FALSE(p.command(3, w.base));
  EXPECT_FALSE(p.labels(w.base));
  EXPECT_FALSE(p.stackError(3, 1, "planner", "late"));
}

TEST(WorkerProtocol, TheFirstStackErrorOfTheRunIsKept) {
  auto p = makeProtocol();
  p.begin(5, 8, windowOf(8));
  EXPECT_FALSE(p.stackError(5, 7, "planner", "from the run before"));
  EXPECT_EQ(p.error(), "");
  EXPECT_TRUE(p.stackError(5, 8, "segmenter", "camera frames are 320x240"));
  EXPECT_FALSE(p.stackError(5, 8, "planner", "a second one"));
  EXPECT_EQ(p.error(), "segmenter: camera frames are 320x240");
}

TEST(WorkerProtocol, TheSilentNodeIsBlamed) {
  auto p = makeProtocol();
  const RunWindow w = windowOf(6);
  p.begin(1, 6, w);
  // No camera frame yet: the planner owes the command.
  EXPECT_EQ(p.blame(w.base + kS / 2), "planner: no command for control tick t = 0.500 s");
  // A frame the segmenter has not labelled: the segmenter is blamed.
  p.cameraFrame(w.base + kS);
  EXPECT_EQ(p.blame(w.base + kS), "segmenter: no labels for the camera frame at t = 1.000 s");
  EXPECT_FALSE(p.labels(windowOf(5).base + kS));  // the previous run's labels do not count
  EXPECT_EQ(p.blame(w.base + kS), "segmenter: no labels for the camera frame at t = 1.000 s");
  EXPECT_TRUE(p.labels(w.base + kS));
  EXPECT_EQ(p.blame(w.base + kS), "planner: no command for control tick t = 1.000 s");
  // Labels arriving out of order keep the newest.
  p.cameraFrame(w.base + 2 * kS);
  EXPECT_TRUE(p.labels(w.base + 2 * kS));
  EXPECT_TRUE(p.labels(w.base + kS));
  EXPECT_EQ(p.blame(w.base + 2 * kS), "planner: no command for control tick t = 2.000 s");
  EXPECT_EQ(p.cameraFrames(), 2u);
  // A ground-truth stack (no labels node) always blames its planner.
  WorkerProtocol gt({{"planner"}, "", true});
  gt.begin(1, 1, windowOf(1));
  gt.cameraFrame(windowOf(1).base);
  EXPECT_EQ(gt.blame(windowOf(1).base), "planner: no command for control tick t = 0.000 s");
}

// The stack node's side (the planner's): repeated announcements, late and early messages, ticks
// of another scenario, failure.
TEST(StackProtocol, AcknowledgeDefersForMissingInputsThenGivesUpForGood) {
  asg_lockstep::StackProtocol p(kWindow);
  EXPECT_TRUE(p.acknowledge(true));
  for (int i = 0; i < asg_lockstep::kAckDeferrals; ++i) EXPECT_FALSE(p.acknowledge(false)) << i;
  EXPECT_TRUE(p.acknowledge(false));  // acknowledged anyway
  EXPECT_TRUE(p.gaveUp());
  EXPECT_TRUE(p.acknowledge(false));  // and never waits again
}

TEST(StackProtocol, RepeatedAnnouncementsAreOneRun) {
  asg_lockstep::StackProtocol p(kWindow);
  EXPECT_FALSE(p.active());
  EXPECT_TRUE(p.announce(7, 3, windowOf(3).base));
  EXPECT_FALSE(p.announce(7, 3, windowOf(3).base));  // repeated until every node acked
  EXPECT_TRUE(p.active());
  p.fail();
  EXPECT_FALSE(p.active());
  EXPECT_FALSE(p.announce(7, 3, windowOf(3).base));  // still failed: the node says so again
  EXPECT_TRUE(p.failed());
  EXPECT_TRUE(p.announce(7, 4, windowOf(4).base));  // the same scenario again: a new run
  EXPECT_FALSE(p.failed());
  EXPECT_EQ(p.run(), 4u);
}

TEST(StackProtocol, MessagesOfOtherRunsAreDroppedAndCounted) {
  asg_lockstep::StackProtocol p(kWindow);
  EXPECT_FALSE(p.current(kS));  // before any run
  const RunWindow w = windowOf(2);
  p.announce(5, 2, w.base);
  EXPECT_EQ(p.staleInRun(), 0u);
  EXPECT_FALSE(p.current(windowOf(1).base + kS));  // late: the run before
  EXPECT_TRUE(p.current(w.base));
  EXPECT_TRUE(p.current(w.base + kWindow - 1));
  EXPECT_FALSE(p.current(w.base + kWindow));  // past the window
  EXPECT_FALSE(p.tick(4, w.base + kS));         // another scenario's tick
  EXPECT_TRUE(p.tick(5, w.base + kS));
  EXPECT_EQ(p.staleInRun(), 2u);
  p.announce(5, 3, windowOf(3).base);
  EXPECT_EQ(p.staleInRun(), 0u);
  EXPECT_FALSE(p.tick(5, w.base + kS));  // the previous run's tick, late
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
