#include "asg_planner/astar.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

namespace asg_planner {
namespace {

// Votes as a dense array over the bounding box of the voted vertices, for quick neighbourhood
// sums (the octree is the store; this is a per-plan snapshot).
class VoteSnapshot {
 public:
  explicit VoteSnapshot(const VoteGrid& g) : spacing_(g.spacing()) {
    const auto v = g.voted();
    if (v.empty()) return;
    i0_ = j0_ = std::numeric_limits<int>::max();
    int i1 = std::numeric_limits<int>::min(), j1 = i1;
    for (const auto& [x, n] : v) {
      i0_ = std::min(i0_, x.i);
      j0_ = std::min(j0_, x.j);
      i1 = std::max(i1, x.i);
      j1 = std::max(j1, x.j);
    }
    ni_ = i1 - i0_ + 1;
    nj_ = j1 - j0_ + 1;
    data_.assign(size_t(ni_) * nj_, 0);
    for (const auto& [x, n] : v) data_[size_t(x.i - i0_) * nj_ + (x.j - j0_)] = n;
  }
  // sum_k votes_k exp(-d_k^2 / 2 sigma^2) over vertices within r of p
  double field(const Eigen::Vector2d& p, double sigma, double r) const {
    if (data_.empty()) return 0.0;
    const int ia = std::max(i0_, int(std::ceil((p.x() - r) / spacing_)));
    const int ib = std::min(i0_ + ni_ - 1, int(std::floor((p.x() + r) / spacing_)));
    const int ja = std::max(j0_, int(std::ceil((p.y() - r) / spacing_)));
    const int jb = std::min(j0_ + nj_ - 1, int(std::floor((p.y() + r) / spacing_)));
    double sum = 0.0;
    const double k = 1.0 / (2.0 * sigma * sigma);
    for (int i = ia; i <= ib; ++i) {
      for (int j = ja; j <= jb; ++j) {
        const uint32_t n = data_[size_t(i - i0_) * nj_ + (j - j0_)];
        if (!n) continue;
        const double dx = i * spacing_ - p.x(), dy = j * spacing_ - p.y();
        const double d2 = dx * dx + dy * dy;
        if (d2 <= r * r) sum += n * std::exp(-d2 * k);
      }
    }
    return sum;
  }

 private:
  double spacing_;
  int i0_ = 0, j0_ = 0, ni_ = 0, nj_ = 0;
  std::vector<uint32_t> data_;
};

}  // namespace

double edgeCost(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const VoteGrid& votes,
                const AStarParams& p) {
  const VoteSnapshot snap(votes);
  const double r = p.kernel_sigmas * p.sigma;
  double sum = snap.field((a + b) / 2, p.sigma, r);
  if (p.edge_points == 3) sum = (sum + snap.field(a, p.sigma, r) + snap.field(b, p.sigma, r)) / 3.0;
  return (b - a).norm() * (1.0 + p.alpha * sum);
}

PlannedPath planPath(const VoteGrid& votes, const AStarParams& p, double size,
                     const Eigen::Vector2d& start, const Eigen::Vector2d& goal) {
  PlannedPath out;
  const double s = p.vehicle_spacing;
  const int n = std::max(1, int(std::floor(size / s + 1e-9)));  // vertices 0..n per axis
  auto snap = [&](const Eigen::Vector2d& q) {
    return Eigen::Vector2i(std::clamp(int(std::lround(q.x() / s)), 0, n),
                           std::clamp(int(std::lround(q.y() / s)), 0, n));
  };
  const Eigen::Vector2i a = snap(start), b = snap(goal);
  const int side = n + 1;
  auto id = [&](int i, int j) { return size_t(i) * side + j; };
  auto pos = [&](int i, int j) { return Eigen::Vector2d(i * s, j * s); };
  const VoteSnapshot snapshot(votes);
  const double r = p.kernel_sigmas * p.sigma;
  // Midpoints and vertices sit on the half-grid: cache their field values, (2n+1)^2 of them.
  const int hs = 2 * n + 1;
  std::vector<double> mid(size_t(hs) * hs, -1.0);
  auto midField = [&](int i2, int j2) {
    double& f = mid[size_t(i2) * hs + j2];
    if (f < 0) f = snapshot.field(Eigen::Vector2d(i2 * s / 2, j2 * s / 2), p.sigma, r);
    return f;
  };
  std::vector<double> g(size_t(side) * side, std::numeric_limits<double>::infinity());
  std::vector<int64_t> parent(g.size(), -1);
  std::vector<char> closed(g.size(), 0);
  using Item = std::pair<double, size_t>;  // f, node
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  const Eigen::Vector2d goal_pos = pos(b.x(), b.y());
  g[id(a.x(), a.y())] = 0.0;
  open.push({(pos(a.x(), a.y()) - goal_pos).norm(), id(a.x(), a.y())});
  static const int di[8] = {1, -1, 0, 0, 1, 1, -1, -1}, dj[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  while (!open.empty()) {
    const size_t u = open.top().second;
    open.pop();
    if (closed[u]) continue;
    closed[u] = 1;
    ++out.expansions;
    const int ui = int(u / side), uj = int(u % side);
    if (ui == b.x() && uj == b.y()) break;
    for (int k = 0; k < 8; ++k) {
      const int vi = ui + di[k], vj = uj + dj[k];
      if (vi < 0 || vj < 0 || vi > n || vj > n) continue;
      const size_t v = id(vi, vj);
      if (closed[v]) continue;
      const double len = (k < 4 ? 1.0 : M_SQRT2) * s;
      double f = midField(ui + vi, uj + vj);
      if (p.edge_points == 3) f = (f + midField(2 * ui, 2 * uj) + midField(2 * vi, 2 * vj)) / 3.0;
      const double c = len * (1.0 + p.alpha * f);
      if (g[u] + c < g[v]) {
        g[v] = g[u] + c;
        parent[v] = int64_t(u);
        open.push({g[v] + (pos(vi, vj) - goal_pos).norm(), v});
      }
    }
  }
  const size_t goal_id = id(b.x(), b.y());
  if (!std::isfinite(g[goal_id])) return out;
  std::vector<Eigen::Vector2d> rev;
  for (int64_t v = int64_t(goal_id); v >= 0; v = parent[size_t(v)])
    rev.push_back(pos(int(size_t(v) / side), int(size_t(v) % side)));
  std::reverse(rev.begin(), rev.end());
  out.points.push_back(start);
  for (size_t i = 1; i + 1 < rev.size(); ++i) out.points.push_back(rev[i]);
  out.points.push_back(goal);
  out.cost = g[goal_id];
  out.found = true;
  return out;
}

}  // namespace asg_planner
