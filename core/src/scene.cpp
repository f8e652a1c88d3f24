#include "hapticut/scene.h"

#include "hapticut/parameter_range.h"

namespace hapticut {

const char* material_model_name(MaterialModel model) {
  switch (model) {
    case MaterialModel::Free:
      return "free";
    case MaterialModel::Drag:
      return "drag";
    case MaterialModel::Rigid:
      return "rigid";
    case MaterialModel::Viscous:
      return "viscous";
    case MaterialModel::Membrane:
      return "membrane";
  }
  return "unknown";
}

const char* blade_coupling_name(BladeCoupling coupling) {
  return coupling == BladeCoupling::Rigid ? "rigid" : "independent";
}

const char* blade_orientation_name(BladeOrientation orientation) {
  return orientation == BladeOrientation::Locked ? "locked" : "free";
}

std::optional<BladeCoupling> blade_coupling_from_name(std::string_view name) {
  for (const BladeCoupling coupling : {BladeCoupling::Rigid, BladeCoupling::Independent}) {
    if (name == blade_coupling_name(coupling)) return coupling;
  }
  return std::nullopt;
}

std::optional<BladeOrientation> blade_orientation_from_name(std::string_view name) {
  for (const BladeOrientation orientation : {BladeOrientation::Free, BladeOrientation::Locked}) {
    if (name == blade_orientation_name(orientation)) return orientation;
  }
  return std::nullopt;
}

void check_safety_limits(const SafetyLimits& limits) {
  check_in_range(setting_range::kMaxForce, limits.max_force_N, "max_force_N");
  check_in_range(setting_range::kMaxTorque, limits.max_torque_N_mm, "max_torque_N_mm");
  check_in_range(setting_range::kRampTime, limits.ramp_time_s, "ramp_time_s");
  check_in_range(setting_range::kCappedTickForce, limits.capped_tick_force_N,
                 "capped_tick_force_N");
}

}  // namespace hapticut
