#include <gtest/gtest.h>

#include <cmath>

#include "asg_sim/renderer.hpp"
#include "asg_sim/scenario_runner.hpp"
#include "test_util.hpp"

using namespace asg_sim;

namespace {

Renderer& renderer() { return sharedRenderer(); }

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

namespace {
// The contrast left in rows [v0, v1): the standard deviation of brightness along each row (flat
// ground at one depth per row, so one fog transmittance per row), averaged over the rows.
double rowContrast(const CameraFrame& f, int v0, int v1) {
  double sum = 0;
  for (int v = v0; v < v1; ++v) {
    double s = 0, s2 = 0;
    const int n = f.rgb.width;
    for (int u = 0; u < n; ++u) {
      const double b = brightness(f, u, v);
      s += b;
      s2 += b * b;
    }
    sum += std::sqrt(std::max(0.0, s2 / n - (s / n) * (s / n)));
  }
  return sum / (v1 - v0);
}
}  // namespace

TEST(Renderer, FogFadesContrastWithDistanceAndHidesWhatLiesBeyond) {
  // Issue #27: fog of 40 m visibility. Near ground (rows near the bottom, 2-4 m ahead) keeps most
  // of its texture contrast, far ground (near the horizon, 30-80 m) loses most of it; the sky
  // turns fog-coloured; a tree 50 m away (beyond the visibility) is neither labelled nor counted.
  auto s = emptyScene();
  addObstacle(&s, "juniper", 85.0, 40.0);
  CameraFrame clear, fog;
  setScene(s);
  renderer().renderCamera(cameraAt(35, 50, 0), true, &clear);
  s.textural.fog_visibility_m = 40.0;
  setScene(s);
  renderer().renderCamera(cameraAt(35, 50, 0), true, &fog);
  const double near_clear = rowContrast(clear, 200, 256), near_fog = rowContrast(fog, 200, 256);
  const double far_clear = rowContrast(clear, 130, 136), far_fog = rowContrast(fog, 130, 136);
  EXPECT_GT(near_fog, 0.6 * near_clear);
  EXPECT_LT(far_fog, 0.35 * far_clear);
  EXPECT_LT(far_fog / far_clear, 0.6 * near_fog / near_clear);
  // The sky is the fog's colour (grey-white), not blue.
  EXPECT_LT(std::abs(int(fog.rgb.at(128, 5, 2)) - int(fog.rgb.at(128, 5, 0))), 20);
  EXPECT_GT(int(clear.rgb.at(128, 5, 2)) - int(clear.rgb.at(128, 5, 0)), 50);
  // The tree at 50 m: seen (labelled, counted) in clear air, not in the fog.
  int tree_clear = 0, tree_fog = 0;
  for (int v = 0; v < 256; ++v)
    for (int u = 0; u < 256; ++u) {
      tree_clear += clear.instances.at(u, v) == 1;
      tree_fog += fog.instances.at(u, v) == 1 || fog.labels.at(u, v) == kNonTraversable;
    }
  EXPECT_GT(tree_clear, 20);
  EXPECT_EQ(tree_fog, 0);
  // Depth is a range sensor's: fog leaves it alone.
  EXPECT_FLOAT_EQ(fog.depth.at(128, 200), clear.depth.at(128, 200));
}

TEST(Renderer, OvercastWeakensShadowsAndGreysTheSky) {
  // The tree's shadow on the ground (as in TreeShadowDarkensTheGround): under a clear sky the
  // shadowed ground is much darker than the lit ground beside it; overcast, much less so.
  auto s = emptyScene();
  addObstacle(&s, "juniper", 50.0, 50.0);
  const int v = int(std::lround(127.5 + 128.0 * 1.4 / 8.5)), u = 128;
  auto ratio = [&](double cover, CameraFrame* f) {
    s.textural.cloud_cover = cover;
    setScene(s);
    renderer().renderCamera(cameraAt(35, 50, 0), true, f);
    return double(brightness(*f, u, v)) / brightness(*f, 20, 250);
  };
  CameraFrame clear, overcast;
  const double r_clear = ratio(0.0, &clear), r_overcast = ratio(1.0, &overcast);
  EXPECT_LT(r_clear, 0.75);
  EXPECT_GT(r_overcast, 0.85);
  EXPECT_EQ(overcast.lit.at(u, v), clear.lit.at(u, v));  // the geometry of the shadow is the same
  EXPECT_LT(std::abs(int(overcast.rgb.at(128, 5, 2)) - int(overcast.rgb.at(128, 5, 0))), 20);
}

TEST(Renderer, WeatherLeavesNoTraceOnTheNextClearScene) {
  // A clear scene after a foggy, overcast one renders the same pixels as before it (the stored
  // reference runs check that clear weather renders as it did before the weather existed).
  auto s = emptyScene();
  addObstacle(&s, "juniper", 50.0, 50.0);
  CameraFrame a, b;
  setScene(s);
  renderer().renderCamera(cameraAt(35, 50, 0), true, &a);
  s.textural.fog_visibility_m = 30.0;
  s.textural.cloud_cover = 0.7;
  setScene(s);
  renderer().renderCamera(cameraAt(35, 50, 0), true, &b);
  s.textural.fog_visibility_m = 0.0;
  s.textural.cloud_cover = 0.0;
  setScene(s);
  renderer().renderCamera(cameraAt(35, 50, 0), true, &b);
  EXPECT_EQ(a.rgb.data, b.rgb.data);
  EXPECT_EQ(a.labels.data, b.labels.data);
}

TEST(Renderer, AHillRaisesTheHorizonAndItsSunnySideIsBrighter) {
  // Issue #27: a hill ahead hides sky that the flat ground leaves open, and is nearer than the
  // flat ground in the rows it covers; its flank facing the sun is brighter than the flank
  // facing away. The labels call it ground, not obstacle.
  auto s = emptyScene();
  s.textural.sun_yaw_deg = 90.0;  // light from +y: the hill's north flank is sunny
  s.textural.sun_inclination_deg = 35.0;
  CameraFrame flat, hilly;
  setScene(s);
  renderer().renderCamera(cameraAt(30, 50, 0), true, &flat);
  s.terrain.hills = {{60.0, 50.0, 16.0, 7.0}};
  setScene(s);
  renderer().renderCamera(cameraAt(30, 50, 0), true, &hilly);
  auto sky = [](const CameraFrame& f) {
    int n = 0;
    for (int v = 0; v < f.labels.height; ++v)
      for (int u = 0; u < f.labels.width; ++u) n += f.labels.at(u, v) == kSky;
    return n;
  };
  auto top = [](const CameraFrame& f, int u) {  // first row from the top that is not sky
    int v = 0;
    while (v < f.labels.height && f.labels.at(u, v) == kSky) ++v;
    return v;
  };
  EXPECT_LT(top(hilly, 128), top(flat, 128) - 20);  // about 28 px: the hill's 7 m at 30 m
  EXPECT_EQ(top(hilly, 0), top(flat, 0));            // beside it, the same horizon
  EXPECT_LT(sky(hilly), sky(flat) - 1000);
  // Straight ahead, just below the flat horizon: far ground (or sky) when flat, the hill near.
  EXPECT_LT(hilly.depth.at(128, 126), 0.5 * (std::isnan(flat.depth.at(128, 126)) ? 1e9 : flat.depth.at(128, 126)));
  EXPECT_EQ(hilly.labels.at(128, 126), kTraversable);
  // The flanks: left of the image is +y (north, sunny), right is -y.
  long north = 0, south = 0;
  for (int v = 100; v < 127; ++v) {
    north += brightness(hilly, 100, v);
    south += brightness(hilly, 156, v);
  }
  EXPECT_GT(north, south * 1.1);
  // Back to flat: the same pixels as before the hill.
  s.terrain = TerrainSpec();
  setScene(s);
  CameraFrame again;
  renderer().renderCamera(cameraAt(30, 50, 0), true, &again);
  EXPECT_EQ(again.rgb.data, flat.rgb.data);
}

TEST(Renderer, AHillShadowsTheGroundBehindItUnderALowSun) {
  // Issue #27: under a low sun from +x, a 5 m hill at x = 60 shades the flat ground west of it
  // (shadow about 28 m long); the same ground is lit without the hill. The lit mask and the
  // colour both show it.
  auto s = emptyScene();
  s.textural.sun_yaw_deg = 0.0;
  s.textural.sun_inclination_deg = 10.0;
  const int v = int(std::lround(127.5 + 128.0 * 1.4 / 8.5)), u = 128;  // ground 8.5 m ahead: x = 40
  CameraFrame flat, hilly;
  setScene(s);
  renderer().renderCamera(cameraAt(30, 50, 0), true, &flat);
  s.terrain.hills = {{60.0, 50.0, 12.0, 5.0}};
  setScene(s);
  renderer().renderCamera(cameraAt(30, 50, 0), true, &hilly);
  EXPECT_GT(flat.lit.at(u, v), 200);
  EXPECT_LT(hilly.lit.at(u, v), 60);
  EXPECT_LT(brightness(hilly, u, v), 0.8 * brightness(flat, u, v));
  EXPECT_EQ(hilly.labels.at(u, v), kTraversable);
}

TEST(Renderer, BackProjectedGroundLiesOnTheGroundPlane) {
  setScene(emptyScene());
  CameraFrame f;
  renderer().renderCamera(cameraAt(30, 50, 0.3), false, &f);
  const CameraModel& c = renderer().camera();
  const auto pts = backProject(f.depth, c, 4);
  size_t returns = 0;
  for (int v = 0; v < f.depth.height; v += 4)
    for (int u = 0; u < f.depth.width; u += 4) returns += std::isfinite(f.depth.at(u, v)) ? 1 : 0;
  ASSERT_EQ(pts.size(), returns);  // sky pixels left out, nothing else
  ASSERT_GT(pts.size(), 1000u);
  for (const auto& p : pts) {
    // Optical y points down: the ground is 1.4 m below the camera wherever it is seen.
    EXPECT_NEAR(p.y(), 1.4, 0.01 + 0.005 * p.z()) << p.transpose();
    EXPECT_GT(p.z(), 0.0f);
  }
  EXPECT_THROW(backProject(f.depth, c, 0), std::invalid_argument);
}
