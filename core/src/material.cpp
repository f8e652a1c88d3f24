#include "hapticut/material.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "hapticut/material_table.h"

namespace hapticut {

namespace {

// Eq. (16): hold while the target is within D, else trail it at distance D.
MoveResult trail(const Vec3& target, const Vec3& q, double lag_mm, double tolerance_mm) {
  const Vec3 back = q - target;
  const double distance = norm(back);
  // Repair 5 (docs/method.md): "< D + eps" so rounding does not creep q by an ulp each call.
  if (distance < lag_mm + tolerance_mm) return {false, q};
  return {true, target + back * (lag_mm / distance)};
}

}  // namespace

void validate_material(const Material& material) {
  if (static_cast<int>(material.model) > static_cast<int>(MaterialModel::Membrane)) {
    throw std::invalid_argument("material '" + material.name + "': unknown model " +
                                std::to_string(static_cast<int>(material.model)));
  }
  const MaterialModelSpec& spec = material_model_spec(material.model);
  for (const MaterialParameterSpec& parameter : spec.parameters) {
    check_in_range(parameter.range, material.*(parameter.field),
                   "material '" + material.name + "' (" + std::string(spec.name) + ") " +
                       std::string(parameter.range.name));
  }
}

namespace {

std::int64_t material_named(const std::vector<Material>& materials, const std::string& name) {
  for (std::size_t i = 0; i < materials.size(); ++i) {
    if (materials[i].name == name) return static_cast<std::int64_t>(i);
  }
  return -1;
}

}  // namespace

std::string cut_to_problem(const std::vector<Material>& materials, std::size_t index) {
  const Material& material = materials[index];
  if (material.cut_to.empty()) return "";
  if (!is_cuttable(material.model)) {
    return "material '" + material.name + "' is " + material_model_name(material.model) +
           ": only drag, viscous and membrane are cut, so only they take a cut_to";
  }
  const std::int64_t target = material_named(materials, material.cut_to);
  if (target < 0) {
    return "material '" + material.name + "': cut_to names no material of the scene ('" +
           material.cut_to + "')";
  }
  if (materials[target].model == MaterialModel::Rigid) {
    return "material '" + material.name + "': cut_to '" + material.cut_to +
           "' is rigid (a cut never makes a tet rigid)";
  }
  // Follow cut_to from here: back at this material is a cycle (a cut that
  // undoes itself); a chain that ends, or that cycles without it, is this
  // material's own business no longer (the others report their own cycle).
  std::string chain = "'" + material.name + "'";
  std::int64_t at = target;
  for (std::size_t steps = 0; at >= 0 && steps < materials.size(); ++steps) {
    chain += " -> '" + materials[at].name + "'";
    if (static_cast<std::size_t>(at) == index) {
      return "material '" + material.name + "': cut_to makes a cycle (" + chain + ")";
    }
    at = materials[at].cut_to.empty() ? -1 : material_named(materials, materials[at].cut_to);
  }
  return "";
}

std::vector<std::int32_t> cut_variants(const std::vector<Material>& materials) {
  std::vector<std::int32_t> variants(materials.size());
  for (std::size_t i = 0; i < materials.size(); ++i) {
    const std::string problem = cut_to_problem(materials, i);
    if (!problem.empty()) throw std::invalid_argument(problem);
    variants[i] = static_cast<std::int32_t>(materials[i].cut_to.empty()
                                                ? static_cast<std::int64_t>(i)
                                                : material_named(materials, materials[i].cut_to));
  }
  return variants;
}

double lag_distance_mm(const Material& material, const MoveContext& context) {
  switch (material.model) {
    case MaterialModel::Drag:
      return material.drag_distance_mm;
    case MaterialModel::Viscous:
      // Steady state of a proxy dragged at speed v: k D = c v.
      return std::min(material.max_lag_mm, material.viscosity_N_s_per_mm *
                                               context.target_speed_mm_per_s /
                                               context.stiffness_N_per_mm);
    case MaterialModel::Free:
      return 0.0;
    case MaterialModel::Rigid:
    case MaterialModel::Membrane:
      break;
  }
  return -1.0;
}

MoveResult move_with_resistance(const Material& material, const Vec3& target, const Vec3& q,
                                const MoveContext& context) {
  switch (material.model) {
    case MaterialModel::Free:
      return {true, target};
    case MaterialModel::Drag:
    case MaterialModel::Viscous: {
      const double lag = lag_distance_mm(material, context);
      if (lag <= context.tolerance_mm) return {true, target};
      return trail(target, q, lag, context.tolerance_mm);
    }
    case MaterialModel::Rigid:
      return {false, q};
    case MaterialModel::Membrane:
      if (context.stiffness_N_per_mm * norm(target - q) > material.break_force_N) {
        return {true, target};
      }
      return {false, q};
  }
  return {false, q};
}

}  // namespace hapticut
