#define GL_GLEXT_PROTOTYPES 1
#include "asg_sim/renderer.hpp"

#include <GL/osmesa.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

#include "asg_sim/meshes.hpp"

namespace asg_sim {
namespace {

using Mat4 = Eigen::Matrix4f;

void checkGl(const char* what) {
  const GLenum e = glGetError();
  if (e != GL_NO_ERROR) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "0x%04x", e);
    throw std::runtime_error(std::string("OpenGL error ") + buf + " in " + what);
  }
}

const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 aPos;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec3 aColor;
uniform mat4 uModel;
uniform mat4 uView;
uniform mat4 uProj;
uniform mat4 uLightViewProj;
out vec3 vWorld;
out vec3 vNormal;
out vec3 vColor;
out vec4 vLight;
out float vEyeDepth;
void main() {
  vec4 world = uModel * vec4(aPos, 1.0);
  vec4 eye = uView * world;
  vWorld = world.xyz;
  vNormal = mat3(uModel) * aNormal;
  vColor = aColor;
  vLight = uLightViewProj * world;
  vEyeDepth = -eye.z;
  gl_Position = uProj * eye;
}
)";

// Compiled twice: with LABELS defined (camera frames with labels) and without (RGB + depth
// only, and the top-down), so frames without labels skip the footprint look-up: llvmpipe runs
// both sides of a branch on a uniform, so a run-time switch would not save it.
const char* kFragmentShader = R"(
in vec3 vWorld;
in vec3 vNormal;
in vec3 vColor;
in vec4 vLight;
in float vEyeDepth;
uniform vec3 uSunDir;
uniform float uSunIntensity;
uniform float uAmbient;
uniform int uGround;
uniform float uSeed;
uniform sampler2DShadow uShadowMap;
uniform sampler2D uShadowOpacity;  // opacity of the caster nearest the sun (dense vs sparse foliage)
uniform int uShadows;
uniform vec4 uLabel;  // r: label / 255, g, b: instance id low, high byte / 255
uniform sampler2D uFootprint;  // ground under a non-traversable obstacle's canopy (top-down)
uniform vec4 uFootprintBox;    // xy: world corner of the footprint map, zw: 1 / its extent
uniform float uFogVisibility;  // [m] contrast down to 5 % at this eye depth; 0: no fog
uniform vec3 uFogColor;        // display colour of the fog (and of the sky far away in it)
layout(location = 0) out vec4 oColor;
layout(location = 1) out float oDepth;
layout(location = 2) out vec4 oLabel;

float hash(vec2 p) {
  p = fract(p * vec2(0.1031, 0.1030) + uSeed);
  p += dot(p, p.yx + 33.33);
  return fract((p.x + p.y) * p.x);
}
float noise(vec2 p) {
  vec2 i = floor(p), f = fract(p);
  vec2 u = f * f * (3.0 - 2.0 * f);
  return mix(mix(hash(i), hash(i + vec2(1, 0)), u.x), mix(hash(i + vec2(0, 1)), hash(i + vec2(1, 1)), u.x), u.y);
}
vec3 groundAlbedo(vec2 xy) {
  float n = 0.5 * noise(xy * 0.08) + 0.3 * noise(xy * 0.4) + 0.2 * noise(xy * 2.1);
  vec3 grass = vec3(0.30, 0.42, 0.17);
  vec3 dry = vec3(0.48, 0.46, 0.26);
  vec3 dirt = vec3(0.46, 0.37, 0.25);
  vec3 c = mix(grass, dry, smoothstep(0.35, 0.65, n));
  c = mix(c, dirt, smoothstep(0.62, 0.80, noise(xy * 0.05 + 17.0)));
  return c * (0.85 + 0.3 * noise(xy * 6.0));
}
void main() {
  vec3 n = normalize(vNormal);
  if (!gl_FrontFacing && uGround == 0) n = -n;
  vec3 albedo = uGround == 1 ? groundAlbedo(vWorld.xy) : vColor;
  float lit = 1.0;
  if (uShadows == 1) {
    vec3 p = vLight.xyz / vLight.w * 0.5 + 0.5;
    if (p.x > 0.0 && p.x < 1.0 && p.y > 0.0 && p.y < 1.0 && p.z < 1.0)
      lit = 1.0 - (1.0 - texture(uShadowMap, vec3(p.xy, p.z - 0.0015))) * texture(uShadowOpacity, p.xy).r;
  }
  float diffuse = max(dot(n, uSunDir), 0.0);
  vec3 c = albedo * (uAmbient + uSunIntensity * diffuse * lit);
  vec3 display = pow(clamp(c, 0.0, 1.0), vec3(1.0 / 1.6));
  if (uFogVisibility > 0.0)  // Koschmieder: transmittance exp(-3 d / V), 5 % at d = V
    display = mix(uFogColor, display, exp(-3.0 * vEyeDepth / uFogVisibility));
  oColor = vec4(display, 1.0);
  oDepth = vEyeDepth;
  vec4 label = uLabel;
  // In fog, what lies beyond the visibility is not seen: labelled as sky (no obstacle, no
  // ground), instance 0, so it neither counts as visible nor gets a label to vote from.
  if (uFogVisibility > 0.0 && vEyeDepth > uFogVisibility) label = vec4(2.0 / 255.0, 0.0, 0.0, 0.0);
#ifdef LABELS
  if (uGround == 1) {
    // Ground under an obstacle's canopy (seen from straight above): void (kUnderCanopy).
    vec2 q = (vWorld.xy - uFootprintBox.xy) * uFootprintBox.zw;
    if (q.x > 0.0 && q.x < 1.0 && q.y > 0.0 && q.y < 1.0 && texture(uFootprint, q).r > 0.5)
      label.r = 3.0 / 255.0;
  }
#endif
  oLabel = vec4(label.rgb, lit);  // a: how lit the surface is (0 = full shadow)
}
)";

const char* kShadowVertexShader = R"(#version 330 core
layout(location = 0) in vec3 aPos;
uniform mat4 uModel;
uniform mat4 uLightViewProj;
void main() { gl_Position = uLightViewProj * uModel * vec4(aPos, 1.0); }
)";

const char* kShadowFragmentShader = R"(#version 330 core
uniform float uOpacity;
layout(location = 0) out vec4 oOpacity;
void main() { oOpacity = vec4(uOpacity); }
)";

GLuint compile(GLenum type, const char* src) {
  GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048];
    glGetShaderInfoLog(s, sizeof(log), nullptr, log);
    throw std::runtime_error(std::string("shader compile failed: ") + log);
  }
  return s;
}

GLuint link(const std::string& vs, const std::string& fs) {
  GLuint p = glCreateProgram();
  GLuint v = compile(GL_VERTEX_SHADER, vs.c_str()), f = compile(GL_FRAGMENT_SHADER, fs.c_str());
  glAttachShader(p, v);
  glAttachShader(p, f);
  glLinkProgram(p);
  glDeleteShader(v);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048];
    glGetProgramInfoLog(p, sizeof(log), nullptr, log);
    throw std::runtime_error(std::string("shader link failed: ") + log);
  }
  return p;
}

Mat4 perspective(double fov_rad, double aspect, double n, double f) {
  const float t = 1.0f / std::tan(fov_rad / 2);
  Mat4 m = Mat4::Zero();
  m(0, 0) = t / aspect;
  m(1, 1) = t;
  m(2, 2) = -(f + n) / (f - n);
  m(2, 3) = -2 * f * n / (f - n);
  m(3, 2) = -1;
  return m;
}

Mat4 ortho(double l, double r, double b, double t, double n, double f) {
  Mat4 m = Mat4::Identity();
  m(0, 0) = 2 / (r - l);
  m(1, 1) = 2 / (t - b);
  m(2, 2) = -2 / (f - n);
  m(0, 3) = -(r + l) / (r - l);
  m(1, 3) = -(t + b) / (t - b);
  m(2, 3) = -(f + n) / (f - n);
  return m;
}

// World -> eye for a camera at `eye` looking at `target` (GL convention: -z forward, y up).
Mat4 lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, const Eigen::Vector3d& up) {
  const Eigen::Vector3d f = (target - eye).normalized();
  const Eigen::Vector3d s = f.cross(up).normalized();
  const Eigen::Vector3d u = s.cross(f);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(eye);
  m(1, 3) = -u.dot(eye);
  m(2, 3) = f.dot(eye);
  return m.cast<float>();
}

struct GpuMesh {
  GLuint vao = 0, vbo = 0, ebo = 0;
  GLsizei count = 0;
};

GpuMesh upload(const Mesh& m) {
  GpuMesh g;
  glGenVertexArrays(1, &g.vao);
  glBindVertexArray(g.vao);
  glGenBuffers(1, &g.vbo);
  glBindBuffer(GL_ARRAY_BUFFER, g.vbo);
  glBufferData(GL_ARRAY_BUFFER, m.vertices.size() * sizeof(Vertex), m.vertices.data(),
               GL_STATIC_DRAW);
  glGenBuffers(1, &g.ebo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ebo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, m.indices.size() * sizeof(uint32_t), m.indices.data(),
               GL_STATIC_DRAW);
  for (int i = 0; i < 3; ++i) {
    glEnableVertexAttribArray(i);
    glVertexAttribPointer(i, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                          reinterpret_cast<void*>(i * 3 * sizeof(float)));
  }
  glBindVertexArray(0);
  g.count = m.indices.size();
  return g;
}

void release(GpuMesh* g) {
  if (g->ebo) glDeleteBuffers(1, &g->ebo);
  if (g->vbo) glDeleteBuffers(1, &g->vbo);
  if (g->vao) glDeleteVertexArrays(1, &g->vao);
  *g = GpuMesh();
}

// Render target with the camera's three colour attachments and a depth buffer.
struct Target {
  GLuint fbo = 0, color = 0, depth = 0, label = 0, zbuf = 0;
  int w = 0, h = 0;
};

GLuint makeTexture(GLenum internal, GLenum format, GLenum type, int w, int h) {
  GLuint t;
  glGenTextures(1, &t);
  glBindTexture(GL_TEXTURE_2D, t);
  glTexImage2D(GL_TEXTURE_2D, 0, internal, w, h, 0, format, type, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  return t;
}

Target makeTarget(int w, int h, bool full) {
  Target t;
  t.w = w;
  t.h = h;
  glGenFramebuffers(1, &t.fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
  t.color = makeTexture(GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, w, h);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, t.color, 0);
  if (full) {
    t.depth = makeTexture(GL_R32F, GL_RED, GL_FLOAT, w, h);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, t.depth, 0);
    t.label = makeTexture(GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, w, h);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT2, GL_TEXTURE_2D, t.label, 0);
  }
  glGenRenderbuffers(1, &t.zbuf);
  glBindRenderbuffer(GL_RENDERBUFFER, t.zbuf);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t.zbuf);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("camera framebuffer incomplete");
  return t;
}

void release(Target* t) {
  GLuint tex[] = {t->color, t->depth, t->label};
  for (GLuint x : tex)
    if (x) glDeleteTextures(1, &x);
  if (t->zbuf) glDeleteRenderbuffers(1, &t->zbuf);
  if (t->fbo) glDeleteFramebuffers(1, &t->fbo);
  *t = Target();
}

// Reads one attachment into a top-row-first buffer.
template <class T>
void readRows(GLenum attachment, GLenum format, GLenum type, int w, int h, int channels,
              std::vector<T>* rows, std::vector<T>* scratch) {
  scratch->resize(size_t(w) * h * channels);
  glReadBuffer(attachment);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, w, h, format, type, scratch->data());
  rows->resize(scratch->size());
  const size_t stride = size_t(w) * channels;
  for (int r = 0; r < h; ++r)  // OSMesa/GL origin is bottom-left
    std::copy_n(scratch->data() + size_t(h - 1 - r) * stride, stride, rows->data() + r * stride);
}

}  // namespace

struct Renderer::Gl {
  OSMesaContext ctx = nullptr;
  std::vector<unsigned char> dummy;
  GLuint program = 0, label_program = 0, shadow_program = 0;
  GLuint shadow_fbo = 0, shadow_tex = 0, shadow_opacity = 0;
  GLuint footprint_fbo = 0, footprint_tex = 0;
  float footprint_box[4] = {0, 0, 0, 0};
  Target camera, topdown;
  GpuMesh ground;
  bool ground_casts = false;  // a shaped ground shades itself (hills cast shadows); flat: no
  std::map<std::string, GpuMesh> meshes;
  struct Instance {
    std::string mesh;
    Mat4 model;
    float label[4];
    bool cast_shadow;
    float shadow_opacity;
    bool traversable;
  };
  std::vector<Instance> instances;
  Mat4 light_view_proj = Mat4::Identity();
  float seed = 0.0f;
  float sun_intensity = 0.9f;
  float ambient = 0.38f;
  float fog_visibility = 0.0f;      // [m]
  float fog_color[3] = {0, 0, 0};   // display colour
  float sky[4] = {0.62f, 0.75f, 0.90f, 1.0f};
  std::vector<uint8_t> scratch8, rows8;
  std::vector<float> scratchf;

  void use() {
    if (!OSMesaMakeCurrent(ctx, dummy.data(), GL_UNSIGNED_BYTE, 16, 16))
      throw std::runtime_error("OSMesaMakeCurrent failed");
  }

  // kCamera: ground and every obstacle with colour and labels; kShadow: shadow casters with
  // their opacity; kFootprint: non-traversable obstacles, opaque.
  enum class Pass { kCamera, kShadow, kFootprint };

  void drawScene(GLuint prog, Pass pass) {
    const bool camera = pass == Pass::kCamera;
    const GLint model_loc = glGetUniformLocation(prog, "uModel");
    const GLint ground_loc = camera ? glGetUniformLocation(prog, "uGround") : -1;
    const GLint label_loc = camera ? glGetUniformLocation(prog, "uLabel") : -1;
    const GLint opacity_loc = camera ? -1 : glGetUniformLocation(prog, "uOpacity");
    if (camera) {
      Mat4 id = Mat4::Identity();
      glUniformMatrix4fv(model_loc, 1, GL_FALSE, id.data());
      glUniform1i(ground_loc, 1);
      glUniform4f(label_loc, kTraversable / 255.0f, 0, 0, 0);
      glBindVertexArray(ground.vao);
      glDrawElements(GL_TRIANGLES, ground.count, GL_UNSIGNED_INT, nullptr);
      glUniform1i(ground_loc, 0);
    }
    if (pass == Pass::kShadow && ground_casts) {
      // Only the ground's faces turned away from the sun go into the shadow map (front faces
      // culled, as seen from the light): ground behind a hill falls in its shadow, and a slope
      // facing the sun never compares against itself (no shadow acne). A slope facing away is
      // unlit by its normal anyway.
      Mat4 id = Mat4::Identity();
      glUniformMatrix4fv(model_loc, 1, GL_FALSE, id.data());
      glUniform1f(opacity_loc, 1.0f);
      glEnable(GL_CULL_FACE);
      glCullFace(GL_FRONT);
      glBindVertexArray(ground.vao);
      glDrawElements(GL_TRIANGLES, ground.count, GL_UNSIGNED_INT, nullptr);
      glCullFace(GL_BACK);
      glDisable(GL_CULL_FACE);
    }
    for (const auto& inst : instances) {
      if (pass == Pass::kShadow && !inst.cast_shadow) continue;
      if (pass == Pass::kFootprint && inst.traversable) continue;
      glUniformMatrix4fv(model_loc, 1, GL_FALSE, inst.model.data());
      if (pass == Pass::kShadow) glUniform1f(opacity_loc, inst.shadow_opacity);
      if (pass == Pass::kFootprint) glUniform1f(opacity_loc, 1.0f);
      if (camera) glUniform4fv(label_loc, 1, inst.label);
      const GpuMesh& m = meshes.at(inst.mesh);
      glBindVertexArray(m.vao);
      glDrawElements(GL_TRIANGLES, m.count, GL_UNSIGNED_INT, nullptr);
    }
    glBindVertexArray(0);
  }
};

// Orthographic camera looking straight down on the square [lo, hi]^2 of the ground (x right,
// y up in the picture).
void topDownCamera(double lo, double hi, Mat4* view, Mat4* proj) {
  const double c = (lo + hi) / 2, r = (hi - lo) / 2;
  *view = lookAt(Eigen::Vector3d(c, c, 100.0), Eigen::Vector3d(c, c, 0), Eigen::Vector3d::UnitY());
  *proj = ortho(-r, r, -r, r, 1.0, 200.0);
}

double CameraModel::fx() const { return (width / 2.0) / std::tan(fov_deg * M_PI / 360.0); }
double CameraModel::fy() const { return fx(); }

std::vector<Eigen::Vector3f> backProject(const DepthImage& depth, const CameraModel& camera, int stride) {
  if (stride < 1) throw std::invalid_argument("backProject: stride must be >= 1 px");
  std::vector<Eigen::Vector3f> out;
  out.reserve(size_t(depth.width / stride + 1) * size_t(depth.height / stride + 1));
  const double fx = camera.fx(), fy = camera.fy(), cx = camera.cx(), cy = camera.cy();
  for (int v = 0; v < depth.height; v += stride)
    for (int u = 0; u < depth.width; u += stride) {
      const float d = depth.at(u, v);
      if (!std::isfinite(d)) continue;
      out.emplace_back(float((u - cx) / fx * d), float((v - cy) / fy * d), d);
    }
  return out;
}

Eigen::Isometry3d cameraMount(double x, double y, double z, double pitch_down_rad) {
  // optical axes in base_link: z_opt = +x_base, x_opt = -y_base, y_opt = -z_base
  Eigen::Matrix3d R;
  R << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(pitch_down_rad, Eigen::Vector3d::UnitY()).toRotationMatrix() * R;
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

Renderer::Renderer(const CameraModel& camera, const RenderOptions& options)
    : gl_(new Gl), camera_(camera), options_(options) {
  const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_PROFILE,
                         OSMESA_CORE_PROFILE, OSMESA_CONTEXT_MAJOR_VERSION, 3,
                         OSMESA_CONTEXT_MINOR_VERSION, 3, 0};
  gl_->ctx = OSMesaCreateContextAttribs(attribs, nullptr);
  if (!gl_->ctx) throw std::runtime_error("OSMesaCreateContextAttribs failed (OpenGL 3.3 core)");
  gl_->dummy.resize(16 * 16 * 4);
  gl_->use();
  gl_->program = link(kVertexShader, std::string("#version 330 core\n") + kFragmentShader);
  gl_->label_program =
      link(kVertexShader, std::string("#version 330 core\n#define LABELS\n") + kFragmentShader);
  gl_->shadow_program = link(kShadowVertexShader, kShadowFragmentShader);
  gl_->camera = makeTarget(camera_.width, camera_.height, true);

  glGenTextures(1, &gl_->shadow_tex);
  glBindTexture(GL_TEXTURE_2D, gl_->shadow_tex);
  const int s = options_.shadow_map_px;
  glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, s, s, 0, GL_DEPTH_COMPONENT, GL_FLOAT,
               nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  gl_->shadow_opacity = makeTexture(GL_R8, GL_RED, GL_UNSIGNED_BYTE, s, s);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glGenFramebuffers(1, &gl_->shadow_fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, gl_->shadow_fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, gl_->shadow_tex, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, gl_->shadow_opacity, 0);
  glDrawBuffer(GL_COLOR_ATTACHMENT0);
  glReadBuffer(GL_NONE);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("shadow framebuffer incomplete");
  const int f = options_.footprint_map_px;
  gl_->footprint_tex = makeTexture(GL_R8, GL_RED, GL_UNSIGNED_BYTE, f, f);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glGenFramebuffers(1, &gl_->footprint_fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, gl_->footprint_fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, gl_->footprint_tex, 0);
  glDrawBuffer(GL_COLOR_ATTACHMENT0);
  glReadBuffer(GL_NONE);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("footprint framebuffer incomplete");
  for (const auto& info : meshCatalogue()) gl_->meshes[info.name] = upload(makeObstacleMesh(info.name));
  glEnable(GL_DEPTH_TEST);
  glEnable(GL_CULL_FACE);
  checkGl("Renderer setup");
}

Renderer::~Renderer() {
  if (!gl_ || !gl_->ctx) return;
  gl_->use();
  // reverse order of creation
  for (auto& kv : gl_->meshes) release(&kv.second);
  release(&gl_->ground);
  if (gl_->shadow_fbo) glDeleteFramebuffers(1, &gl_->shadow_fbo);
  if (gl_->shadow_tex) glDeleteTextures(1, &gl_->shadow_tex);
  if (gl_->shadow_opacity) glDeleteTextures(1, &gl_->shadow_opacity);
  if (gl_->footprint_fbo) glDeleteFramebuffers(1, &gl_->footprint_fbo);
  if (gl_->footprint_tex) glDeleteTextures(1, &gl_->footprint_tex);
  release(&gl_->topdown);
  release(&gl_->camera);
  glDeleteProgram(gl_->shadow_program);
  glDeleteProgram(gl_->label_program);
  glDeleteProgram(gl_->program);
  OSMesaDestroyContext(gl_->ctx);
}

void Renderer::setScene(const SceneSpec& spec, const std::vector<PlacedObstacle>& placed) {
  gl_->use();
  const auto& L = spec.landscape;
  scene_size_ = L.size;
  release(&gl_->ground);
  const Terrain terrain(spec.terrain);
  const Mesh ground = makeGroundMesh(L.size, L.border, L.subdivisions, terrain);
  float ground_lo = 0.0f, ground_hi = 0.0f;  // [m] the ground's height range (0, 0 when flat)
  for (const auto& v : ground.vertices) {
    ground_lo = std::min(ground_lo, v.pos[2]);
    ground_hi = std::max(ground_hi, v.pos[2]);
  }
  gl_->ground = upload(ground);
  gl_->ground_casts = !terrain.flat();
  gl_->seed = float(spec.textural.ground_texture_seed % 9973) * 0.6180339f;
  gl_->instances.clear();
  for (const auto& p : placed) {
    Eigen::Affine3f m = Eigen::Affine3f::Identity();
    m.translate(Eigen::Vector3f(p.pose.x, p.pose.y, p.z));
    m.rotate(Eigen::AngleAxisf(p.pose.yaw, Eigen::Vector3f::UnitZ()));
    m.scale(float(p.pose.scale));
    const MeshInfo* info = findMesh(p.mesh_name);
    Gl::Instance inst{p.mesh_name, m.matrix(), {}, p.pose.cast_shadow,
                      info ? float(info->shadow_opacity) : 1.0f, p.traversable};
    inst.label[0] = (p.traversable ? kTraversable : kNonTraversable) / 255.0f;
    inst.label[1] = (p.id & 0xFF) / 255.0f;
    inst.label[2] = ((p.id >> 8) & 0xFF) / 255.0f;
    inst.label[3] = 0.0f;
    gl_->instances.push_back(inst);
  }

  const double inc = spec.textural.sun_inclination_deg * M_PI / 180.0;
  const double yaw = spec.textural.sun_yaw_deg * M_PI / 180.0;
  // A sun below 5 degrees is lit as at 5 degrees: the ground stays visible at dawn and dusk.
  const double elev = std::max(inc, 5.0 * M_PI / 180.0);
  sun_dir_ = Eigen::Vector3d(std::cos(elev) * std::cos(yaw), std::cos(elev) * std::sin(yaw),
                             std::sin(elev));

  // Orthographic light frustum fitted around the ground box and the tallest obstacle.
  double top = 1.0;
  for (const auto& p : placed) top = std::max(top, p.z + p.height);
  top = std::max(top, double(ground_hi));
  const Eigen::Vector3d centre(L.size / 2, L.size / 2, 0);
  const double R = L.size / 2 + L.border;
  const Eigen::Vector3d up =
      std::abs(sun_dir_.z()) > 0.99 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ();
  const Mat4 view = lookAt(centre + sun_dir_ * (2 * R + top), centre, up);
  Eigen::Vector3f lo(1e9, 1e9, 1e9), hi(-1e9, -1e9, -1e9);
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector4f corner(centre.x() + ((c & 1) ? R : -R), centre.y() + ((c & 2) ? R : -R),
                                 (c & 4) ? top : double(ground_lo), 1.0);
    const Eigen::Vector4f v = view * corner;
    lo = lo.cwiseMin(v.head<3>());
    hi = hi.cwiseMax(v.head<3>());
  }
  gl_->light_view_proj = ortho(lo.x(), hi.x(), lo.y(), hi.y(), -hi.z() - 1, -lo.z() + 1) * view;
  // Weather (textural): cloud cover c takes the direct sun to (1 - 0.8 c) of clear sky and adds
  // 0.3 c of diffuse sky light (weaker shadows), and greys the sky; fog blends towards its colour
  // with eye depth. Clear skies (c = 0, no fog) keep exactly the constants of before.
  const float c = float(spec.textural.cloud_cover);
  gl_->sun_intensity = c > 0.0f ? 0.95f * (1.0f - 0.8f * c) : 0.95f;
  gl_->ambient = c > 0.0f ? 0.38f + 0.30f * c : 0.38f;
  const float clear_sky[3] = {0.62f, 0.75f, 0.90f}, grey_sky[3] = {0.70f, 0.72f, 0.75f};
  const float fog_clear[3] = {0.80f, 0.82f, 0.85f}, fog_grey[3] = {0.72f, 0.73f, 0.75f};
  gl_->fog_visibility = float(spec.textural.fog_visibility_m);
  // The sky seen through fog: as a surface 1 km away.
  const float sky_t = gl_->fog_visibility > 0.0f ? std::exp(-3.0f * 1000.0f / gl_->fog_visibility) : 1.0f;
  for (int k = 0; k < 3; ++k) {
    gl_->fog_color[k] = fog_clear[k] + (fog_grey[k] - fog_clear[k]) * c;
    const float sky = clear_sky[k] + (grey_sky[k] - clear_sky[k]) * c;
    gl_->sky[k] = gl_->fog_color[k] + (sky - gl_->fog_color[k]) * sky_t;
  }
  if (c == 0.0f && gl_->fog_visibility == 0.0f)
    for (int k = 0; k < 3; ++k) gl_->sky[k] = clear_sky[k];

  const auto t0 = std::chrono::steady_clock::now();
  glBindFramebuffer(GL_FRAMEBUFFER, gl_->shadow_fbo);
  glViewport(0, 0, options_.shadow_map_px, options_.shadow_map_px);
  const float no_caster[] = {0, 0, 0, 0};
  glClearBufferfv(GL_COLOR, 0, no_caster);
  glClear(GL_DEPTH_BUFFER_BIT);
  if (options_.shadows) {
    glUseProgram(gl_->shadow_program);
    glUniformMatrix4fv(glGetUniformLocation(gl_->shadow_program, "uLightViewProj"), 1, GL_FALSE,
                       gl_->light_view_proj.data());
    glDisable(GL_CULL_FACE);  // thin foliage must cast from both sides
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1.5f, 2.0f);
    gl_->drawScene(gl_->shadow_program, Gl::Pass::kShadow);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glEnable(GL_CULL_FACE);
  }
  renderFootprints(L.size);
  glFinish();
  shadow_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  checkGl("Renderer::setScene");
}

void Renderer::renderFootprints(double size) {
  // Top-down orthographic coverage of every non-traversable obstacle over the landscape plus a
  // margin for canopies that overhang its edge: the label pass marks the ground under them
  // kUnderCanopy.
  const double margin = 5.0, lo = -margin, hi = size + margin;
  gl_->footprint_box[0] = gl_->footprint_box[1] = float(lo);
  gl_->footprint_box[2] = gl_->footprint_box[3] = float(1.0 / (hi - lo));
  glBindFramebuffer(GL_FRAMEBUFFER, gl_->footprint_fbo);
  glViewport(0, 0, options_.footprint_map_px, options_.footprint_map_px);
  const float none[] = {0, 0, 0, 0};
  glClearBufferfv(GL_COLOR, 0, none);
  Mat4 view, proj;
  topDownCamera(lo, hi, &view, &proj);
  const Mat4 view_proj = proj * view;
  glUseProgram(gl_->shadow_program);
  glUniformMatrix4fv(glGetUniformLocation(gl_->shadow_program, "uLightViewProj"), 1, GL_FALSE,
                     view_proj.data());
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  gl_->drawScene(gl_->shadow_program, Gl::Pass::kFootprint);
  glEnable(GL_CULL_FACE);
  glEnable(GL_DEPTH_TEST);
}

namespace {
void setCommonUniforms(GLuint prog, const Mat4& view, const Mat4& proj, const Mat4& light,
                       const Eigen::Vector3d& sun, float intensity, float ambient, float fog_visibility,
                       const float* fog_color, float seed, bool shadows, GLuint shadow_tex,
                       GLuint shadow_opacity, GLuint footprint_tex, const float* footprint_box) {
  glUseProgram(prog);
  glUniformMatrix4fv(glGetUniformLocation(prog, "uView"), 1, GL_FALSE, view.data());
  glUniformMatrix4fv(glGetUniformLocation(prog, "uProj"), 1, GL_FALSE, proj.data());
  glUniformMatrix4fv(glGetUniformLocation(prog, "uLightViewProj"), 1, GL_FALSE, light.data());
  glUniform3f(glGetUniformLocation(prog, "uSunDir"), sun.x(), sun.y(), sun.z());
  glUniform1f(glGetUniformLocation(prog, "uSunIntensity"), intensity);
  glUniform1f(glGetUniformLocation(prog, "uAmbient"), ambient);
  glUniform1f(glGetUniformLocation(prog, "uFogVisibility"), fog_visibility);
  glUniform3fv(glGetUniformLocation(prog, "uFogColor"), 1, fog_color);
  glUniform1f(glGetUniformLocation(prog, "uSeed"), seed);
  glUniform1i(glGetUniformLocation(prog, "uShadows"), shadows ? 1 : 0);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, shadow_tex);
  glUniform1i(glGetUniformLocation(prog, "uShadowMap"), 0);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, shadow_opacity);
  glUniform1i(glGetUniformLocation(prog, "uShadowOpacity"), 1);
  glActiveTexture(GL_TEXTURE2);
  glBindTexture(GL_TEXTURE_2D, footprint_tex);
  glUniform1i(glGetUniformLocation(prog, "uFootprint"), 2);
  glUniform4fv(glGetUniformLocation(prog, "uFootprintBox"), 1, footprint_box);
  glActiveTexture(GL_TEXTURE0);
}
}  // namespace

void Renderer::renderCamera(const Eigen::Isometry3d& T_map_optical, bool with_labels,
                            CameraFrame* out) {
  gl_->use();
  const int w = camera_.width, h = camera_.height;
  Eigen::Matrix4d flip = Eigen::Matrix4d::Identity();
  flip(1, 1) = -1;
  flip(2, 2) = -1;  // optical (y down, z forward) -> GL eye (y up, -z forward)
  const Mat4 view = (flip * T_map_optical.inverse().matrix()).cast<float>();
  const Mat4 proj = perspective(camera_.fov_deg * M_PI / 180.0, double(w) / h, camera_.near, camera_.far);
  glBindFramebuffer(GL_FRAMEBUFFER, gl_->camera.fbo);
  glViewport(0, 0, w, h);
  const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
  glDrawBuffers(with_labels ? 3 : 2, bufs);
  const float* sky = gl_->sky;
  const float nan[] = {std::numeric_limits<float>::quiet_NaN(), 0, 0, 0};
  const float sky_label[] = {kSky / 255.0f, 0, 0, 0};
  glClearBufferfv(GL_COLOR, 0, sky);
  glClearBufferfv(GL_COLOR, 1, nan);
  if (with_labels) glClearBufferfv(GL_COLOR, 2, sky_label);
  glClear(GL_DEPTH_BUFFER_BIT);
  const GLuint prog = with_labels ? gl_->label_program : gl_->program;
  setCommonUniforms(prog, view, proj, gl_->light_view_proj, sun_dir_, gl_->sun_intensity, gl_->ambient,
                    gl_->fog_visibility, gl_->fog_color, gl_->seed, options_.shadows, gl_->shadow_tex,
                    gl_->shadow_opacity, gl_->footprint_tex, gl_->footprint_box);
  gl_->drawScene(prog, Gl::Pass::kCamera);

  readRows(GL_COLOR_ATTACHMENT0, GL_RGBA, GL_UNSIGNED_BYTE, w, h, 4, &gl_->rows8, &gl_->scratch8);
  out->rgb.resize(w, h);
  for (size_t i = 0, n = size_t(w) * h; i < n; ++i)
    for (int c = 0; c < 3; ++c) out->rgb.data[i * 3 + c] = gl_->rows8[i * 4 + c];
  out->depth.resize(w, h);
  readRows(GL_COLOR_ATTACHMENT1, GL_RED, GL_FLOAT, w, h, 1, &out->depth.data, &gl_->scratchf);
  if (with_labels) {
    readRows(GL_COLOR_ATTACHMENT2, GL_RGBA, GL_UNSIGNED_BYTE, w, h, 4, &gl_->rows8, &gl_->scratch8);
    out->labels.resize(w, h);
    out->instances.resize(w, h);
    out->lit.resize(w, h);
    for (size_t i = 0, n = size_t(w) * h; i < n; ++i) {
      out->labels.data[i] = gl_->rows8[i * 4];
      out->instances.data[i] = uint16_t(gl_->rows8[i * 4 + 1] | (gl_->rows8[i * 4 + 2] << 8));
      out->lit.data[i] = gl_->rows8[i * 4 + 3];
    }
  } else {
    out->labels = LabelImage();
    out->instances = InstanceImage();
    out->lit = LabelImage();
  }
  checkGl("Renderer::renderCamera");
}

void Renderer::renderTopDown(int px, RgbImage* out) {
  gl_->use();
  if (gl_->topdown.w != px) {
    release(&gl_->topdown);
    gl_->topdown = makeTarget(px, px, false);
  }
  Mat4 view, proj;
  topDownCamera(0.0, scene_size_, &view, &proj);
  glBindFramebuffer(GL_FRAMEBUFFER, gl_->topdown.fbo);
  glViewport(0, 0, px, px);
  const GLenum bufs[] = {GL_COLOR_ATTACHMENT0};
  glDrawBuffers(1, bufs);
  glClearColor(0.62f, 0.75f, 0.90f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  // From above, fog would hide the whole scene: the top-down view shows the light, not the fog.
  setCommonUniforms(gl_->program, view, proj, gl_->light_view_proj, sun_dir_, gl_->sun_intensity, gl_->ambient,
                    0.0f, gl_->fog_color, gl_->seed, options_.shadows, gl_->shadow_tex, gl_->shadow_opacity,
                    gl_->footprint_tex, gl_->footprint_box);
  gl_->drawScene(gl_->program, Gl::Pass::kCamera);
  readRows(GL_COLOR_ATTACHMENT0, GL_RGBA, GL_UNSIGNED_BYTE, px, px, 4, &gl_->rows8, &gl_->scratch8);
  out->resize(px, px);
  for (size_t i = 0, n = size_t(px) * px; i < n; ++i)
    for (int c = 0; c < 3; ++c) out->data[i * 3 + c] = gl_->rows8[i * 4 + c];
  checkGl("Renderer::renderTopDown");
}

}  // namespace asg_sim
