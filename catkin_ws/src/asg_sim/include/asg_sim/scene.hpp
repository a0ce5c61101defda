#pragma once
/// @file scene.hpp
/// The scene description as plain C++ (a mirror of asg_msgs/SceneDescription, no ROS), its
/// validation, and the safety-radius filter. Units: metres, seconds, radians unless a name ends
/// in Deg. Frame: map (x east, y north, z up, landscape corner at the origin).

#include "asg_sim/scene_schema.hpp"
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "asg_sim/terrain.hpp"

namespace asg_sim {

/// One placed obstacle.
struct ObstacleInstance {
  bool visible = schema::kInstanceVisible.default_value != 0.0;          ///< false: not placed
  bool cast_shadow = schema::kInstanceCastShadow.default_value != 0.0;  ///< false: rendered without shadow
  double x = 0.0;           ///< [m]
  double y = 0.0;           ///< [m]
  double yaw = schema::kInstanceYaw.default_value;      ///< [rad]
  double scale = schema::kInstanceScale.default_value;  ///< [-] > 0
};

/// All instances of one obstacle type.
struct ObstacleLayout {
  std::string mesh_name;
  std::vector<ObstacleInstance> instances;
};

struct Landscape {
  double size = 100.0;          ///< [m] side of the nominal square
  uint32_t subdivisions = static_cast<uint32_t>(schema::kLandscapeSubdivisions.default_value);  ///< [-] per side
  double border = schema::kLandscapeBorder.default_value;  ///< [m] ground beyond the nominal square
};

struct Textural {
  double sun_inclination_deg = 45.0;  ///< [deg] elevation, 0..90
  double sun_yaw_deg = schema::kTexturalSunYawDeg.default_value;  ///< [deg] direction the light comes from
  uint32_t ground_texture_seed = static_cast<uint32_t>(schema::kTexturalGroundTextureSeed.default_value);
  /// [m] meteorological visibility of fog: the distance at which a surface keeps 5 % of its
  /// contrast (transmittance exp(-3 d / V)); 0: no fog. Beyond it nothing is labelled visible.
  double fog_visibility_m = schema::kTexturalFogVisibilityM.default_value;
  /// [-] cloud cover, 0 (clear sky) .. 1 (overcast): the sun's direct light falls to 20 %, the
  /// diffuse sky light rises, so shadows are weaker, and the sky turns grey.
  double cloud_cover = schema::kTexturalCloudCover.default_value;
};

struct Operational {
  // The defaults are the schema's (scene_schema.hpp, generated from asg_scenario/schema.py);
  // start and goal are required there (0 until a scenario sets them).
  double start_x = 0, start_y = 0;                                        ///< [m]
  double start_yaw = schema::kOperationalStartYaw.default_value;          ///< [rad]
  double goal_x = 0, goal_y = 0;                                          ///< [m]
  double goal_radius = schema::kOperationalGoalRadius.default_value;      ///< [m]
  double safety_radius = schema::kOperationalSafetyRadius.default_value;  ///< [m]
  double speed = schema::kOperationalSpeed.default_value;                 ///< [m/s]
  double sim_timeout = schema::kOperationalSimTimeout.default_value;      ///< [s], -1 disables
  double idle_timeout = schema::kOperationalIdleTimeout.default_value;    ///< [s], -1 disables
  double stuck_timeout = schema::kOperationalStuckTimeout.default_value;  ///< [s], -1 disables
  double max_roll_deg = schema::kOperationalMaxRollDeg.default_value;     ///< [deg]
  double max_pitch_deg = schema::kOperationalMaxPitchDeg.default_value;   ///< [deg]
  bool allow_collisions = schema::kOperationalAllowCollisions.default_value != 0.0;
};

struct SceneSpec {
  Landscape landscape;
  TerrainSpec terrain;  ///< structural.terrain: the ground's shape (flat by default)
  std::vector<ObstacleLayout> layouts;
  Textural textural;
  Operational operational;
};

/// A malformed scene: the message names the field, the value and what is allowed.
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The scene budget (docs/scenario-format.md): what one worker can build and run in bounded
/// memory and time; from the one schema (asg_scenario/schema.py, scene_schema.hpp).
constexpr size_t kMaxObstacles = schema::kMaxObstacles;  ///< [-] obstacle instances, all layouts
constexpr double kMaxLandscapeSize = schema::kLandscapeSize.hi;  ///< [m] side of the nominal square
constexpr double kMaxBorder = schema::kLandscapeBorder.hi;       ///< [m]
constexpr double kMaxGroundCellsPerSide = schema::kMaxGroundCellsPerSide;  ///< [-] subdivisions x (size + 2 border) / size
constexpr double kMaxSimTimeout = schema::kOperationalSimTimeout.hi;  ///< [s] sim_timeout is required to be finite

/// Throws SceneError listing every problem (NaN, out of range, unknown mesh, too many
/// obstacles, start inside an obstacle that the safety radius keeps).
void validateScene(const SceneSpec& spec);

/// An obstacle the worker places: its indices in the request and its resolved geometry.
struct PlacedObstacle {
  uint32_t layout_index = 0;
  uint32_t instance_index = 0;
  uint32_t id = 0;          ///< [-] 1-based, unique in the scene (0 is "no obstacle")
  std::string mesh_name;
  ObstacleInstance pose;
  double height = 0.0;      ///< [m] height x scale
  double radius = 0.0;      ///< [m] collision radius x scale
  double z = 0.0;           ///< [m] ground height at (pose.x, pose.y): where it stands
  bool traversable = false; ///< height <= 0.2 m
};

struct RemovedObstacle {
  uint32_t layout_index = 0;
  uint32_t instance_index = 0;
  std::string reason;  ///< "start_safety_radius" or "goal_safety_radius"
};

/// Splits the visible instances into placed ones and those inside a safety radius.
void placeObstacles(const SceneSpec& spec, std::vector<PlacedObstacle>* placed,
                    std::vector<RemovedObstacle>* removed);

/// Total instance count over all layouts (visible or not); visibility arrays use this order.
size_t instanceCount(const SceneSpec& spec);

}  // namespace asg_sim
