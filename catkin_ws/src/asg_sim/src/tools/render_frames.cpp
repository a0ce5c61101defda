// asg_sim_render: renders a scenario's camera at the start pose (or a given pose) and a
// top-down view to PNG files, for docs and for looking at what the simulator shows.
//   asg_sim_render SCENARIO.yaml OUT_PREFIX [x y yaw]
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "asg_sim/renderer.hpp"
#include "asg_sim/scenario_runner.hpp"
#include "asg_sim/scene_yaml.hpp"

using namespace asg_sim;

int main(int argc, char** argv) {
  if (argc != 3 && argc != 6) {
    std::fprintf(stderr, "usage: %s SCENARIO.yaml OUT_PREFIX [x y yaw]\n", argv[0]);
    return 2;
  }
  try {
    ScenarioFile f = loadScenarioYaml(argv[1]);
    if (argc == 6) {
      f.spec.operational.start_x = std::atof(argv[3]);
      f.spec.operational.start_y = std::atof(argv[4]);
      f.spec.operational.start_yaw = std::atof(argv[5]);
    }
    const std::string out = argv[2];
    Renderer renderer;
    ScenarioRunner runner(&renderer);
    runner.reset(f.spec);
    CameraFrame frame;
    runner.renderCamera(true, &frame);
    const int w = frame.rgb.width, h = frame.rgb.height;
    cv::Mat rgb(h, w, CV_8UC3, frame.rgb.data.data()), bgr;
    cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
    cv::imwrite(out + "_rgb.png", bgr);
    cv::Mat depth(h, w, CV_8UC1), labels(h, w, CV_8UC3);
    // BGR per label: traversable, non-traversable, sky, void (ground under a canopy)
    const cv::Vec3b palette[4] = {{80, 160, 80}, {40, 40, 200}, {230, 200, 140}, {128, 128, 128}};
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u) {
        const float d = frame.depth.at(u, v);
        depth.at<uint8_t>(v, u) = std::isfinite(d) ? uint8_t(255.0 * std::min(1.0f, d / 40.0f)) : 255;
        labels.at<cv::Vec3b>(v, u) = palette[std::min<int>(frame.labels.at(u, v), 3)];
      }
    cv::Mat depth_color;
    cv::applyColorMap(depth, depth_color, cv::COLORMAP_VIRIDIS);
    cv::imwrite(out + "_depth.png", depth_color);
    cv::imwrite(out + "_labels.png", labels);
    RgbImage top;
    renderer.renderTopDown(768, &top);
    cv::Mat topm(top.height, top.width, CV_8UC3, top.data.data()), topb;
    cv::cvtColor(topm, topb, cv::COLOR_RGB2BGR);
    cv::imwrite(out + "_top.png", topb);
    std::printf("wrote %s_{rgb,depth,labels,top}.png\n", out.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
