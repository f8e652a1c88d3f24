#include "hapticut/space.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "hapticut/material.h"

namespace hapticut {

void RuntimeSettings::validate() const {
  if (!(std::isfinite(stiffness_N_per_mm) && stiffness_N_per_mm > 0.0)) {
    throw std::invalid_argument("stiffness_N_per_mm must be finite and > 0, got " +
                                std::to_string(stiffness_N_per_mm));
  }
  if (max_transitions_per_tick < 1 || max_transitions_per_tick > kMaxTransitionsPerTick) {
    throw std::invalid_argument("max_transitions_per_tick must be in 1.." +
                                std::to_string(kMaxTransitionsPerTick) + ", got " +
                                std::to_string(max_transitions_per_tick));
  }
  if (!(std::isfinite(capped_tick_force_N) && capped_tick_force_N >= 0.0)) {
    throw std::invalid_argument("capped_tick_force_N must be finite and >= 0, got " +
                                std::to_string(capped_tick_force_N));
  }
  if (blade_transition_budget < 0) {
    throw std::invalid_argument("blade_transition_budget must be >= 0 (0: automatic), got " +
                                std::to_string(blade_transition_budget));
  }
}

Space::Space(Key /*key*/, TetMesh mesh, std::vector<Material> materials, EngineSettings settings)
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
  runtime_settings_.stiffness_N_per_mm = settings_.stiffness_N_per_mm;
  runtime_settings_.max_transitions_per_tick =
      std::min(settings_.max_transitions_per_tick, RuntimeSettings::kMaxTransitionsPerTick);
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
  EngineSettings settings;
  settings.stiffness_N_per_mm = scene.stiffness_N_per_mm;
  settings.servo_rate_Hz = scene.servo_rate_Hz;
  settings.max_transitions_per_tick = scene.safety.max_transitions_per_tick;
  settings.capped_tick_force_N = scene.safety.capped_tick_force_N;
  return create(TetMesh(scene.vertices_mm, scene.tets, scene.tet_materials, scene.tolerance_mm),
                scene.materials, settings);
}

std::shared_ptr<const Space> owner_of(const Space& space) { return space.shared_from_this(); }

}  // namespace hapticut
