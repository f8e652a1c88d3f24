#include "hapticut/space.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "hapticut/material.h"
#include "hapticut/parameter_range.h"

namespace hapticut {

void RuntimeSettings::validate() const {
  check_in_range(setting_range::kStiffness, stiffness_N_per_mm, "stiffness_N_per_mm");
  check_in_range(setting_range::kMaxTransitions, max_transitions_per_tick,
                 "max_transitions_per_tick");
  check_in_range(setting_range::kCappedTickForce, capped_tick_force_N, "capped_tick_force_N");
  if (blade_transition_budget < 0) {
    throw std::invalid_argument("blade_transition_budget must be >= 0 (0: automatic), got " +
                                std::to_string(blade_transition_budget));
  }
}

Space::Space(Key /*key*/, TetMesh mesh, std::vector<Material> materials, EngineSettings settings)
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
  cut_variants_ = hapticut::cut_variants(materials_);
  const auto material_count = static_cast<std::int32_t>(materials_.size());
  models_.resize(2 * static_cast<std::size_t>(mesh_.tet_count()));
  for (std::int32_t t = 0; t < mesh_.tet_count(); ++t) {
    if (mesh_.material(t) >= material_count) {
      throw MeshError("tet " + std::to_string(t) + " refers to material " +
                          std::to_string(mesh_.material(t)) + ", not defined (" +
                          std::to_string(material_count) + " materials)",
                      t);
    }
    const std::int32_t own = mesh_.material(t);
    models_[2 * static_cast<std::size_t>(t)] = materials_[own].model;
    models_[2 * static_cast<std::size_t>(t) + 1] = materials_[cut_variants_[own]].model;
  }
  for (const Material& m : materials_)
    uses_speed_ = uses_speed_ || m.model == MaterialModel::Viscous;
  runtime_settings_.stiffness_N_per_mm = settings_.stiffness_N_per_mm;
  runtime_settings_.max_transitions_per_tick = settings_.max_transitions_per_tick;
  runtime_settings_.capped_tick_force_N = settings_.capped_tick_force_N;
  runtime_settings_.force_shading = settings_.force_shading;
  Aabb box;
  for (const Vec3& v : mesh_.vertices()) box.grow(v);
  const double margin = kWorkspaceMargin * norm(box.hi - box.lo);
  workspace_ = {box.lo - Vec3{margin, margin, margin}, box.hi + Vec3{margin, margin, margin}};
}

std::shared_ptr<const Space> Space::create(TetMesh mesh, std::vector<Material> materials,
                                           EngineSettings settings) {
  return std::make_shared<const Space>(Key{}, std::move(mesh), std::move(materials), settings);
}

std::shared_ptr<const Space> Space::from_scene(const Scene& scene) {
  check_safety_limits(scene.safety);
  EngineSettings settings;
  settings.stiffness_N_per_mm = scene.stiffness_N_per_mm;
  settings.servo_rate_Hz = scene.servo_rate_Hz;
  settings.max_transitions_per_tick = scene.max_transitions_per_tick;
  settings.capped_tick_force_N = scene.safety.capped_tick_force_N;
  return create(TetMesh(scene.vertices_mm, scene.tets, scene.tet_materials, scene.tolerance_mm),
                scene.materials, settings);
}

std::shared_ptr<const Space> owner_of(const Space& space) { return space.shared_from_this(); }

}  // namespace hapticut
