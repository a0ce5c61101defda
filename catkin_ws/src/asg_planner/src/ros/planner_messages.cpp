#include "planner_messages.hpp"

#include <cmath>
#include <memory>

namespace asg_planner {

Eigen::Isometry3d toIso(const geometry_msgs::Pose& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z)
                   .normalized()
                   .toRotationMatrix();
  T.translation() << p.position.x, p.position.y, p.position.z;
  return T;
}

ImageIn toImage(const sensor_msgs::ImageConstPtr& m) {
  ImageIn i;
  i.encoding = m->encoding;
  i.width = m->width;
  i.height = m->height;
  i.step = m->step;
  i.data = m->data.data();
  i.size = m->data.size();
  i.keep = std::shared_ptr<const void>(m.get(), [m](const void*) {});  // holds the message
  return i;
}

OdomIn toOdom(const geometry_msgs::Pose& pose, double forward_speed) {
  OdomIn o;
  o.pose = toIso(pose);
  o.state.x = pose.position.x;
  o.state.y = pose.position.y;
  const auto& q = pose.orientation;
  o.state.yaw = std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
  o.state.speed = forward_speed;
  return o;
}

geometry_msgs::Point point(double x, double y, double z) {
  geometry_msgs::Point p;
  p.x = x;
  p.y = y;
  p.z = z;
  return p;
}

asg_msgs::PlannerState stateMessage(const VotingPlanner& planner, const ControlCommand& c, bool replanned) {
  asg_msgs::PlannerState st;
  st.header.frame_id = "map";
  st.frames = planner.frames();
  st.plan_count = planner.plans();
  st.replanned = replanned;
  st.path_cost = planner.path().cost;
  st.expansions = planner.path().expansions;
  // O(1) counters: the control tick must not walk the octree (it runs 10 x per replan).
  st.voted_vertices = planner.votes().votedCount();
  st.total_votes = planner.votes().totalVotes();
  if (replanned)
    for (const auto& p : planner.path().points) st.path.push_back(point(p.x(), p.y()));
  const auto& la = planner.follower().lookaheadPoint();
  st.lookahead = point(la.x(), la.y(), planner.ground().heightOr(la.x(), la.y(), 0.0));
  st.heading_error = planner.follower().headingError();
  st.throttle = c.throttle;
  st.steering = c.steering;
  st.brake = c.brake;
  st.target_speed = c.target_speed;
  return st;
}

nav_msgs::Path pathMessage(const VotingPlanner& planner, const ros::Time& stamp) {
  const GroundMap& ground = planner.ground();
  nav_msgs::Path path;
  path.header.stamp = stamp;
  path.header.frame_id = "map";
  for (const auto& p : planner.path().points) {
    geometry_msgs::PoseStamped ps;
    ps.header = path.header;
    ps.pose.position = point(p.x(), p.y(), ground.heightOr(p.x(), p.y(), 0.0) + 0.1);
    ps.pose.orientation.w = 1.0;
    path.poses.push_back(ps);
  }
  return path;
}

visualization_msgs::MarkerArray voteMarkers(const VotingPlanner& planner, const ros::Time& stamp) {
  const GroundMap& ground = planner.ground();
  visualization_msgs::Marker m;
  m.header.stamp = stamp;
  m.header.frame_id = "map";
  m.ns = "votes";
  m.id = 0;
  m.type = visualization_msgs::Marker::CUBE_LIST;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1.0;
  const double s = planner.params().vote_spacing;
  m.scale.x = m.scale.y = 0.6 * s;
  m.scale.z = 0.1;
  for (const auto& [v, n] : planner.votes().voted()) {
    m.points.push_back(point(v.i * s, v.j * s, ground.heightOr(v.i * s, v.j * s, 0.0) + 0.05));
    std_msgs::ColorRGBA c;
    const float k = float(n) / float(planner.params().max_votes);  // intensity by votes
    c.r = 1.0f;
    c.g = 1.0f - k;
    c.b = 0.0f;
    c.a = 0.3f + 0.7f * k;
    m.colors.push_back(c);
  }
  if (m.points.empty()) m.action = visualization_msgs::Marker::DELETE;
  visualization_msgs::MarkerArray arr;
  arr.markers.push_back(m);
  return arr;
}

visualization_msgs::Marker vehicleGridMarker(double spacing, double landscape_size) {
  visualization_msgs::Marker grid;
  grid.header.frame_id = "map";
  grid.ns = "vehicle_grid";
  grid.type = visualization_msgs::Marker::POINTS;
  grid.scale.x = grid.scale.y = 0.3;
  grid.color.r = grid.color.g = grid.color.b = 0.8f;
  grid.color.a = 0.6f;
  grid.pose.orientation.w = 1.0;
  const int n = int(std::floor(landscape_size / spacing + 1e-9));
  if (n <= 400)
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j) grid.points.push_back(point(i * spacing, j * spacing));
  return grid;
}

}  // namespace asg_planner
