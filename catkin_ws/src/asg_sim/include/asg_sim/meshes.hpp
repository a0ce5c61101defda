#pragma once
/// @file meshes.hpp
/// Procedural, deterministic meshes: the ground and the obstacle catalogue.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "asg_sim/terrain.hpp"

namespace asg_sim {

struct Vertex {
  std::array<float, 3> pos;     ///< [m] mesh frame (z up, origin on the ground)
  std::array<float, 3> normal;  ///< unit
  std::array<float, 3> color;   ///< linear RGB 0..1
};

struct Mesh {
  std::vector<Vertex> vertices;
  std::vector<uint32_t> indices;  ///< triangles, counter-clockwise seen from outside
};

/// Size figures of an obstacle type at scale 1, from the catalogue (scene_schema.hpp kCatalogue).
struct MeshInfo {
  std::string name;
  double height;            ///< [m]
  double collision_radius;  ///< [m]
  double shadow_opacity;    ///< [-] share of sunlight its shadow blocks: dense conifer 1, sparse shrub less
};

/// Catalogue of obstacle meshes, sorted by name.
const std::vector<MeshInfo>& meshCatalogue();

/// nullptr when the name is unknown.
const MeshInfo* findMesh(const std::string& name);

/// Builds the named obstacle mesh at scale 1. Throws std::invalid_argument on an unknown name.
Mesh makeObstacleMesh(const std::string& name);

/// Ground over [-border, size + border]^2 with subdivisions cells across the nominal size
/// (at most 8 x 8 cells when the ground is flat), heights and normals from the terrain.
Mesh makeGroundMesh(double size, double border, uint32_t subdivisions, const Terrain& terrain = Terrain());

}  // namespace asg_sim
