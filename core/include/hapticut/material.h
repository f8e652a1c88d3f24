// The materials (their models and parameters) and their move function, eq. (1): given the target p'
// and the current proxy q, decide whether and where the proxy moves. Pure functions: the same
// inputs give the same output, and q' always lies on the segment [q, p'] so
// FACE and EDGE motion stays on its constraint (docs/method.md).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "hapticut/parameter_range.h"
#include "hapticut/vec3.h"

namespace hapticut {

class CutState;

// The move function a material applies (docs/method.md, "The material's move
// function"). Names match the scene file's "model" strings.
enum class MaterialModel : std::uint8_t { Free, Drag, Rigid, Viscous, Membrane };

struct Material {
  std::string name;
  MaterialModel model = MaterialModel::Free;
  double drag_distance_mm = 0.0;      // Drag: the proxy trails its target by at most this.
  double viscosity_N_s_per_mm = 0.0;  // Viscous: resistance c in f = c v.
  // Viscous: cap on the speed-dependent lag (optional in a file: the table's default).
  double max_lag_mm = material_range::kMaxLag.default_value;
  double break_force_N = 0.0;  // Membrane: rigid until k|p'-q| exceeds this.
  // Rigid: friction at a rigid blade's contacts, static and dynamic.
  double static_friction = material_range::kStaticFriction.default_value;
  double dynamic_friction = material_range::kDynamicFriction.default_value;
  // Cut memory (docs/decisions.md, "Cut memory"): the name of the material of
  // the scene a tet of this one acts as once a blade has cut it; empty: a cut
  // tet stays as it is. Only a cuttable material (drag, viscous, membrane) has
  // one, and it names a material that is not rigid (cut_to_problem).
  std::string cut_to{};
};

// What a move may depend on besides p' and q; fixed for the whole tick so a
// tick's transitions see one consistent material.
struct MoveContext {
  // k, for the membrane's push k|p'-q|.
  double stiffness_N_per_mm = setting_range::kStiffness.default_value;
  double target_speed_mm_per_s = 0.0;  // Speed of the device point this tick (viscous).
  double tolerance_mm = 1e-9;          // docs/method.md, repair 5: not moved if |p'-q| < D + eps.
  // The tets cut so far (cut_state.h), for the walk's lookup of the material
  // a tet acts as (Space::material_of_tet); null: nothing is cut. The move
  // function itself does not read it.
  const CutState* cuts = nullptr;
};

struct MoveResult {
  bool moved = false;
  Vec3 q;  // q' (equal to q when not moved).
};

// move() for the models with a resistance (drag, viscous, membrane).
MoveResult move_with_resistance(const Material& material, const Vec3& target, const Vec3& q,
                                const MoveContext& context);

// Free: q' = p'. Drag (16): the proxy trails p' by at most D. Rigid (17):
// never moves. Viscous: drag whose lag D = c v / k grows with the stroke
// speed v, so the force k D equals the viscous resistance c v (capped at
// max_lag_mm). Membrane: rigid until the push k|p'-q| exceeds break_force_N,
// then free. The free and rigid cases, which the walk calls most, are inline.
inline MoveResult move(const Material& material, const Vec3& target, const Vec3& q,
                       const MoveContext& context) {
  if (material.model == MaterialModel::Free) return {true, target};
  if (material.model == MaterialModel::Rigid) return {false, q};
  return move_with_resistance(material, target, q, context);
}

// The lag distance below which the material holds the proxy (drag-like
// models), or a negative number for models without one.
double lag_distance_mm(const Material& material, const MoveContext& context);

inline bool is_rigid(const Material& material) { return material.model == MaterialModel::Rigid; }

// Whether a blade cuts a tet of this model (and a cut_to is allowed on it):
// the materials that resist without being rigid. As core/hapticut/cut_surface.py's
// CUTTABLE_MODELS.
inline bool is_cuttable(MaterialModel model) {
  return model == MaterialModel::Drag || model == MaterialModel::Viscous ||
         model == MaterialModel::Membrane;
}

// Why material `index`'s cut_to is wrong among `materials`, or "" when it is
// fine (empty, or on a cuttable material naming a material of the list that
// is not rigid, and following cut_to from there never leads back to it). The
// scene reader puts the reason under the field's path; Space::create throws it.
std::string cut_to_problem(const std::vector<Material>& materials, std::size_t index);
// For each material, the index of the material its tets act as once cut (its
// own index when it has no cut_to). Throws std::invalid_argument naming the
// material for the first cut_to_problem.
std::vector<std::int32_t> cut_variants(const std::vector<Material>& materials);

// Throws std::invalid_argument naming the material, the parameter and the value
// unless every parameter of its model is in the table's range
// (material_table.h); the parameters of other models are not read.
void validate_material(const Material& material);

}  // namespace hapticut
