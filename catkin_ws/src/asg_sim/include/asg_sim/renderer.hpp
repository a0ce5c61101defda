#pragma once
/// @file renderer.hpp
/// Headless OpenGL 3.3 rendering through OSMesa (llvmpipe): camera RGB, planar depth,
/// ground-truth labels and instance ids from one pass, sun shadows by shadow mapping, and an
/// orthographic top-down capture. No window system and no GPU needed.

#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "asg_sim/image.hpp"
#include "asg_sim/scene.hpp"

namespace asg_sim {

/// Pinhole camera. Intrinsics follow sensor_msgs/CameraInfo: pixel (u, v) centres at integer
/// coordinates, fx = fy = (width / 2) / tan(fov / 2), cx = (width - 1) / 2.
struct CameraModel {
  int width = 256;
  int height = 256;
  double fov_deg = 90.0;  ///< [deg] horizontal (and vertical: square pixels)
  double near = 0.1;      ///< [m]
  double far = 400.0;     ///< [m]
  double fx() const;
  double fy() const;
  double cx() const { return (width - 1) / 2.0; }
  double cy() const { return (height - 1) / 2.0; }
};

struct RenderOptions {
  int shadow_map_px = 2048;   ///< [px] side of the shadow map (covers landscape + border)
  int footprint_map_px = 2048;  ///< [px] side of the canopy footprint map (landscape + 5 m)
  bool shadows = true;
};

/// What one camera frame holds. labels/instances are empty unless asked for.
struct CameraFrame {
  RgbImage rgb;
  DepthImage depth;
  LabelImage labels;
  InstanceImage instances;
  LabelImage lit;  ///< 0 (sun fully shadowed) .. 255 (fully lit); with labels only
};

/// Owns one OSMesa context; one per thread that renders. Not copyable.
class Renderer {
 public:
  /// Creates the OSMesa context (core profile 3.3). Throws std::runtime_error on failure.
  explicit Renderer(const CameraModel& camera = CameraModel(),
                    const RenderOptions& options = RenderOptions());
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Uploads a scene (ground, placed obstacles, sun) and renders its shadow map and its canopy
  /// footprint map (ground covered by a non-traversable obstacle, seen from straight above,
  /// is labelled kUnderCanopy): the sun and the obstacles are static during a scenario, so
  /// this happens once per scene.
  void setScene(const SceneSpec& spec, const std::vector<PlacedObstacle>& placed);

  /// Renders the camera at T_map_optical (optical frame: z forward, x right, y down).
  void renderCamera(const Eigen::Isometry3d& T_map_optical, bool with_labels, CameraFrame* out);

  /// Orthographic top-down RGB of the landscape [0, size]^2 (x right, y up in the picture).
  void renderTopDown(int px, RgbImage* out);

  const CameraModel& camera() const { return camera_; }
  /// Sun direction (unit vector from the ground towards the sun) in map frame.
  Eigen::Vector3d sunDirection() const { return sun_dir_; }

  /// Milliseconds of the last setScene's shadow and footprint passes.
  double lastShadowPassMs() const { return shadow_ms_; }

 private:
  void renderFootprints(double size);
  struct Gl;
  std::unique_ptr<Gl> gl_;
  CameraModel camera_;
  RenderOptions options_;
  Eigen::Vector3d sun_dir_{0, 0, 1};
  double scene_size_ = 100.0;
  double shadow_ms_ = 0.0;
};

/// The depth image's returns as points in the optical frame [m] (x right, y down, z forward):
/// every `stride`-th pixel in u and v, row by row, pixels without a return (NaN) left out.
std::vector<Eigen::Vector3f> backProject(const DepthImage& depth, const CameraModel& camera, int stride = 1);

/// T_base_optical for a camera at (x, y, z) in base_link looking along base_link +x.
Eigen::Isometry3d cameraMount(double x, double y, double z, double pitch_down_rad = 0.0);

}  // namespace asg_sim
