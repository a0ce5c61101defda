// The scene worker's parameter table (src/ros/worker_parameters.hpp): ROS-free, so tested here
// without a master. Every row checks its kind and range and names the parameter when it refuses.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>

#include "../src/ros/worker_parameters.hpp"

using asg_sim::WorkerParameterSpec;
using asg_sim::WorkerParams;
using asg_sim::WorkerValue;

namespace {

const WorkerParameterSpec& row(const std::string& name) {
  for (const auto& s : asg_sim::workerParameters().rows)
    if (name == s.name) return s;
  throw std::runtime_error("no row " + name);
}

WorkerValue number(double v) {
  WorkerValue w;
  w.number = v;
  return w;
}

WorkerValue text(const std::string& t) {
  WorkerValue w;
  w.text = t;
  return w;
}

}  // namespace

TEST(WorkerParameters, EveryRowRoundTripsItsDefaultAndNamesAreUnique) {
  WorkerParams p;
  const WorkerParams defaults;
  std::set<std::string> names;
  for (const auto& s : asg_sim::workerParameters().rows) {
    EXPECT_TRUE(names.insert(s.name).second) << s.name;
    EXPECT_STRNE(s.unit, "") << s.name;
    EXPECT_STRNE(s.description, "") << s.name;
    if (s.kind == asg_lockstep::params::Kind::kList) continue;  // required: no default to check
    EXPECT_EQ(asg_sim::setWorkerParameter(&p, s, s.get(&defaults), std::string("~") + s.name), "") << s.name;
  }
}

TEST(WorkerParameters, OutOfRangeValuesAreRefusedByName) {
  WorkerParams p;
  EXPECT_EQ(asg_sim::setWorkerParameter(&p, row("camera/width"), number(8), "~camera/width"),
            "~camera/width = 8: must be in 16..4096 [px]");
  EXPECT_EQ(p.width, 256);  // unchanged
  EXPECT_EQ(asg_sim::setWorkerParameter(&p, row("camera/width"), number(320.5), "~camera/width"),
            "~camera/width = 320: must be a whole number");
  // open ranges exclude their ends
  EXPECT_NE(asg_sim::setWorkerParameter(&p, row("ack_timeout"), number(0), "~ack_timeout"), "");
  EXPECT_NE(asg_sim::setWorkerParameter(&p, row("camera/fov_deg"), number(179), "~camera/fov_deg"), "");
  EXPECT_EQ(asg_sim::setWorkerParameter(&p, row("camera/fov_deg"), number(120), "~camera/fov_deg"), "");
  EXPECT_DOUBLE_EQ(p.fov_deg, 120);
  EXPECT_NE(asg_sim::setWorkerParameter(&p, row("realtime_factor"), number(std::nan("")), "x").find("finite"),
            std::string::npos);
  const std::string why =
      asg_sim::setWorkerParameter(&p, row("points_stride"), number(65), "stack/worker/points_stride");
  EXPECT_EQ(why.rfind("stack/worker/points_stride = 65", 0), 0u) << why;
}

TEST(WorkerParameters, TextsAreCheckedAgainstTheirChoicesAndNodesAcross) {
  WorkerParams p;
  EXPECT_EQ(asg_sim::setWorkerParameter(&p, row("command_interface"), text("joystick"), "~command_interface"),
            "~command_interface = joystick: must be one of vehicle_command, twist");
  EXPECT_EQ(asg_sim::setWorkerParameter(&p, row("command_interface"), text("twist"), "~command_interface"), "");
  EXPECT_EQ(p.command_interface, "twist");
  p.stack_nodes = {"planner", "segmenter"};
  p.labels_node = "segmenter";
  EXPECT_EQ(asg_sim::checkWorkerParameters(p), "");
  p.labels_node = "labeller";
  EXPECT_NE(asg_sim::checkWorkerParameters(p).find("~labels_node = labeller"), std::string::npos);
}

TEST(WorkerParameters, TheMarkdownHasARowPerParameterAndSaysWhatARegistrationMaySet) {
  const std::string md = asg_sim::workerParameterTableMarkdown();
  for (const auto& s : asg_sim::workerParameters().rows)
    EXPECT_NE(md.find(std::string("| `") + s.name + "` |"), std::string::npos) << s.name;
  EXPECT_NE(md.find("| `points_stride` | px | 2 | 1..64 | yes |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `render_threads` | - | 1 | 1..64 | - |"), std::string::npos) << md;
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
