// Space: a TetMesh with the materials its tets refer to and the engine's
// settings. Proxies and blades step inside one Space; it never changes after
// construction, so any number of proxies may share it.
//
// Who owns a Space (docs/decisions.md): a Space is neither copyable nor
// movable and exists only behind a std::shared_ptr<const Space> made by
// Space::create or Space::from_scene. Every Proxy, Blade and ForceShading keeps
// such a pointer, so the Space lives as long as the last of them: loading a
// new scene while proxies of the old one exist leaves no dangling pointer.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "hapticut/aabb_tree.h"
#include "hapticut/cut_state.h"
#include "hapticut/geometry.h"
#include "hapticut/material.h"
#include "hapticut/parameter_range.h"
#include "hapticut/scene.h"
#include "hapticut/tet_mesh.h"

namespace hapticut {

// The scene's settings, fixed with the Space.
// Defaults: parameter_range.h (setting_range).
struct EngineSettings {
  double stiffness_N_per_mm = setting_range::kStiffness.default_value;
  double servo_rate_Hz = setting_range::kServoRate.default_value;
  int max_transitions_per_tick = default_count(setting_range::kMaxTransitions);
  double capped_tick_force_N = setting_range::kCappedTickForce.default_value;
  bool force_shading = false;  // Default of RuntimeSettings::force_shading.
};

// Settings per tick (docs/decisions.md, "Settings per tick"): what a servo may
// change between ticks without rebuilding the Space. Passed by value to
// Proxy::step and Blade::step; the overloads without it use
// Space::runtime_settings(), the scene's own values. Plain data, trivially
// copyable, so a servo can hand it between threads through a sequence lock.
struct RuntimeSettings {
  // k of eq. (15); > 0.
  double stiffness_N_per_mm = setting_range::kStiffness.default_value;
  // Per proxy per tick (>= 1); exact (see Proxy::step).
  int max_transitions_per_tick = default_count(setting_range::kMaxTransitions);
  // Per-point force limit on an unfinished tick.
  double capped_tick_force_N = setting_range::kCappedTickForce.default_value;
  bool force_shading = false;  // Blade: shade its force (ForceShading).
  // Blade: total transitions over all its points in one tick (docs/decisions.md,
  // "Work budget per tick"); 0 means kDefaultTransitionsPerPoint per point.
  int blade_transition_budget = 0;

  static constexpr int kDefaultTransitionsPerPoint = 16;
  // Whether every field is in its range (parameter_range.h, setting_range: the
  // same ranges the scene file is checked against; budget >= 0). A tick given
  // settings out of range is rejected (zero force, counted).
  bool valid() const {
    return in_range(setting_range::kStiffness, stiffness_N_per_mm) &&
           in_range(setting_range::kMaxTransitions, max_transitions_per_tick) &&
           in_range(setting_range::kCappedTickForce, capped_tick_force_N) &&
           blade_transition_budget >= 0;
  }
  // Throws std::invalid_argument naming the first field out of range.
  void validate() const;
  // The budget a blade of `points` points gets under these settings.
  int blade_budget(int points) const {
    return blade_transition_budget > 0 ? blade_transition_budget
                                       : kDefaultTransitionsPerPoint * points;
  }
};

class Space : public std::enable_shared_from_this<Space> {
  struct Key {};  // Only create() constructs a Space, always behind a shared_ptr.

 public:
  // Throws MeshError if a tet refers to a material that does not exist.
  static std::shared_ptr<const Space> create(TetMesh mesh, std::vector<Material> materials,
                                             EngineSettings settings = {});
  static std::shared_ptr<const Space> from_scene(const Scene& scene);

  Space(Key, TetMesh mesh, std::vector<Material> materials, EngineSettings settings);
  Space(const Space&) = delete;
  Space(Space&&) = delete;
  Space& operator=(const Space&) = delete;
  Space& operator=(Space&&) = delete;
  ~Space() = default;

  const TetMesh& mesh() const { return mesh_; }
  const std::vector<Material>& materials() const { return materials_; }
  // The material tet t acts as now (docs/decisions.md, "Cut memory"): its
  // own, or, once `cuts` has it cut, its material's cut variant (cut_to; the
  // material itself without one). cuts null: nothing is cut. The one
  // definition the walk, the rigid edge's walls and its probes ask.
  const Material& material_of_tet(std::int32_t t, const CutState* cuts) const {
    const std::int32_t own = mesh_.material(t);
    return materials_[cut_byte(t, cuts) != 0 ? cut_variants_[own] : own];
  }
  // The model of the material tet t acts as now, from two bytes a tet (its
  // own model's, its cut variant's), side by side: the walk asks it per step.
  MaterialModel tet_model(std::int32_t t, const CutState* cuts) const {
    return models_[2 * static_cast<std::size_t>(t) + cut_byte(t, cuts)];
  }
  // The model of tet t's own material, cut or not (what decides that it is cut).
  MaterialModel own_model(std::int32_t t) const { return models_[2 * static_cast<std::size_t>(t)]; }
  // Whether tet t is bone. A cut never changes it: no rigid material has a
  // cut_to, and none is one (cut_to_problem).
  bool tet_is_rigid(std::int32_t t) const { return own_model(t) == MaterialModel::Rigid; }
  // For each material, the index of its cut variant (its own without a cut_to).
  const std::vector<std::int32_t>& cut_variants() const { return cut_variants_; }
  // TetMesh::prefetch_tet and the tet's model bytes.
  void prefetch_tet(std::int32_t t) const {
    mesh_.prefetch_tet(t);
    __builtin_prefetch(&models_[2 * static_cast<std::size_t>(t)]);
  }
  // prefetch_tet for every tet round tet t's local edge, all at once: the EDGE
  // step's loop over the fan would wait for each in turn (its branches depend
  // on them). A FACE slide asks as it reaches the edge.
  void prefetch_edge_fan(std::int32_t t, int local_edge) const {
    for (const EdgeFanEntry& entry : mesh_.edge_fan_of(t, local_edge)) prefetch_tet(entry.tet);
  }
  // Whether any material needs the device point's speed (viscous).
  bool uses_speed() const { return uses_speed_; }
  const EngineSettings& settings() const { return settings_; }
  // The scene's values as settings per tick (the caps clamped into range).
  const RuntimeSettings& runtime_settings() const { return runtime_settings_; }
  double tolerance() const { return mesh_.tolerance(); }

  // The workspace: the mesh's bounding box enlarged on every side by
  // kWorkspaceMargin x its diagonal. A device point outside it is a device
  // fault (docs/decisions.md, "Absurd device samples"): Proxy::step and
  // Blade::step reject it (zero force, state kept, counted).
  static constexpr double kWorkspaceMargin = 10.0;
  const Aabb& workspace() const { return workspace_; }
  bool in_workspace(const Vec3& p) const { return box_holds(workspace_, p); }

 private:
  static std::size_t cut_byte(std::int32_t t, const CutState* cuts) {
    return cuts != nullptr ? cuts->cut(t) : 0;
  }

  TetMesh mesh_;
  std::vector<Material> materials_;
  // Two a tet: models_[2 t] its own material's, models_[2 t + 1] its cut variant's.
  std::vector<MaterialModel> models_;
  std::vector<std::int32_t> cut_variants_;
  bool uses_speed_ = false;
  EngineSettings settings_;
  RuntimeSettings runtime_settings_;
  Aabb workspace_;
};

// The std::shared_ptr owning `space`: every Space has one (see create).
std::shared_ptr<const Space> owner_of(const Space& space);

}  // namespace hapticut
