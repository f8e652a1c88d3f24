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

}  // namespace hapticut::testing
