// Shared helpers of the C++ tests: a Space from reference geometry.
#pragma once

#include <memory>
#include <vector>

#include "hapticut/reference_meshes.h"
#include "hapticut/space.h"

namespace hapticut::testing {

inline Material free_material() { return {"air", MaterialModel::Free}; }
inline Material drag_material(double d_mm) {
  Material m{"flesh", MaterialModel::Drag};
  m.drag_distance_mm = d_mm;
  return m;
}
inline Material rigid_material() { return {"bone", MaterialModel::Rigid}; }

// Materials: 0 air (free), 1 flesh (drag 1 mm), 2 bone (rigid).
inline std::vector<Material> paper_materials() {
  return {free_material(), drag_material(1.0), rigid_material()};
}

inline std::shared_ptr<const Space> make_space(const MeshData& data,
                                               std::vector<std::int32_t> tet_materials,
                                               std::vector<Material> materials = paper_materials(),
                                               EngineSettings settings = {}) {
  return Space::create(TetMesh(data.vertices_mm, data.tets, std::move(tet_materials)),
                       std::move(materials), settings);
}

inline std::shared_ptr<const Space> make_space(const MeshData& data, std::int32_t material) {
  return make_space(data, std::vector<std::int32_t>(data.tets.size(), material));
}

// Bone below z = 0 inside a free 40 mm box (material 2 of paper_materials).
inline std::shared_ptr<const Space> bone_floor(EngineSettings settings = {}) {
  const MeshData mesh = grid_mesh({-20, 0, 20}, {-20, 0, 20}, {-20, 0, 20});
  std::vector<std::int32_t> m(mesh.tets.size(), 0);
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    double z = 0;
    for (std::int32_t v : mesh.tets[t]) z += mesh.vertices_mm[v].z * 0.25;
    if (z < 0) m[t] = 2;
  }
  return make_space(mesh, m, paper_materials(), settings);
}

}  // namespace hapticut::testing
