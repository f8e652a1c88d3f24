#include "devices/device_limits_json.h"

namespace hapticut::servo {

nlohmann::json device_limits_json(const DeviceLimits& limits, double rate_Hz) {
  const auto xyz = [](const Vec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); };
  return {{"has_force_output", limits.has_force_output},
          {"max_force_N", limits.max_force_N},
          {"max_torque_N_mm", limits.max_torque_N_mm},
          {"max_stiffness_N_per_mm", limits.max_stiffness_N_per_mm},
          {"max_stiffness_stated_rate_Hz", kStiffnessLimitRate_Hz},
          {"max_stiffness_N_per_mm_at_rate", stiffness_limit(limits, rate_Hz)},
          {"workspace_min_mm", xyz(limits.workspace_min_mm)},
          {"workspace_max_mm", xyz(limits.workspace_max_mm)}};
}

}  // namespace hapticut::servo
