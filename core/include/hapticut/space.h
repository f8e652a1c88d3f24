// Space: a TetMesh with the materials its tets refer to and the engine's
// settings. Proxies and blades step inside one Space; it never changes after
// construction, so any number of proxies may share it.
#pragma once

#include <vector>

#include "hapticut/scene.h"
#include "hapticut/tet_mesh.h"

namespace hapticut {

struct EngineSettings {
  double stiffness_N_per_mm = 0.1;
  double servo_rate_Hz = 1000.0;
  int max_transitions_per_tick = 64;
  double capped_tick_force_N = 1.0;
};

class Space {
 public:
  // Throws MeshError if a tet refers to a material that does not exist.
  Space(TetMesh mesh, std::vector<Material> materials, EngineSettings settings = {});
  static Space from_scene(const Scene& scene);

  const TetMesh& mesh() const { return mesh_; }
  const std::vector<Material>& materials() const { return materials_; }
  const Material& material_of_tet(std::int32_t t) const { return materials_[mesh_.material(t)]; }
  bool tet_is_rigid(std::int32_t t) const { return rigid_[t] != 0; }
  // Whether any material needs the device point's speed (viscous).
  bool uses_speed() const { return uses_speed_; }
  const EngineSettings& settings() const { return settings_; }
  double tolerance() const { return mesh_.tolerance(); }

 private:
  TetMesh mesh_;
  std::vector<Material> materials_;
  std::vector<std::uint8_t> rigid_;
  bool uses_speed_ = false;
  EngineSettings settings_;
};

}  // namespace hapticut
