#pragma once
/// @file astar.hpp
/// A* over an 8-connected vehicle grid on [0, size]^2 with a Euclidean heuristic. An edge from
/// a to b costs |ab| (1 + alpha F), F = sum_k votes_k exp(-d_k^2 / (2 sigma^2)) with d_k the
/// distance to vote vertex k (vertices beyond kernel_sigmas sigma are left out), F evaluated at
/// the edge midpoint (edge_points = 1) or averaged over both ends and the midpoint
/// (edge_points = 3, the reference's version with sigma 2.5 m).

#include <Eigen/Core>
#include <vector>

#include "asg_planner/vote_grid.hpp"

namespace asg_planner {

struct AStarParams {
  double vehicle_spacing = 5.0;  ///< [m] vehicle grid spacing
  double alpha = 1.0 / 50.0;     ///< [-] cost weight of one vote
  double sigma = 2.5;            ///< [m] vote influence radius
  double kernel_sigmas = 4.0;    ///< [-] votes further than this many sigma are ignored
  int edge_points = 3;           ///< [-] 1: kernel at the edge midpoint; 3: mean of ends and midpoint
};

struct PlannedPath {
  std::vector<Eigen::Vector2d> points;  ///< [m] start, grid vertices, goal
  double cost = 0.0;                    ///< [m-equivalent] sum of edge costs
  size_t expansions = 0;                ///< nodes expanded
  bool found = false;
};

/// Cost of the straight edge a -> b given the votes (the formula above, exactly).
double edgeCost(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const VoteGrid& votes,
                const AStarParams& params);

/// Plans from start to goal (both snapped to the nearest vehicle-grid vertex inside [0, size]^2;
/// the returned polyline begins at start and ends at goal exactly).
PlannedPath planPath(const VoteGrid& votes, const AStarParams& params, double size,
                     const Eigen::Vector2d& start, const Eigen::Vector2d& goal);

}  // namespace asg_planner
