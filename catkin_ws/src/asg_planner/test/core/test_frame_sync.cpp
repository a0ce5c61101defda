// The planner's frame synchroniser (frame_sync.hpp): what makes a frame, when a tick may be
// answered, and what is dropped, in the orderings ROS delivers (issue #38).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "asg_planner/frame_sync.hpp"

using namespace asg_planner;

namespace {
constexpr Nanos kWindow = 4096LL * 1000000000LL;
constexpr Nanos kBase = 8192LL * 1000000000LL;
constexpr Nanos kMs = 1000000;

std::vector<uint8_t> kDepthBytes(8 * 8 * 4, 0), kLabelBytes(8 * 8, 0);

ImageIn depth(const std::string& encoding = "32FC1") {
  return {encoding, 8, 8, 32, kDepthBytes.data(), kDepthBytes.size(), nullptr};
}
ImageIn labels(uint32_t width = 8) {
  return {"mono8", width, 8, width, kLabelBytes.data(), size_t(width) * 8, nullptr};
}
OdomIn odomAt(double x) {
  OdomIn o;
  o.pose.translation().x() = x;
  o.state.x = x;
  return o;
}

struct Ready : ::testing::Test {
  FrameSync sync{kWindow};
  void SetUp() override {
    ASSERT_TRUE(sync.announce(7, 1, kBase));
    sync.setMount(Eigen::Isometry3d::Identity());
    sync.setIntrinsicsKnown(true);
  }
};
}  // namespace

TEST(FrameSyncTimes, SecondsAsRosDurationComputesThem) {
  EXPECT_EQ(seconds(1500 * kMs), 1.5);
  EXPECT_EQ(seconds(-500 * kMs), -0.5);
  const Nanos d = 16666666666LL;  // 16.666666666 s: sec + 1e-9 * nsec, not d * 1e-9
  EXPECT_EQ(seconds(d), double(16) + 1e-9 * double(666666666));
}

TEST_F(Ready, OutOfOrderDepthLabelsAndOdometryMakeOneFrame) {
  std::string error;
  EXPECT_TRUE(sync.addLabels(kBase + 66 * kMs, labels()));
  EXPECT_FALSE(sync.nextFrame(&error));
  EXPECT_TRUE(sync.addOdom(kBase + 66 * kMs, odomAt(3.0)));
  EXPECT_FALSE(sync.nextFrame(&error));
  EXPECT_TRUE(sync.addDepth(kBase + 66 * kMs, depth()));
  auto f = sync.nextFrame(&error);
  ASSERT_TRUE(f);
  EXPECT_TRUE(error.empty());
  EXPECT_EQ(f->stamp, kBase + 66 * kMs);
  EXPECT_DOUBLE_EQ(f->t, 0.066);
  EXPECT_EQ(f->T_map_optical.translation().x(), 3.0);  // the pose of its own stamp
  EXPECT_FALSE(sync.nextFrame(&error));
  EXPECT_EQ(sync.framesDone(), 1u);
}

TEST_F(Ready, FramesComeOutInStampOrderAndWaitForMountAndIntrinsics) {
  FrameSync fresh{kWindow};
  fresh.announce(7, 1, kBase);
  std::string error;
  for (Nanos t : {133 * kMs, 0 * kMs, 66 * kMs}) {
    fresh.addDepth(kBase + t, depth());
    fresh.addLabels(kBase + t, labels());
    fresh.addOdom(kBase + t, odomAt(double(t / kMs)));
  }
  EXPECT_FALSE(fresh.nextFrame(&error));  // no camera mount yet
  fresh.setMount(Eigen::Isometry3d::Identity());
  EXPECT_FALSE(fresh.nextFrame(&error));  // no intrinsics yet
  fresh.setIntrinsicsKnown(true);
  std::vector<Nanos> order;
  while (auto f = fresh.nextFrame(&error)) order.push_back(f->stamp - kBase);
  EXPECT_EQ(order, (std::vector<Nanos>{0, 66 * kMs, 133 * kMs}));
}

TEST_F(Ready, ATickWaitsForItsFramesAndItsOdometry) {
  std::string error;
  EXPECT_TRUE(sync.addTick(7, kBase + 50 * kMs, 1));  // one camera frame (t = 0) before it
  EXPECT_FALSE(sync.nextTick());                      // frame not voted yet
  sync.addDepth(kBase, depth());
  sync.addLabels(kBase, labels());
  sync.addOdom(kBase, odomAt(0.0));
  ASSERT_TRUE(sync.nextFrame(&error));
  EXPECT_FALSE(sync.nextTick());  // its own odometry is not here
  sync.addOdom(kBase + 50 * kMs, odomAt(0.25));
  auto t = sync.nextTick();
  ASSERT_TRUE(t);
  EXPECT_EQ(t->stamp, kBase + 50 * kMs);
  EXPECT_EQ(t->state.x, 0.25);
  EXPECT_DOUBLE_EQ(t->t, 0.05);
  EXPECT_FALSE(sync.nextTick());
}

TEST_F(Ready, TicksAreAnsweredInOrderAndOldOdometryIsDropped) {
  for (int k = 0; k < 40; ++k) sync.addOdom(kBase + k * 50 * kMs, odomAt(k));
  sync.addTick(7, kBase + 1900 * kMs, 0);
  sync.addTick(7, kBase + 1950 * kMs, 0);
  EXPECT_EQ(sync.nextTick()->stamp, kBase + 1900 * kMs);
  EXPECT_EQ(sync.nextTick()->stamp, kBase + 1950 * kMs);
  EXPECT_EQ(sync.held(), 21u);  // odometry from 0.95 s on: 1 s behind the newest tick
}

TEST_F(Ready, LateFramesOfAnEarlierRunAndTicksOfAnotherScenarioAreDropped) {
  EXPECT_FALSE(sync.addDepth(kBase - kMs, depth()));
  EXPECT_FALSE(sync.addOdom(kBase + kWindow, odomAt(0)));
  EXPECT_FALSE(sync.addTick(7, kBase - kMs, 0));
  EXPECT_EQ(sync.protocol().staleInRun(), 3u);
  EXPECT_FALSE(sync.addTick(8, kBase + 50 * kMs, 0));  // another scenario: not even stale
  EXPECT_EQ(sync.protocol().staleInRun(), 3u);
  EXPECT_EQ(sync.held(), 0u);
  // A new run drops what the last one left.
  sync.addDepth(kBase + 5 * kMs, depth());
  EXPECT_FALSE(sync.announce(7, 1, kBase));  // the same announcement again: nothing reset
  EXPECT_EQ(sync.held(), 1u);
  EXPECT_TRUE(sync.announce(7, 2, kBase + kWindow));
  EXPECT_EQ(sync.held(), 0u);
}

TEST_F(Ready, AnUnusableFrameIsNamedAndStopsTheRun) {
  std::string error;
  sync.addDepth(kBase, depth("16UC1"));
  sync.addLabels(kBase, labels());
  sync.addOdom(kBase, odomAt(0));
  EXPECT_FALSE(sync.nextFrame(&error));
  EXPECT_EQ(error, "cannot use the frame at t = 0.000 s: depth encoding '16UC1' (expected 32FC1)");
  std::string why;
  EXPECT_FALSE(frameValid(depth(), labels(4), &why));
  EXPECT_EQ(why, "depth and labels differ in size");
  sync.protocol().fail();
  sync.addTick(7, kBase, 0);
  EXPECT_FALSE(sync.nextTick());  // a failed run answers nothing
}

TEST(FrameSyncGrid, TheVehicleGridCapIsNamed) {
  std::string why;
  EXPECT_TRUE(gridFits(100.0, 1.0, &why));
  EXPECT_FALSE(gridFits(5000.0, 1.0, &why));
  EXPECT_EQ(why, "landscape of 5000 m is 5000 vehicle-grid cells per side at 1.00 m spacing (at most 4096)");
}
