// asg_sim_dataset: renders a segmentation dataset with the simulator's ground-truth labeler.
//   asg_sim_dataset --out DIR --count N [--seed S] [--meshes juniper,barberry]
//                   [--frames-per-scene 8] [--size 100] [--terrain P] [--weather P]
// Random scenes (deterministic from the seed), sun inclinations cycling through 0, 15, ..., 90
// degrees, 10..30 obstacles per scene, camera poses mostly facing an obstacle at 3..20 m. Writes DIR/images/NNNNNN_{rgb,
// labels,lit}.png and DIR/manifest.csv (one row per frame). The same arguments give the same
// files on the same build.
// Issue #27: --terrain P gives a share P of the scenes random terrain (rolling ground of
// amplitude 0.2..1.5 m at wavelength 20..60 m, and 0..3 hills or ditches of radius 6..15 m), the
// camera standing on it and tilted with it; --weather P a share P random weather (fog of 25..500 m
// visibility on half of them, cloud cover 0..1). Their draws come from a generator of their own,
// so with both at 0 (the default) the files are those of before.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <sstream>
#include <string>
#include <sys/stat.h>
#include <vector>

#include "asg_sim/meshes.hpp"
#include "asg_sim/renderer.hpp"
#include "asg_sim/scene.hpp"

using namespace asg_sim;

namespace {

struct Args {
  std::string out;
  int count = 0;
  uint64_t seed = 0;
  std::vector<std::string> meshes{"juniper", "barberry"};
  int frames_per_scene = 8;
  double size = 100.0;
  double terrain = 0.0;  ///< [-] share of scenes with terrain
  double weather = 0.0;  ///< [-] share of scenes with weather
};

[[noreturn]] void usage(const std::string& why) {
  std::fprintf(stderr,
               "error: %s\nusage: asg_sim_dataset --out DIR --count N [--seed S] "
               "[--meshes juniper,barberry] [--frames-per-scene 8] [--size 100] [--terrain P] [--weather P]\n",
               why.c_str());
  std::exit(2);
}

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (i + 1 >= argc) usage("missing value for " + k);
    const std::string v = argv[++i];
    try {
      if (k == "--out") a.out = v;
      else if (k == "--count") a.count = std::stoi(v);
      else if (k == "--seed") a.seed = std::stoull(v);
      else if (k == "--frames-per-scene") a.frames_per_scene = std::stoi(v);
      else if (k == "--size") a.size = std::stod(v);
      else if (k == "--terrain") a.terrain = std::stod(v);
      else if (k == "--weather") a.weather = std::stod(v);
      else if (k == "--meshes") {
        a.meshes.clear();
        std::stringstream ss(v);
        for (std::string m; std::getline(ss, m, ',');) {
          if (!findMesh(m)) usage("unknown mesh '" + m + "'");
          a.meshes.push_back(m);
        }
      } else usage("unknown option " + k);
    } catch (const std::logic_error&) {
      usage("bad value '" + v + "' for " + k);
    }
  }
  if (a.out.empty()) usage("--out is required");
  if (a.count <= 0) usage("--count must be > 0");
  if (a.frames_per_scene <= 0) usage("--frames-per-scene must be > 0");
  if (a.meshes.empty()) usage("--meshes must name at least one mesh");
  if (!(a.size >= 30.0)) usage("--size must be >= 30 m");
  if (!(a.terrain >= 0.0 && a.terrain <= 1.0)) usage("--terrain must be a share in [0, 1]");
  if (!(a.weather >= 0.0 && a.weather <= 1.0)) usage("--weather must be a share in [0, 1]");
  return a;
}

// Uniform in [lo, hi) from the raw generator: std distributions differ between libraries.
double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * (double(rng() >> 11) * (1.0 / 9007199254740992.0));
}

void writePng(const std::string& path, const cv::Mat& m) {
  if (!cv::imwrite(path, m)) throw std::runtime_error("cannot write " + path);
}

}  // namespace

int main(int argc, char** argv) {
  const Args a = parse(argc, argv);
  try {
    mkdir(a.out.c_str(), 0755);
    const std::string img_dir = a.out + "/images";
    mkdir(img_dir.c_str(), 0755);
    std::ofstream manifest(a.out + "/manifest.csv");
    if (!manifest) throw std::runtime_error("cannot write " + a.out + "/manifest.csv");
    manifest << "index,scene,rgb,labels,lit,sun_inclination_deg,sun_yaw_deg,meshes,obstacles,"
                "cam_x,cam_y,cam_yaw,terrain_amplitude_m,hills,fog_visibility_m,cloud_cover\n";
    std::mt19937_64 rng(a.seed);
    std::mt19937_64 env(a.seed ^ 0x7E44A1A5EA7Eull);  // terrain and weather draws only
    Renderer renderer;
    CameraFrame frame;
    int index = 0;
    for (int scene = 0; index < a.count; ++scene) {
      SceneSpec spec;
      spec.landscape.size = a.size;
      spec.landscape.border = 50.0;
      spec.textural.sun_inclination_deg = 15.0 * (scene % 7);
      spec.textural.sun_yaw_deg = uniform(rng, -180.0, 180.0);
      spec.textural.ground_texture_seed = uint32_t(rng() & 0xFFFF);
      const int n = 10 + int(uniform(rng, 0, 21));
      std::vector<std::pair<double, double>> spots;
      for (const auto& m : a.meshes) spec.layouts.push_back({m, {}});
      for (int k = 0; k < n; ++k) {
        auto& layout = spec.layouts[size_t(uniform(rng, 0, a.meshes.size()))];
        ObstacleInstance inst;
        inst.x = uniform(rng, 5, a.size - 5);
        inst.y = uniform(rng, 5, a.size - 5);
        inst.yaw = uniform(rng, -M_PI, M_PI);
        inst.scale = uniform(rng, 0.7, 1.3);
        layout.instances.push_back(inst);
      }
      if (a.terrain > 0.0 && uniform(env, 0, 1) < a.terrain) {
        auto& t = spec.terrain;
        t.wavelength_m = uniform(env, 20.0, 60.0);
        t.amplitude_m = std::min(uniform(env, 0.2, 1.5), 0.1 * t.wavelength_m);
        t.seed = uint32_t(env() & 0xFFFFFFFF);
        const int hills = int(uniform(env, 0, 4));
        for (int k = 0; k < hills; ++k) {
          Hill h;
          h.x = uniform(env, 0, a.size);
          h.y = uniform(env, 0, a.size);
          h.radius_m = uniform(env, 6.0, 15.0);
          h.height_m = uniform(env, -0.45, 0.45) * h.radius_m;
          t.hills.push_back(h);
        }
      }
      if (a.weather > 0.0 && uniform(env, 0, 1) < a.weather) {
        if (uniform(env, 0, 1) < 0.5) spec.textural.fog_visibility_m = uniform(env, 25.0, 500.0);
        spec.textural.cloud_cover = uniform(env, 0.0, 1.0);
      }
      const Terrain ground(spec.terrain);
      spec.operational.safety_radius = 0.0;
      std::vector<PlacedObstacle> placed;
      std::vector<RemovedObstacle> removed;
      placeObstacles(spec, &placed, &removed);
      renderer.setScene(spec, placed);
      for (int f = 0; f < a.frames_per_scene && index < a.count; ++f) {
        // Face an obstacle from 3..20 m (80 %), or anywhere.
        double x = 0, y = 0, yaw = 0;
        for (int attempt = 0; attempt < 50; ++attempt) {
          if (!placed.empty() && uniform(rng, 0, 1) < 0.8) {
            const auto& o = placed[size_t(uniform(rng, 0, placed.size()))];
            const double r = uniform(rng, 3.0, 20.0), th = uniform(rng, -M_PI, M_PI);
            x = o.pose.x + r * std::cos(th);
            y = o.pose.y + r * std::sin(th);
            yaw = std::atan2(o.pose.y - y, o.pose.x - x) + uniform(rng, -0.6, 0.6);
          } else {
            x = uniform(rng, 0, a.size);
            y = uniform(rng, 0, a.size);
            yaw = uniform(rng, -M_PI, M_PI);
          }
          bool clear = true;
          for (const auto& o : placed) clear = clear && std::hypot(o.pose.x - x, o.pose.y - y) > o.radius + 2.0;
          if (clear) break;
        }
        Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
        base.translation() << x, y, ground.height(x, y);
        base.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
        if (!ground.flat())  // the vehicle stands on the slope: tilted with the ground's normal
          base.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), ground.normal(x, y))
                              .toRotationMatrix() * base.linear();
        renderer.renderCamera(base * cameraMount(1.5, 0.0, 1.4), true, &frame);
        const int w = frame.rgb.width, h = frame.rgb.height;
        char name[32];
        std::snprintf(name, sizeof(name), "%06d", index);
        cv::Mat rgb(h, w, CV_8UC3, frame.rgb.data.data()), bgr;
        cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
        writePng(img_dir + "/" + name + "_rgb.png", bgr);
        writePng(img_dir + "/" + name + "_labels.png", cv::Mat(h, w, CV_8UC1, frame.labels.data.data()));
        writePng(img_dir + "/" + name + "_lit.png", cv::Mat(h, w, CV_8UC1, frame.lit.data.data()));
        std::string meshes;
        for (const auto& m : a.meshes) meshes += (meshes.empty() ? "" : "+") + m;
        manifest << index << "," << scene << ",images/" << name << "_rgb.png,images/" << name
                 << "_labels.png,images/" << name << "_lit.png," << spec.textural.sun_inclination_deg
                 << "," << spec.textural.sun_yaw_deg << "," << meshes << "," << placed.size() << ","
                 << x << "," << y << "," << yaw << "," << spec.terrain.amplitude_m << ","
                 << spec.terrain.hills.size() << "," << spec.textural.fog_visibility_m << ","
                 << spec.textural.cloud_cover << "\n";
        ++index;
        if (index % 25 == 0 || index == a.count) {
          const int bar = 30 * index / a.count;
          std::fprintf(stderr, "\r[%.*s%*s] %d/%d frames", bar, "##############################",
                       30 - bar, "", index, a.count);
        }
      }
    }
    std::fprintf(stderr, "\nwrote %d frames to %s\n", index, a.out.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "\nerror: %s\n", e.what());
    return 1;
  }
  return 0;
}
