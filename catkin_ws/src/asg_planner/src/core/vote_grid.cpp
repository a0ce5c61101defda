#include "asg_planner/vote_grid.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace asg_planner {

namespace {
constexpr int kOffset = 1 << 15;  // OcTreeKey centre (tree depth 16)
}

VoteGrid::VoteGrid(double spacing, uint32_t max_votes)
    : spacing_(spacing), max_votes_(max_votes), tree_(spacing) {
  if (!(spacing > 0)) throw std::invalid_argument("vote grid spacing must be > 0 m");
}

void VoteGrid::clear() {
  tree_.clear();
  voted_count_ = 0;
  total_votes_ = 0;
}

Vertex VoteGrid::nearest(double x, double y) const {
  return {int(std::lround(x / spacing_)), int(std::lround(y / spacing_))};
}

bool VoteGrid::key(const Vertex& v, octomap::OcTreeKey* k) const {
  if (std::abs(v.i) >= kOffset || std::abs(v.j) >= kOffset) return false;
  *k = octomap::OcTreeKey(v.i + kOffset, v.j + kOffset, kOffset);
  return true;
}

uint32_t VoteGrid::add(const Vertex& v, uint32_t n) {
  octomap::OcTreeKey k;
  if (n == 0 || !key(v, &k)) return votes(v);
  octomap::CountingOcTreeNode* node = tree_.search(k);
  const uint32_t before = node ? node->getCount() : 0;
  if (before >= max_votes_) return before;
  if (!node) node = tree_.updateNode(k);  // creates the leaf (count 1)
  const uint32_t after = std::min<uint64_t>(uint64_t(before) + n, max_votes_);
  node->setCount(after);
  if (before == 0) ++voted_count_;
  total_votes_ += after - before;
  return after;
}

uint32_t VoteGrid::votes(const Vertex& v) const {
  octomap::OcTreeKey k;
  if (!key(v, &k)) return 0;
  const octomap::CountingOcTreeNode* node = tree_.search(k);
  return node ? node->getCount() : 0;
}

std::vector<std::pair<Vertex, uint32_t>> VoteGrid::voted() const {
  std::vector<std::pair<Vertex, uint32_t>> out;
  for (auto it = tree_.begin_leafs(), end = tree_.end_leafs(); it != end; ++it) {
    if (it->getCount() == 0) continue;
    const octomap::OcTreeKey k = it.getKey();
    out.push_back({{int(k[0]) - kOffset, int(k[1]) - kOffset}, it->getCount()});
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return a.first.i != b.first.i ? a.first.i < b.first.i : a.first.j < b.first.j;
  });
  return out;
}

}  // namespace asg_planner
