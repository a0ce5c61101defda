#include "asg_sim/meshes.hpp"

#include "asg_sim/scene_schema.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace asg_sim {
namespace {

using V3 = std::array<float, 3>;

V3 normalize(V3 v) {
  const float n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  return n > 0 ? V3{v[0] / n, v[1] / n, v[2] / n} : V3{0, 0, 1};
}

// Small deterministic hash in [0, 1): colour variation without any global RNG state.
float hash01(uint32_t a, uint32_t b) {
  uint32_t h = a * 0x9E3779B1u ^ (b + 0x7F4A7C15u) * 0x85EBCA77u;
  h ^= h >> 15;
  h *= 0x2C1B3C6Du;
  h ^= h >> 12;
  return (h & 0xFFFFFF) / float(0x1000000);
}

// Surface of revolution around z: rings of (z, r(theta)) with smooth normals computed from the
// grid; colour(ring, segment) per vertex. Closed at the top with a fan.
template <class RadiusFn, class ColorFn>
void addLathe(Mesh* m, int rings, int segments, float z0, float z1, RadiusFn radius,
              ColorFn color) {
  const uint32_t base = m->vertices.size();
  std::vector<V3> pos;
  for (int r = 0; r <= rings; ++r) {
    const float z = z0 + (z1 - z0) * r / rings;
    for (int s = 0; s < segments; ++s) {
      const float th = 2.0f * float(M_PI) * s / segments;
      const float rad = radius(z, th);
      pos.push_back({rad * std::cos(th), rad * std::sin(th), z});
    }
  }
  auto at = [&](int r, int s) { return pos[r * segments + ((s + segments) % segments)]; };
  for (int r = 0; r <= rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      const V3 a = at(std::min(r + 1, rings), s), b = at(std::max(r - 1, 0), s);
      const V3 c = at(r, s + 1), d = at(r, s - 1);
      const V3 up{a[0] - b[0], a[1] - b[1], a[2] - b[2]};
      const V3 side{c[0] - d[0], c[1] - d[1], c[2] - d[2]};
      V3 n{side[1] * up[2] - side[2] * up[1], side[2] * up[0] - side[0] * up[2],
           side[0] * up[1] - side[1] * up[0]};
      m->vertices.push_back({at(r, s), normalize(n), color(r, s)});
    }
  }
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      const uint32_t i0 = base + r * segments + s, i1 = base + r * segments + (s + 1) % segments;
      const uint32_t j0 = i0 + segments, j1 = i1 + segments;
      m->indices.insert(m->indices.end(), {i0, i1, j1, i0, j1, j0});
    }
  }
  // cap
  const uint32_t top = m->vertices.size();
  const float rtop = radius(z1, 0.0f);
  m->vertices.push_back({{0, 0, z1 + 0.3f * rtop}, {0, 0, 1}, color(rings, 0)});
  for (int s = 0; s < segments; ++s) {
    const uint32_t i0 = base + rings * segments + s, i1 = base + rings * segments + (s + 1) % segments;
    m->indices.insert(m->indices.end(), {i0, i1, top});
  }
}

Mesh makeJuniper() {
  Mesh m;
  // Trunk: brown cylinder [0, 1.0] m, radius 0.18 m.
  addLathe(&m, 1, 10, 0.0f, 1.0f, [](float, float) { return 0.18f; },
           [](int, int s) { return V3{0.30f + 0.04f * hash01(7, s), 0.20f, 0.12f}; });
  // Foliage: dense lumpy cone from 0.5 m (radius 1.3 m) to 4.5 m.
  const float z0 = 0.5f, z1 = 4.3f;
  addLathe(&m, 12, 18, z0, z1,
           [&](float z, float th) {
             const float u = (z - z0) / (z1 - z0);
             const float lump = 1.0f + 0.13f * std::sin(5.0f * th + 4.0f * z) *
                                           std::cos(3.0f * th - 2.0f * z);
             return std::max(0.05f, 1.3f * std::pow(1.0f - u, 0.85f) * lump + 0.05f);
           },
           [](int r, int s) {
             const float v = hash01(r, s);
             return V3{0.10f + 0.05f * v, 0.26f + 0.10f * v, 0.10f + 0.04f * v};
           });
  return m;
}

Mesh makeBarberry() {
  Mesh m;
  // Rounded shrub: squashed lumpy sphere, ground contact ring at 0.05 m, top at 1.2 m.
  const float z0 = 0.02f, z1 = 1.12f, zc = 0.55f;
  addLathe(&m, 10, 16, z0, z1,
           [&](float z, float th) {
             const float u = (z - zc) / (z1 - zc + 0.06f);
             const float base = 0.8f * std::sqrt(std::max(0.02f, 1.0f - u * u));
             return base * (1.0f + 0.12f * std::sin(4.0f * th + 6.0f * z));
           },
           [](int r, int s) {
             // Dark olive-green barberry foliage.
             const float v = hash01(r + 100, s);
             return V3{0.12f + 0.05f * v, 0.16f + 0.05f * v, 0.06f + 0.02f * v};
           });
  return m;
}

// Each class's mesh function, by its catalogue name (scene_schema.hpp's kCatalogue, generated
// from asg_scenario/catalogue.py): a new obstacle class is a catalogue entry and a row here.
struct MeshBuilder {
  const char* name;
  Mesh (*build)();
};
const MeshBuilder kMeshBuilders[] = {
    {"juniper", makeJuniper},
    {"barberry", makeBarberry},
};

}  // namespace

const std::vector<MeshInfo>& meshCatalogue() {
  static const std::vector<MeshInfo> catalogue = [] {
    std::vector<MeshInfo> c;
    for (const auto& e : schema::kCatalogue) c.push_back({e.name, e.height, e.collision_radius, e.shadow_opacity});
    std::sort(c.begin(), c.end(), [](const MeshInfo& a, const MeshInfo& b) { return a.name < b.name; });
    return c;
  }();
  return catalogue;
}

const MeshInfo* findMesh(const std::string& name) {
  for (const auto& m : meshCatalogue())
    if (m.name == name) return &m;
  return nullptr;
}

Mesh makeObstacleMesh(const std::string& name) {
  if (!findMesh(name)) throw std::invalid_argument("unknown mesh '" + name + "'");
  for (const auto& b : kMeshBuilders)
    if (name == b.name) return b.build();
  throw std::invalid_argument("mesh '" + name + "' is in the catalogue but has no mesh function (meshes.cpp)");
}

Mesh makeGroundMesh(double size, double border, uint32_t subdivisions, const Terrain& terrain) {
  Mesh m;
  const double lo = -border, hi = size + border;
  int n = std::max<int>(1, std::ceil(subdivisions * (hi - lo) / size));
  // A flat ground looks the same at any tessellation; its vertex count is most of the
  // rasteriser's cost (llvmpipe shades every vertex), so a flat one is drawn as 8 x 8 cells.
  n = std::min(n, terrain.flat() ? 8 : kMaxTerrainCellsPerSide);
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      const double x = lo + (hi - lo) * j / n, y = lo + (hi - lo) * i / n;
      const Eigen::Vector3f nrm = terrain.normal(x, y).cast<float>();
      m.vertices.push_back({{float(x), float(y), float(terrain.height(x, y))}, {nrm.x(), nrm.y(), nrm.z()}, {1, 1, 1}});
    }
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const uint32_t a = i * (n + 1) + j, b = a + 1, c = a + n + 1, d = c + 1;
      m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
    }
  }
  return m;
}

}  // namespace asg_sim
