#include "asg_sim/scene.hpp"

#include <cmath>
#include <sstream>

#include "asg_sim/meshes.hpp"

namespace asg_sim {
namespace {

// The vehicle's half width and the traversable height: asg_scenario/catalogue.py's, through the
// generated scene_schema.hpp.
using schema::kTraversableHeight;
using schema::kVehicleHalfWidth;

class Problems {
 public:
  void add(const std::string& field, const std::string& msg) {
    out_ << "\n  - " << field << ": " << msg;
    ++n_;
  }
  void finite(const std::string& field, double v) {
    if (!std::isfinite(v)) add(field, "= " + num(v) + ": must be a finite number");
  }
  void range(const std::string& field, double v, double lo, double hi, const std::string& unit,
             bool allow_disable = false) {
    if (!std::isfinite(v)) {
      finite(field, v);
    } else if (allow_disable && v == -1.0) {
      return;
    } else if (v < lo || v > hi) {
      add(field, "= " + num(v) + ": out of range, must be in [" + num(lo) + ", " + num(hi) + "] " +
                     unit + (allow_disable ? ", or -1 to disable" : ""));
    }
  }
  // A field of the one schema (scene_schema.hpp): its range, unit and whether -1 disables it.
  void range(const std::string& field, double v, const schema::Field& f) {
    range(field, v, f.lo, f.hi, f.unit, f.disable);
  }
  void range(double v, const schema::Field& f) { range(f.key, v, f); }
  static std::string num(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
  }
  void raise() const {
    if (n_) throw SceneError("invalid scene, " + std::to_string(n_) + " problem(s):" + out_.str());
  }

 private:
  std::ostringstream out_;
  int n_ = 0;
};

}  // namespace

size_t instanceCount(const SceneSpec& spec) {
  size_t n = 0;
  for (const auto& l : spec.layouts) n += l.instances.size();
  return n;
}

namespace {

// Whether (x, y) lies in the landscape [0, size]^2; a problem naming prefix + axis otherwise.
bool insideLandscape(Problems& p, const std::string& prefix, double x, double y, double size) {
  bool ok = true;
  for (auto [axis, v] : {std::pair<const char*, double>{"x", x}, {"y", y}}) {
    if (!std::isfinite(v)) {
      p.finite(prefix + axis, v);
      ok = false;
    } else if (v < 0.0 || v > size) {
      p.add(prefix + axis, "= " + Problems::num(v) + ": outside the landscape, must be in [0, " +
                               Problems::num(size) + "] m");
      ok = false;
    }
  }
  return ok;
}

void checkLandscape(Problems& p, const Landscape& L) {
  p.range(L.size, schema::kLandscapeSize);
  p.range(L.subdivisions, schema::kLandscapeSubdivisions);
  p.range(L.border, schema::kLandscapeBorder);
  if (std::isfinite(L.size) && std::isfinite(L.border) && L.size >= 1.0 && L.border >= 0.0) {
    const double cells = L.subdivisions * (L.size + 2.0 * L.border) / L.size;
    if (cells > kMaxGroundCellsPerSide)
      p.add("structural.landscape.subdivisions",
            "= " + std::to_string(L.subdivisions) + " gives " + Problems::num(std::ceil(cells)) +
                " ground cells per side with the border: at most " +
                Problems::num(kMaxGroundCellsPerSide) + " (subdivisions x (size + 2 border) / size)");
  }
}

void checkTerrain(Problems& p, const TerrainSpec& T, double size) {
  p.range(T.amplitude_m, schema::kTerrainAmplitudeM);
  // The wavelength matters only with an amplitude: a message that leaves both 0 is flat.
  if (T.amplitude_m != 0.0) p.range(T.wavelength_m, schema::kTerrainWavelengthM);
  if (std::isfinite(T.amplitude_m) && std::isfinite(T.wavelength_m) && T.amplitude_m > 0.0 &&
      T.amplitude_m > kMaxAmplitudePerWavelength * T.wavelength_m)
    p.add("structural.terrain.amplitude_m",
          "= " + Problems::num(T.amplitude_m) + ": too steep for wavelength_m " + Problems::num(T.wavelength_m) +
              ", must be at most wavelength_m / 10 m");
  if (T.hills.size() > kMaxHills)
    p.add("structural.terrain.hills",
          std::to_string(T.hills.size()) + " hills: at most " + std::to_string(kMaxHills) + " allowed");
  for (size_t i = 0; i < T.hills.size() && i < kMaxHills; ++i) {
    const auto& h = T.hills[i];
    const std::string hp = "structural.terrain.hills[" + std::to_string(i) + "].";
    insideLandscape(p, hp, h.x, h.y, size);
    p.range(hp + "radius_m", h.radius_m, schema::kHillRadiusM);
    p.range(hp + "height_m", h.height_m, schema::kHillHeightM);
    if (std::isfinite(h.radius_m) && std::isfinite(h.height_m) &&
        std::abs(h.height_m) > kMaxHillHeightPerRadius * h.radius_m)
      p.add(hp + "height_m", "= " + Problems::num(h.height_m) + ": too steep for radius_m " +
                                 Problems::num(h.radius_m) + ", |height_m| must be at most radius_m / 2 m");
  }
}

void checkOperationalAndTextural(Problems& p, const Operational& O, const Textural& X, double size) {
  insideLandscape(p, "operational.start_", O.start_x, O.start_y, size);
  insideLandscape(p, "operational.goal_", O.goal_x, O.goal_y, size);
  p.range(O.start_yaw, schema::kOperationalStartYaw);
  p.range(O.goal_radius, schema::kOperationalGoalRadius);
  p.range(O.safety_radius, schema::kOperationalSafetyRadius);
  p.range(O.speed, schema::kOperationalSpeed);
  p.range(O.sim_timeout, schema::kOperationalSimTimeout);
  p.range(O.idle_timeout, schema::kOperationalIdleTimeout);
  p.range(O.stuck_timeout, schema::kOperationalStuckTimeout);
  p.range(O.max_roll_deg, schema::kOperationalMaxRollDeg);
  p.range(O.max_pitch_deg, schema::kOperationalMaxPitchDeg);
  p.range(X.sun_inclination_deg, schema::kTexturalSunInclinationDeg);
  p.range(X.sun_yaw_deg, schema::kTexturalSunYawDeg);
  p.range(X.fog_visibility_m, schema::kTexturalFogVisibilityM);
  p.range(X.cloud_cover, schema::kTexturalCloudCover);
}

void checkLayouts(Problems& p, const SceneSpec& spec, double size) {
  const auto& O = spec.operational;
  const size_t n = instanceCount(spec);
  if (n > kMaxObstacles) {
    p.add("structural.layouts", std::to_string(n) + " obstacle instances: at most " +
                                    std::to_string(kMaxObstacles) + " allowed");
    return;
  }
  for (size_t i = 0; i < spec.layouts.size(); ++i) {
    const auto& layout = spec.layouts[i];
    const std::string lp = "structural.layouts[" + std::to_string(i) + "]";
    const MeshInfo* mesh = findMesh(layout.mesh_name);
    if (!mesh) {
      std::string names;
      for (const auto& m : meshCatalogue()) names += (names.empty() ? "" : ", ") + m.name;
      p.add(lp + ".mesh_name", "= '" + layout.mesh_name + "': unknown mesh (one of " + names + ")");
    }
    for (size_t j = 0; j < layout.instances.size(); ++j) {
      const auto& inst = layout.instances[j];
      const std::string ip = lp + ".instances[" + std::to_string(j) + "].";
      bool ok = insideLandscape(p, ip, inst.x, inst.y, size);
      p.range(ip + "yaw", inst.yaw, schema::kInstanceYaw);
      p.range(ip + "scale", inst.scale, schema::kInstanceScale);
      ok = ok && std::isfinite(inst.scale) && inst.scale > 0;
      if (!ok || !mesh || !inst.visible || mesh->height * inst.scale <= kTraversableHeight) continue;
      const double d = std::hypot(inst.x - O.start_x, inst.y - O.start_y);
      const double reach = mesh->collision_radius * inst.scale + kVehicleHalfWidth;
      if (std::isfinite(d) && d >= O.safety_radius && d < reach)
        p.add(ip.substr(0, ip.size() - 1), "the start pose is inside this " + layout.mesh_name + " (distance " +
                                               Problems::num(d) + " m < " + Problems::num(reach) + " m)");
    }
  }
}

}  // namespace

void validateScene(const SceneSpec& spec) {
  Problems p;
  checkLandscape(p, spec.landscape);
  const double size = std::isfinite(spec.landscape.size) ? spec.landscape.size : 0.0;
  checkTerrain(p, spec.terrain, size);
  checkOperationalAndTextural(p, spec.operational, spec.textural, size);
  checkLayouts(p, spec, size);
  p.raise();
}

void placeObstacles(const SceneSpec& spec, std::vector<PlacedObstacle>* placed,
                    std::vector<RemovedObstacle>* removed) {
  placed->clear();
  removed->clear();
  const auto& O = spec.operational;
  const Terrain ground(spec.terrain);
  uint32_t id = 0;
  for (uint32_t i = 0; i < spec.layouts.size(); ++i) {
    const auto& layout = spec.layouts[i];
    const MeshInfo* mesh = findMesh(layout.mesh_name);
    for (uint32_t j = 0; j < layout.instances.size(); ++j) {
      ++id;  // ids follow the flattened request order, placed or not
      const auto& inst = layout.instances[j];
      if (!inst.visible || !mesh) continue;
      if (std::hypot(inst.x - O.start_x, inst.y - O.start_y) < O.safety_radius) {
        removed->push_back({i, j, "start_safety_radius"});
        continue;
      }
      if (std::hypot(inst.x - O.goal_x, inst.y - O.goal_y) < O.safety_radius) {
        removed->push_back({i, j, "goal_safety_radius"});
        continue;
      }
      PlacedObstacle p;
      p.layout_index = i;
      p.instance_index = j;
      p.id = id;
      p.mesh_name = layout.mesh_name;
      p.pose = inst;
      p.height = mesh->height * inst.scale;
      p.radius = mesh->collision_radius * inst.scale;
      p.traversable = p.height <= kTraversableHeight;
      p.z = ground.height(inst.x, inst.y);
      placed->push_back(p);
    }
  }
}

}  // namespace asg_sim
