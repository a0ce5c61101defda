// asg_sim_dataset: renders a segmentation dataset with the simulator's ground-truth labeler.
//   asg_sim_dataset --out DIR --count N [--seed S] [--meshes NAME,NAME (default: every class of the
//                   catalogue, in its order: juniper,barberry)]
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
// Issue #40: --poses FILE.csv renders given scenes at given poses instead of random ones: frames
// for hardening a model on found failure scenes (asg_agent.campaign.hardening writes the file).
// FILE.csv has the header scenario,x,y,yaw: a scenario YAML (relative to FILE.csv's folder) and
// the vehicle's pose on its ground ([m], [m], [rad]); perturbed scenes are scenario files of their
// own. The manifest gets a last column, source: the scenario file of each frame.
// Issue #57: --instances 1 (with --poses) writes NNNNNN_instances.png too, 16-bit: 1 + the index of
// the obstacle seen at each pixel in the scenario's flat obstacle list (layouts in order, their
// instances in order; the index of an export's `collision_with`), 0 where none is.
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
#include "asg_sim/scene_schema.hpp"
#include "asg_sim/scene_yaml.hpp"

using namespace asg_sim;

namespace {

/// Every class of the catalogue, in catalogue.py's order (the scenes' draws follow the order).
std::vector<std::string> catalogueNames() {
  std::vector<std::string> names;
  for (const auto& e : schema::kCatalogue) names.push_back(e.name);
  return names;
}

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ",") + n;
  return s;
}

struct Args {
  std::string out;
  int count = 0;
  uint64_t seed = 0;
  std::vector<std::string> meshes = catalogueNames();  ///< the classes scenes draw from
  int frames_per_scene = 8;
  double size = 100.0;
  double terrain = 0.0;  ///< [-] share of scenes with terrain
  double weather = 0.0;  ///< [-] share of scenes with weather
  std::string poses;     ///< CSV of scenario poses (issue #40); empty: random scenes
  bool instances = false;  ///< with --poses: write each frame's obstacle index image (issue #57)
};

/// One row of a --poses file.
struct PoseRow {
  std::string scenario;  ///< path of the scenario YAML, resolved against the poses file's folder
  double x = 0, y = 0, yaw = 0;  ///< [m], [m], [rad]
};

[[noreturn]] void usage(const std::string& why) {
  std::fprintf(stderr,
               "error: %s\nusage: asg_sim_dataset --out DIR --count N [--seed S] "
               "[--meshes %s] [--frames-per-scene 8] [--size 100] [--terrain P] [--weather P]\n"
               "       asg_sim_dataset --out DIR --poses FILE.csv [--instances 1]\n",
               why.c_str(), joined(catalogueNames()).c_str());
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
      else if (k == "--poses") a.poses = v;
      else if (k == "--instances") a.instances = std::stoi(v) != 0;
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
  if (a.instances && a.poses.empty()) usage("--instances needs --poses");
  if (!a.poses.empty()) return a;  // the rows give everything else
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

const char* kManifestHeader =
    "index,scene,rgb,labels,lit,sun_inclination_deg,sun_yaw_deg,meshes,obstacles,"
    "cam_x,cam_y,cam_yaw,terrain_amplitude_m,hills,fog_visibility_m,cloud_cover";

/// Renders the camera of a vehicle standing at (x, y, yaw) on the scene's ground and writes the
/// frame's three PNG files and its manifest row (without a line end).
void renderFrame(Renderer& renderer, const SceneSpec& spec, size_t obstacles, const std::string& meshes,
                 int index, int scene, double x, double y, double yaw, const std::string& img_dir,
                 std::ostream& manifest, const std::vector<uint16_t>* flat_of_id = nullptr) {
  const Terrain ground(spec.terrain);
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.translation() << x, y, ground.height(x, y);
  base.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  if (!ground.flat())  // the vehicle stands on the slope: tilted with the ground's normal
    base.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), ground.normal(x, y))
                        .toRotationMatrix() * base.linear();
  CameraFrame frame;
  renderer.renderCamera(base * cameraMount(1.5, 0.0, 1.4), true, &frame);
  const int w = frame.rgb.width, h = frame.rgb.height;
  char name[32];
  std::snprintf(name, sizeof(name), "%06d", index);
  cv::Mat rgb(h, w, CV_8UC3, frame.rgb.data.data()), bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  writePng(img_dir + "/" + name + "_rgb.png", bgr);
  writePng(img_dir + "/" + name + "_labels.png", cv::Mat(h, w, CV_8UC1, frame.labels.data.data()));
  writePng(img_dir + "/" + name + "_lit.png", cv::Mat(h, w, CV_8UC1, frame.lit.data.data()));
  if (flat_of_id) {  // renderer ids -> 1 + the obstacle's index in the scenario's flat list
    cv::Mat ids(h, w, CV_16UC1);
    for (int k = 0; k < w * h; ++k) {
      const uint16_t id = frame.instances.data[size_t(k)];
      ids.at<uint16_t>(k / w, k % w) = id < flat_of_id->size() ? (*flat_of_id)[id] : 0;
    }
    writePng(img_dir + "/" + name + "_instances.png", ids);
  }
  manifest << index << "," << scene << ",images/" << name << "_rgb.png,images/" << name
           << "_labels.png,images/" << name << "_lit.png," << spec.textural.sun_inclination_deg << ","
           << spec.textural.sun_yaw_deg << "," << meshes << "," << obstacles << "," << x << "," << y << ","
           << yaw << "," << spec.terrain.amplitude_m << "," << spec.terrain.hills.size() << ","
           << spec.textural.fog_visibility_m << "," << spec.textural.cloud_cover;
}

void progress(int index, int count) {
  if (index % 25 == 0 || index == count) {
    const int bar = 30 * index / count;
    std::fprintf(stderr, "\r[%.*s%*s] %d/%d frames", bar, "##############################", 30 - bar, "",
                 index, count);
  }
}

std::vector<PoseRow> readPoses(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read");
  const std::string header = "scenario,x,y,yaw";
  std::string line;
  if (!std::getline(in, line) || line.substr(0, header.size()) != header)
    throw std::runtime_error(path + ": the first line must be " + header);
  const std::string dir = path.find('/') == std::string::npos ? "." : path.substr(0, path.rfind('/'));
  std::vector<PoseRow> rows;
  for (int n = 2; std::getline(in, line); ++n) {
    if (line.empty()) continue;
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) f.push_back(c);
    if (line.back() == ',') f.push_back("");
    const std::string where = path + " line " + std::to_string(n);
    if (f.size() != 4) throw std::runtime_error(where + ": " + std::to_string(f.size()) + " fields, 4 expected");
    PoseRow r;
    r.scenario = f[0].empty() || f[0][0] == '/' ? f[0] : dir + "/" + f[0];
    try {
      auto num = [&](const std::string& v) {
        size_t used = 0;
        const double d = std::stod(v, &used);
        if (used != v.size() || !std::isfinite(d)) throw std::invalid_argument(v);
        return d;
      };
      r.x = num(f[1]);
      r.y = num(f[2]);
      r.yaw = num(f[3]);
    } catch (const std::logic_error&) {
      throw std::runtime_error(where + ": x, y and yaw must be finite numbers");
    }
    if (f[0].empty()) throw std::runtime_error(where + ": no scenario file");
    rows.push_back(r);
  }
  if (rows.empty()) throw std::runtime_error(path + ": no poses");
  return rows;
}

/// The frames of a --poses file; consecutive rows of one scenario share its scene.
int renderPoses(const Args& a, const std::string& img_dir, std::ostream& manifest) {
  const std::vector<PoseRow> rows = readPoses(a.poses);
  Renderer renderer;
  std::string key, meshes;
  SceneSpec spec;
  size_t obstacles = 0;
  int scene = -1;
  std::vector<uint16_t> flat_of_id;  // renderer id -> 1 + flat obstacle index (--instances)
  for (size_t i = 0; i < rows.size(); ++i) {
    const PoseRow& r = rows[i];
    if (r.scenario != key) {
      key = r.scenario;
      ++scene;
      ScenarioFile f;
      try {
        f = loadScenarioYaml(r.scenario);
      } catch (const std::exception& e) {
        throw std::runtime_error(a.poses + " row " + std::to_string(i + 1) + ": " + e.what());
      }
      spec = f.spec;
      std::vector<PlacedObstacle> placed;
      std::vector<RemovedObstacle> removed;
      placeObstacles(spec, &placed, &removed);
      renderer.setScene(spec, placed);
      obstacles = placed.size();
      std::vector<size_t> offset(1, 0);
      for (const auto& l : spec.layouts) offset.push_back(offset.back() + l.instances.size());
      flat_of_id.assign(1, 0);
      for (const auto& p : placed) {
        if (flat_of_id.size() <= p.id) flat_of_id.resize(p.id + 1, 0);
        flat_of_id[p.id] = uint16_t(1 + offset[p.layout_index] + p.instance_index);
      }
      meshes.clear();
      for (const auto& l : spec.layouts) meshes += (meshes.empty() ? "" : "+") + l.mesh_name;
    }
    renderFrame(renderer, spec, obstacles, meshes, int(i), scene, r.x, r.y, r.yaw, img_dir, manifest,
                a.instances ? &flat_of_id : nullptr);
    manifest << "," << rows[i].scenario.substr(rows[i].scenario.rfind('/') + 1) << "\n";
    progress(int(i) + 1, int(rows.size()));
  }
  return int(rows.size());
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
    if (!a.poses.empty()) {
      manifest << kManifestHeader << ",source\n";
      const int n = renderPoses(a, img_dir, manifest);
      std::fprintf(stderr, "\nwrote %d frames to %s\n", n, a.out.c_str());
      return 0;
    }
    manifest << kManifestHeader << "\n";
    std::mt19937_64 rng(a.seed);
    std::mt19937_64 env(a.seed ^ 0x7E44A1A5EA7Eull);  // terrain and weather draws only
    Renderer renderer;
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
        std::string meshes;
        for (const auto& m : a.meshes) meshes += (meshes.empty() ? "" : "+") + m;
        renderFrame(renderer, spec, placed.size(), meshes, index, scene, x, y, yaw, img_dir, manifest);
        manifest << "\n";
        ++index;
        progress(index, a.count);
      }
    }
    std::fprintf(stderr, "\nwrote %d frames to %s\n", index, a.out.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "\nerror: %s\n", e.what());
    return 1;
  }
  return 0;
}
