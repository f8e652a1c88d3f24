#include "hapticut/space.h"

#include <stdexcept>
#include <string>

#include "hapticut/material.h"
#include "hapticut/parameter_range.h"

namespace hapticut {

Space::Space(TetMesh mesh, std::vector<Material> materials, EngineSettings settings)
    : mesh_(std::move(mesh)), materials_(std::move(materials)), settings_(settings) {
  // The engine checks its own inputs (std::invalid_argument naming the value):
  // a NaN, infinite, negative or absurd setting would reach the device.
  check_in_range(setting_range::kStiffness, settings_.stiffness_N_per_mm, "stiffness_N_per_mm");
  check_in_range(setting_range::kServoRate, settings_.servo_rate_Hz, "servo_rate_Hz");
  check_in_range(setting_range::kMaxTransitions, settings_.max_transitions_per_tick,
                 "max_transitions_per_tick");
  check_in_range(setting_range::kCappedTickForce, settings_.capped_tick_force_N,
                 "capped_tick_force_N");
  for (const Material& material : materials_) validate_material(material);
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
}

Space Space::from_scene(const Scene& scene) {
  check_safety_limits(scene.safety);
  EngineSettings settings;
  settings.stiffness_N_per_mm = scene.stiffness_N_per_mm;
  settings.servo_rate_Hz = scene.servo_rate_Hz;
  settings.max_transitions_per_tick = scene.safety.max_transitions_per_tick;
  settings.capped_tick_force_N = scene.safety.capped_tick_force_N;
  return Space(TetMesh(scene.vertices_mm, scene.tets, scene.tet_materials, scene.tolerance_mm),
               scene.materials, settings);
}

}  // namespace hapticut
