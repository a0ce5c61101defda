#pragma once
/// @file vote_grid.hpp
/// The obstacle vote grid, stored in an OctoMap CountingOcTree whose resolution is the vote
/// spacing: grid vertex (i, j) at map position (i * spacing, j * spacing) is the leaf with key
/// (i + 2^15, j + 2^15, 2^15). A leaf's count is that vertex's votes, capped at max_votes.

#include <octomap/CountingOcTree.h>

#include <cstdint>
#include <utility>
#include <vector>

namespace asg_planner {

struct Vertex {
  int i = 0;  ///< x index: x = i * spacing [m]
  int j = 0;  ///< y index: y = j * spacing [m]
  bool operator==(const Vertex& o) const { return i == o.i && j == o.j; }
};

class VoteGrid {
 public:
  /// @param spacing [m] distance between vertices, > 0
  /// @param max_votes cap per vertex
  explicit VoteGrid(double spacing = 5.0, uint32_t max_votes = 50);

  /// Removes every vote (a new scenario).
  void clear();
  /// The vertex nearest to (x, y) [m, map].
  Vertex nearest(double x, double y) const;
  /// Adds n votes to v, capped at max_votes. Returns the votes v holds afterwards.
  /// Vertices beyond +-32767 cells are ignored (returns 0).
  uint32_t add(const Vertex& v, uint32_t n = 1);
  uint32_t votes(const Vertex& v) const;
  /// Every vertex with at least one vote.
  std::vector<std::pair<Vertex, uint32_t>> voted() const;
  /// Vertices with at least one vote, kept as votes are added (no tree walk).
  size_t votedCount() const { return voted_count_; }
  /// Sum of all votes, kept as votes are added (no tree walk).
  uint64_t totalVotes() const { return total_votes_; }
  double spacing() const { return spacing_; }
  uint32_t maxVotes() const { return max_votes_; }
  const octomap::CountingOcTree& tree() const { return tree_; }

 private:
  bool key(const Vertex& v, octomap::OcTreeKey* k) const;
  double spacing_;
  uint32_t max_votes_;
  octomap::CountingOcTree tree_;
  size_t voted_count_ = 0;
  uint64_t total_votes_ = 0;
};

}  // namespace asg_planner
