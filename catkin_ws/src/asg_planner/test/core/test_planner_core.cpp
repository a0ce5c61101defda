#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <vector>

#include "asg_planner/astar.hpp"
#include "asg_planner/path_follower.hpp"
#include "asg_planner/projection.hpp"
#include "asg_planner/vote_grid.hpp"
#include "asg_planner/voting_planner.hpp"

using namespace asg_planner;

namespace {

// Optical frame of a level camera at (x, y, 1.4) looking along map +x.
Eigen::Isometry3d levelCamera(double x, double y) {
  Eigen::Matrix3d R;
  R << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // columns: optical x, y, z in map
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() << x, y, 1.4;
  return T;
}

struct Frame {
  int w = 64, h = 64;
  std::vector<float> depth = std::vector<float>(64 * 64, NAN);
  std::vector<uint8_t> labels = std::vector<uint8_t>(64 * 64, 0);
};

Intrinsics K64() { return {32.0, 32.0, 31.5, 31.5}; }  // 90 degrees, 64 px

}  // namespace

TEST(VoteGrid, NearestVertexAndCap) {
  VoteGrid g(5.0, 50);
  EXPECT_EQ(g.nearest(12.4, -2.6).i, 2);
  EXPECT_EQ(g.nearest(12.4, -2.6).j, -1);
  EXPECT_EQ(g.add({2, 3}, 30), 30u);
  EXPECT_EQ(g.add({2, 3}, 30), 50u);  // capped
  EXPECT_EQ(g.add({2, 3}), 50u);
  EXPECT_EQ(g.votes({2, 3}), 50u);
  EXPECT_EQ(g.votes({3, 2}), 0u);
  g.add({-4, 7}, 1);
  const auto v = g.voted();
  ASSERT_EQ(v.size(), 2u);
  EXPECT_EQ(g.votedCount(), 2u);  // the running counters agree with the tree
  EXPECT_EQ(g.totalVotes(), 51u);
  EXPECT_EQ(v[0].first.i, -4);
  EXPECT_EQ(v[1].second, 50u);
  g.clear();
  EXPECT_TRUE(g.voted().empty());
  EXPECT_EQ(g.votedCount(), 0u);
  EXPECT_EQ(g.totalVotes(), 0u);
}

TEST(Projection, WallVotesLandOnTheRightVertices) {
  // A wall 20 m ahead of a camera at (30, 50): labelled pixels of rows below the horizon
  // (world z < 1.4 m) and the columns of the central 16 px. Planar depth 20 m.
  Frame f;
  for (int v = 32; v < 64; ++v)
    for (int u = 24; u < 40; ++u) {
      f.depth[v * 64 + u] = 20.0f;
      f.labels[v * 64 + u] = 1;
    }
  VoteGrid g(5.0, 50);
  const size_t n = castVotes(f.depth.data(), f.labels.data(), 64, 64, K64(), levelCamera(30, 50),
                             ProjectionParams(), &g);
  EXPECT_EQ(n, 32u * 16u);
  // y = 50 - (u - 31.5) / 32 * 20 spans 45.3 .. 54.7: vertices j = 9, 10, 11; x = 50: i = 10.
  std::set<int> js;
  for (const auto& [vx, votes] : g.voted()) {
    EXPECT_EQ(vx.i, 10);
    js.insert(vx.j);
    EXPECT_LE(votes, 50u);
  }
  EXPECT_EQ(js, (std::set<int>{9, 10, 11}));
  EXPECT_EQ(g.votes({10, 10}), 50u);  // many pixels, capped
}

TEST(Projection, HighPointsAndOtherLabelsDoNotVote) {
  Frame f;
  // Rows v < 27 at 20 m are higher than 1.4 + 20 * (31.5 - 27) / 32 = 4.2 m; v = 30 is ~2.3 m.
  for (int v = 0; v < 31; ++v)
    for (int u = 0; u < 64; ++u) {
      f.depth[v * 64 + u] = 20.0f;
      f.labels[v * 64 + u] = 1;
    }
  for (int u = 0; u < 64; ++u) {  // ground and sky labels below
    f.depth[60 * 64 + u] = 5.0f;
    f.labels[60 * 64 + u] = (u % 2) ? 0 : 2;
  }
  VoteGrid g(1.0, 50);
  EXPECT_EQ(castVotes(f.depth.data(), f.labels.data(), 64, 64, K64(), levelCamera(0, 0),
                      ProjectionParams(), &g), 0u);
  EXPECT_TRUE(g.voted().empty());
}

TEST(Projection, OnAHillTheHeightRuleIsAboveTheGroundTheStackSees) {
  // Issue #27: the vehicle on a 4 m plateau, camera at map z 5.4, level, looking along +x. The
  // plateau's ground fills the rows below the horizon; a wall 20 m ahead covers rows 28..33
  // (map z 7.6 .. 4.5, so 3.6 .. 0.5 m above the plateau). Against map z every wall point is
  // above 2 m and none votes; against the ground the planner estimates from its own returns,
  // rows 31..33 (1.7, 1.1, 0.5 m above it) vote and row 30 (2.3 m) does not.
  Frame f;
  for (int v = 34; v < 64; ++v)
    for (int u = 0; u < 64; ++u) f.depth[v * 64 + u] = float(1.4 * 32.0 / (v - 31.5));  // plateau, label 0
  for (int v = 28; v < 34; ++v)
    for (int u = 24; u < 40; ++u) {
      f.depth[v * 64 + u] = 20.0f;
      f.labels[v * 64 + u] = 1;
    }
  Eigen::Isometry3d T = levelCamera(0, 0);
  T.translation().z() = 5.4;
  ProjectionParams p;
  p.ground_cell = 5.0;
  VoteGrid map_rule(1.0, 50), ground_rule(1.0, 50);
  GroundMap ground(p.ground_cell);
  EXPECT_EQ(castVotes(f.depth.data(), f.labels.data(), 64, 64, K64(), T, p, &map_rule), 0u);
  p.height_above_ground = true;
  EXPECT_EQ(castVotes(f.depth.data(), f.labels.data(), 64, 64, K64(), T, p, &ground_rule, &ground), 3u * 16u);
  EXPECT_NEAR(ground.lowNear(20.0, 0.0), 4.0, 0.01);
  EXPECT_TRUE(std::isinf(ground.lowNear(80.0, 0.0)));  // nothing seen there
  // rviz draws votes and plans on that ground, and at the fallback where none was seen
  EXPECT_NEAR(ground.heightOr(20.0, 0.0, 0.0), 4.0, 0.01);
  EXPECT_EQ(ground.heightOr(80.0, 0.0, -1.5), -1.5);
  // On flat ground (camera at 1.4) both rules agree: the wall's points below 2 m vote.
  T.translation().z() = 1.4;  // the same depths now meet the ground at map z 0
  VoteGrid a(1.0, 50), b(1.0, 50);
  GroundMap flat(p.ground_cell);
  p.height_above_ground = false;
  const size_t na = castVotes(f.depth.data(), f.labels.data(), 64, 64, K64(), T, p, &a);
  p.height_above_ground = true;
  const size_t nb = castVotes(f.depth.data(), f.labels.data(), 64, 64, K64(), T, p, &b, &flat);
  EXPECT_GT(na, 0u);
  EXPECT_EQ(na, nb);
}

TEST(AStar, CostFormulaMatchesHandComputedEdge) {
  VoteGrid g(5.0, 50);
  g.add({1, 1}, 10);  // vertex (5, 5)
  g.add({0, 0}, 50);  // vertex (0, 0)
  AStarParams p;      // alpha 1/50, sigma 2.5
  p.edge_points = 1;
  // Midpoint (2.5, 0): d^2 = 31.25 and 6.25.
  const double expected = 5.0 * (1.0 + 10.0 / 50.0 * std::exp(-31.25 / 12.5) +
                                  50.0 / 50.0 * std::exp(-6.25 / 12.5));
  EXPECT_NEAR(edgeCost({0, 0}, {5, 0}, g, p), expected, 1e-12);
  EXPECT_NEAR(expected, 5.0 * (1 + 0.0164170 + 0.6065307), 1e-6);
  EXPECT_DOUBLE_EQ(edgeCost({0, 0}, {5, 0}, VoteGrid(5.0), p), 5.0);
  // The reference's version with sigma 2.5 m: the kernel sum averaged over (0, 0), (2.5, 0), (5, 0).
  // At (0, 0): d^2 = 50 and 0; at (5, 0): d^2 = 25 and 25.
  p.edge_points = 3;
  const double f0 = 10.0 * std::exp(-50.0 / 12.5) + 50.0;
  const double fm = 10.0 * std::exp(-31.25 / 12.5) + 50.0 * std::exp(-6.25 / 12.5);
  const double f1 = 10.0 * std::exp(-25.0 / 12.5) + 50.0 * std::exp(-25.0 / 12.5);
  EXPECT_NEAR(edgeCost({0, 0}, {5, 0}, g, p), 5.0 * (1.0 + (f0 + fm + f1) / 3.0 / 50.0), 1e-12);
  // A* uses the same costs: a one-edge plan costs what edgeCost says.
  const PlannedPath one = planPath(g, p, 100.0, {0, 0}, {5, 0});
  EXPECT_NEAR(one.cost, edgeCost({0, 0}, {5, 0}, g, p), 1e-12);
}

TEST(AStar, StraightPathOnEmptyGrid) {
  VoteGrid g(5.0);
  AStarParams p;
  const PlannedPath path = planPath(g, p, 100.0, {10, 50}, {90, 50});
  ASSERT_TRUE(path.found);
  for (const auto& q : path.points) EXPECT_DOUBLE_EQ(q.y(), 50.0);
  EXPECT_NEAR(path.cost, 80.0, 1e-9);
  const PlannedPath diag = planPath(g, p, 100.0, {20, 20}, {80, 80});
  ASSERT_TRUE(diag.found);
  for (const auto& q : diag.points) EXPECT_NEAR(q.x(), q.y(), 1e-9);
  EXPECT_NEAR(diag.cost, 60.0 * M_SQRT2, 1e-9);
}

TEST(AStar, DetoursAroundAVotedWall) {
  // A fully voted wall three vertices thick, x = 45 .. 55, y = 35 .. 65, across the straight line.
  VoteGrid g(5.0);
  for (int i = 9; i <= 11; ++i)
    for (int j = 7; j <= 13; ++j) g.add({i, j}, 50);
  AStarParams p;
  const PlannedPath path = planPath(g, p, 100.0, {10, 50}, {90, 50});
  ASSERT_TRUE(path.found);
  double len = 0;
  for (size_t i = 1; i < path.points.size(); ++i) len += (path.points[i] - path.points[i - 1]).norm();
  EXPECT_GT(len, 82.0);  // longer than the straight 80 m
  for (const auto& q : path.points) {
    if (std::abs(q.x() - 50.0) <= 5.0) {
      EXPECT_GE(std::abs(q.y() - 50.0), 20.0) << q.transpose();
    }
  }
  // Cheaper than pushing straight through.
  double straight = 0;
  for (int k = 0; k < 16; ++k) straight += edgeCost({10.0 + 5 * k, 50}, {15.0 + 5 * k, 50}, g, p);
  EXPECT_LT(path.cost, straight);
}

TEST(AStar, OneVotedVertexIsCheaperToCrossThanAWideDetour) {
  // Votes are soft costs (alpha = 1/50): a lone voted vertex on the line is driven past closely.
  VoteGrid g(5.0);
  g.add({10, 10}, 50);
  const PlannedPath path = planPath(g, AStarParams(), 100.0, {10, 50}, {90, 50});
  ASSERT_TRUE(path.found);
  for (const auto& q : path.points) EXPECT_LE(std::abs(q.y() - 50.0), 5.0 + 1e-9);
}

TEST(Follower, LookaheadOnPath) {
  const std::vector<Eigen::Vector2d> path = {{0, 0}, {10, 0}, {10, 10}};
  const auto la = PathFollower::lookahead(path, {2, 1}, 5.0);
  EXPECT_NEAR((la - Eigen::Vector2d(2, 1)).norm(), 5.0, 1e-9);
  EXPECT_NEAR(la.y(), 0.0, 1e-9);
  EXPECT_GT(la.x(), 2.0);
  EXPECT_TRUE(PathFollower::lookahead(path, {10, 8}, 5.0).isApprox(Eigen::Vector2d(10, 10)));
  // Far from the path: the closest point.
  EXPECT_TRUE(PathFollower::lookahead(path, {5, -30}, 5.0).isApprox(Eigen::Vector2d(5, 0)));
}

TEST(Follower, HairpinInsideTheCircleFirstOrFurthestCrossing) {
  // The path leaves the 3 m circle at (3, 0), comes back in at (2.24, 2) and leaves again at
  // (0, 3): the reference aims at the first exit, the default at the furthest one.
  const std::vector<Eigen::Vector2d> path = {{0, 0}, {4, 0}, {4, 2}, {0, 2}, {0, 10}};
  EXPECT_TRUE(PathFollower::lookahead(path, {0, 0}, 3.0, true).isApprox(Eigen::Vector2d(3, 0)));
  EXPECT_TRUE(PathFollower::lookahead(path, {0, 0}, 3.0, false).isApprox(Eigen::Vector2d(0, 3)));
  // Without a hairpin both agree.
  const std::vector<Eigen::Vector2d> straight = {{0, 0}, {10, 0}, {10, 10}};
  EXPECT_TRUE(PathFollower::lookahead(straight, {2, 1}, 5.0, true)
                  .isApprox(PathFollower::lookahead(straight, {2, 1}, 5.0, false)));
}

TEST(Follower, ConvergesOntoStraightPathFromOffset) {
  PathFollower f;
  f.setPath({{0, 0}, {300, 0}});
  VehicleState2D s{0.0, 3.0, 0.0, 5.0};
  const double wheelbase = 2.3, max_steer = 0.6, dt = 0.05;
  double max_abs_y_late = 0;
  for (int k = 0; k < 400; ++k) {  // 20 s at 20 Hz, kinematic bicycle at 5 m/s
    const ControlCommand c = f.update(k * dt, s, 5.0);
    const double delta = c.steering * max_steer;
    s.yaw += s.speed / wheelbase * std::tan(delta) * dt;
    s.x += s.speed * std::cos(s.yaw) * dt;
    s.y += s.speed * std::sin(s.yaw) * dt;
    if (k > 200) max_abs_y_late = std::max(max_abs_y_late, std::abs(s.y));
  }
  EXPECT_LT(max_abs_y_late, 0.2);
  EXPECT_LT(std::abs(s.yaw), 0.05);
}

TEST(Follower, SpeedControlAndStop) {
  PathFollower f;
  f.setPath({{0, 0}, {100, 0}});
  EXPECT_GT(f.update(0.0, {0, 0, 0, 0.0}, 5.0).throttle, 0.5);
  const auto fast = f.update(0.05, {0, 0, 0, 7.0}, 5.0);
  EXPECT_EQ(fast.throttle, 0.0);
  EXPECT_GT(fast.brake, 0.0);
  PathFollower none;
  const auto c = none.update(0.0, {}, 5.0);  // no path yet: hold still
  EXPECT_EQ(c.brake, 1.0);
  EXPECT_EQ(c.target_speed, 0.0);
}

TEST(VotingPlanner, ReplansOnTheSimulatedClock) {
  VotingPlanner p;
  p.reset({80, 80, 11, 100, 5});
  Frame f;
  bool replanned = false;
  p.tick(0.0, {20, 20, 0, 0}, &replanned);
  EXPECT_FALSE(replanned);  // no frame yet
  p.addFrame(0.2, f.depth.data(), f.labels.data(), 64, 64, K64(), levelCamera(20, 20));
  std::vector<double> plan_times;
  for (int k = 0; k <= 120; ++k) {  // 6 s of 20 Hz ticks
    p.tick(k * 0.05, {20, 20, 0, 0}, &replanned);
    if (replanned) plan_times.push_back(k * 0.05);
  }
  ASSERT_EQ(plan_times.size(), 3u);
  EXPECT_NEAR(plan_times[0], 1.2, 1e-9);
  EXPECT_NEAR(plan_times[1], 3.2, 1e-9);
  EXPECT_NEAR(plan_times[2], 5.2, 1e-9);
  EXPECT_TRUE(p.path().found);
  p.reset({80, 80, 11, 100, 5});
  EXPECT_EQ(p.plans(), 0u);
  EXPECT_FALSE(p.path().found);
}
