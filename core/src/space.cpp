#include "hapticut/space.h"

#include <string>

#include "hapticut/material.h"

namespace hapticut {

Space::Space(TetMesh mesh, std::vector<Material> materials, EngineSettings settings)
    : mesh_(std::move(mesh)), materials_(std::move(materials)), settings_(settings) {
  const auto material_count = static_cast<std::int32_t>(materials_.size());
  rigid_.resize(mesh_.tet_count());
  for (std::int32_t t = 0; t < mesh_.tet_count(); ++t) {
    if (mesh_.material(t) >= material_count) {
      throw MeshError("tet " + std::to_string(t) + " refers to material " +
                          std::to_string(mesh_.material(t)) + ", not defined (" +
                          std::to_string(material_count) + " materials)",
                      t);
    }
    rigid_[t] = is_rigid(materials_[mesh_.material(t)]) ? 1 : 0;
  }
  for (const Material& m : materials_)
    uses_speed_ = uses_speed_ || m.model == MaterialModel::Viscous;
  if (settings_.max_transitions_per_tick < 1) settings_.max_transitions_per_tick = 1;
}

Space Space::from_scene(const Scene& scene) {
  EngineSettings settings;
  settings.stiffness_N_per_mm = scene.stiffness_N_per_mm;
  settings.servo_rate_Hz = scene.servo_rate_Hz;
  settings.max_transitions_per_tick = scene.safety.max_transitions_per_tick;
  settings.capped_tick_force_N = scene.safety.capped_tick_force_N;
  return Space(TetMesh(scene.vertices_mm, scene.tets, scene.tet_materials, scene.tolerance_mm),
               scene.materials, settings);
}

}  // namespace hapticut
