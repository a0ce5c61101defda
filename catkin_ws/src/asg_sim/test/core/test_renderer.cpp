#include <gtest/gtest.h>

#include <cmath>

#include "asg_sim/renderer.hpp"
#include "asg_sim/scenario_runner.hpp"
#include "test_util.hpp"

using namespace asg_sim;

namespace {

Renderer& renderer() {
  static Renderer r;  // one OSMesa context for the whole test binary
  return r;
}

// Camera at (x, y) on the ground plane, heading yaw, mounted as on the vehicle.
Eigen::Isometry3d cameraAt(double x, double y, double yaw) {
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.translation() << x, y, 0.0;
  base.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return base * cameraMount(1.5, 0.0, 1.4);
}

void setScene(const SceneSpec& s) {
  std::vector<PlacedObstacle> placed;
  std::vector<RemovedObstacle> removed;
  placeObstacles(s, &placed, &removed);
  renderer().setScene(s, placed);
}

int brightness(const CameraFrame& f, int u, int v) {
  return f.rgb.at(u, v, 0) + f.rgb.at(u, v, 1) + f.rgb.at(u, v, 2);
}

}  // namespace

TEST(Renderer, IntrinsicsFollowCameraInfoConvention) {
  const CameraModel& c = renderer().camera();
  EXPECT_DOUBLE_EQ(c.fx(), 128.0);  // 256 px, 90 degrees
  EXPECT_DOUBLE_EQ(c.cx(), 127.5);
}

TEST(Renderer, DepthOfGroundPlaneMatchesPinholeModel) {
  setScene(emptyScene());
  CameraFrame f;
  renderer().renderCamera(cameraAt(30, 50, 0.3), false, &f);
  const CameraModel& c = renderer().camera();
  for (int v : {140, 160, 200, 255}) {
    for (int u : {0, 60, 128, 250}) {
      // Ground is 1.4 m below the optical centre (+y optical), so depth = h * fy / (v - cy).
      const double expected = 1.4 * c.fy() / (v - c.cy());
      EXPECT_NEAR(f.depth.at(u, v), expected, 0.005 * expected + 1e-3) << "u=" << u << " v=" << v;
    }
  }
  EXPECT_TRUE(std::isnan(f.depth.at(128, 20)));  // sky: no depth
}

TEST(Renderer, TreeShadowDarkensTheGround) {
  // Sun from +x at 30 degrees: the tree at x = 50 throws its shadow towards -x, onto the ground
  // between the camera (x = 35) and the tree. Same scene, shadow on and off.
  auto s = emptyScene();
  addObstacle(&s, "juniper", 50.0, 50.0);
  CameraFrame lit, shaded;
  // Ground point (45, 50): planar depth 45 - 35 - 1.5 = 8.5 m, v = cy + fy * 1.4 / 8.5.
  const int v = int(std::lround(127.5 + 128.0 * 1.4 / 8.5)), u = 128;
  s.layouts[0].instances[0].cast_shadow = false;
  setScene(s);
  renderer().renderCamera(cameraAt(35, 50, 0), true, &lit);
  s.layouts[0].instances[0].cast_shadow = true;
  setScene(s);
  renderer().renderCamera(cameraAt(35, 50, 0), true, &shaded);
  ASSERT_EQ(shaded.labels.at(u, v), kTraversable);  // it is ground, not the tree
  EXPECT_LT(shaded.lit.at(u, v), 30);                // and the shadow mask says so
  EXPECT_GT(lit.lit.at(u, v), 225);
  EXPECT_LT(brightness(shaded, u, v), 0.75 * brightness(lit, u, v));
  // Ground beside the shadow stays lit.
  EXPECT_NEAR(brightness(shaded, 20, 250), brightness(lit, 20, 250), 3);
}

TEST(Renderer, LabelsMarkObstacleGroundAndSky) {
  auto s = emptyScene();
  addObstacle(&s, "juniper", 50.0, 50.0);
  setScene(s);
  CameraFrame f;
  renderer().renderCamera(cameraAt(35, 50, 0), true, &f);
  EXPECT_EQ(f.labels.at(128, 127), kNonTraversable);  // the tree, straight ahead
  EXPECT_EQ(f.instances.at(128, 127), 1);
  EXPECT_NEAR(f.depth.at(128, 127), 50.0 - 35.0 - 1.5 - 1.2, 0.6);  // its front surface
  EXPECT_EQ(f.labels.at(128, 240), kTraversable);
  EXPECT_EQ(f.instances.at(128, 240), 0);
  EXPECT_EQ(f.labels.at(128, 5), kSky);
  EXPECT_EQ(f.labels.at(5, 127), kSky);  // beside the tree at the horizon row: sky or ground
}

TEST(Renderer, GroundUnderACanopyIsVoid) {
  // Camera at x = 35 (optical centre 36.5, 1.4 m up) facing the juniper at x = 50, whose foliage
  // skirt (0.5 m up) reaches about 1.3 m from its axis: the ground seen beneath the skirt is
  // labelled kUnderCanopy (void), the open ground in front of the canopy traversable; both are
  // ground in the depth image and carry no instance id.
  auto s = emptyScene();
  addObstacle(&s, "juniper", 50.0, 50.0);
  setScene(s);
  CameraFrame f;
  renderer().renderCamera(cameraAt(35, 50, 0), true, &f);
  const auto groundDepth = [](int v) { return 1.4 * 128.0 / (v - 127.5); };
  const int under = 142;  // ground at x = 48.86, 1.14 m from the axis
  ASSERT_NEAR(f.depth.at(128, under), groundDepth(under), 0.05);
  EXPECT_EQ(f.labels.at(128, under), kUnderCanopy);
  EXPECT_EQ(f.instances.at(128, under), 0);
  const int open = 145;  // ground at x = 46.74, 3.3 m from the axis
  ASSERT_NEAR(f.depth.at(128, open), groundDepth(open), 0.05);
  EXPECT_EQ(f.labels.at(128, open), kTraversable);
}

TEST(Renderer, TopDownShowsObstacleWhereItIs) {
  auto s = emptyScene();
  addObstacle(&s, "juniper", 25.0, 75.0);
  setScene(s);
  RgbImage top;
  renderer().renderTopDown(200, &top);
  // 2 px per metre; (25, 75) -> column 50, row 50 (y up in the picture). Foliage is dark green.
  const int g = top.at(50, 50, 1), r = top.at(50, 50, 0);
  EXPECT_GT(g, r);
  EXPECT_LT(top.at(50, 50, 0) + top.at(50, 50, 1) + top.at(50, 50, 2),
            top.at(150, 150, 0) + top.at(150, 150, 1) + top.at(150, 150, 2));
}

TEST(Renderer, SameSceneSamePixels) {
  auto s = emptyScene();
  addObstacle(&s, "juniper", 50.0, 50.0);
  addObstacle(&s, "barberry", 45.0, 47.0);
  setScene(s);
  CameraFrame a, b;
  renderer().renderCamera(cameraAt(35, 50, 0.1), true, &a);
  setScene(s);
  renderer().renderCamera(cameraAt(35, 50, 0.1), true, &b);
  EXPECT_EQ(a.rgb.data, b.rgb.data);
  EXPECT_EQ(a.labels.data, b.labels.data);
  EXPECT_EQ(0, std::memcmp(a.depth.data.data(), b.depth.data.data(), a.depth.data.size() * 4));
}

TEST(Runner, VisibilityCountsSeenObstacles) {
  auto s = emptyScene();
  addObstacle(&s, "juniper", 45.0, 50.0);  // ahead: seen
  addObstacle(&s, "juniper", 5.0, 50.0);   // behind: never seen
  addObstacle(&s, "juniper", 22.0, 51.0);  // inside the start safety radius: removed
  ScenarioRunner runner(&renderer());
  runner.reset(s);
  CameraFrame f;
  runner.renderCamera(true, &f);
  const auto vis = runner.obstacleVisibility();
  ASSERT_EQ(vis.size(), 3u);
  EXPECT_FLOAT_EQ(vis[0], 1.0f);
  EXPECT_FLOAT_EQ(vis[1], 0.0f);
  EXPECT_FLOAT_EQ(vis[2], -1.0f);
  ASSERT_EQ(runner.removed().size(), 1u);
}
