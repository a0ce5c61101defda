// The tools' planner options go through the planner's table: files in order, then KEY=VALUE; a key
// outside the table, a value outside its range or not a number is refused by name.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>

#include "asg_planner_harness/planner_options.hpp"

using asg_planner::PlannerParams;
using namespace asg_planner_harness;

namespace {

std::string writeYaml(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(PlannerOptions, FilesThenSetsInOrder) {
  const auto base = writeYaml("base.yaml", "vote_spacing: 5.0\nastar:\n  sigma: 2.5\n  edge_points: 3\n");
  const auto fine = writeYaml("fine.yaml", "vote_spacing: 1.0\nastar:\n  vehicle_spacing: 2.0\n  edge_points: 1\n"
                                           "publish_markers: false\n");
  std::string a0 = "tool", a1 = "--planner", a2 = base, a3 = "--planner", a4 = fine, a5 = "--set",
              a6 = "astar/sigma=1.5", a7 = "scene.yaml", a8 = "--set", a9 = "follower/first_crossing=true";
  char* argv[] = {&a0[0], &a1[0], &a2[0], &a3[0], &a4[0], &a5[0], &a6[0], &a7[0], &a8[0], &a9[0]};
  PlannerParams p;
  const auto rest = takePlannerOptions(10, argv, &p);
  ASSERT_EQ(rest.size(), 1u);
  EXPECT_EQ(rest[0], "scene.yaml");
  EXPECT_DOUBLE_EQ(p.vote_spacing, 1.0);  // the overlay after the base
  EXPECT_DOUBLE_EQ(p.astar.vehicle_spacing, 2.0);
  EXPECT_DOUBLE_EQ(p.astar.sigma, 1.5);  // --set after both files
  EXPECT_EQ(p.astar.edge_points, 1);
  EXPECT_TRUE(p.follower.first_crossing);
}

TEST(PlannerOptions, BadKeysValuesAndFilesAreNamed) {
  PlannerParams p;
  EXPECT_NE(errorOf([&] { setPlannerValue(&p, "astar/sigmaa=1"); }).find("astar/sigmaa"), std::string::npos);
  EXPECT_NE(errorOf([&] { setPlannerValue(&p, "vote_spacing=0"); }).find("vote_spacing"), std::string::npos);
  EXPECT_NE(errorOf([&] { setPlannerValue(&p, "vote_spacing=5m"); }).find("not a number"), std::string::npos);
  EXPECT_NE(errorOf([&] { setPlannerValue(&p, "vote_spacing"); }).find("KEY=VALUE"), std::string::npos);
  EXPECT_NE(errorOf([&] { loadPlannerYaml(&p, "/no/such/planner.yaml"); }).find("/no/such/planner.yaml"),
            std::string::npos);
  const auto bad = writeYaml("bad.yaml", "astar:\n  edge_points: 2\n");
  const std::string e = errorOf([&] { loadPlannerYaml(&p, bad); });
  EXPECT_NE(e.find(bad), std::string::npos) << e;
  EXPECT_NE(e.find("edge_points"), std::string::npos) << e;
  EXPECT_DOUBLE_EQ(p.vote_spacing, PlannerParams().vote_spacing);  // nothing applied by the refusals
}
