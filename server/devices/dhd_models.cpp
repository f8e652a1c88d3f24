#include "devices/dhd_models.h"

#include <array>

#include "devices/dhd_api.h"

namespace hapticut::servo {
namespace {

// One row per model family and hand; the limits are the cautious defaults of dhd_models.h.
constexpr std::array<DhdModel, 16> kModels = {{
    {dhd::kDeviceOmega3, "omega.3", false, 6.0, 3.0, 120.0},
    {dhd::kDeviceOmega6Right, "omega.6 (right)", true, 6.0, 3.0, 120.0},
    {dhd::kDeviceOmega6Left, "omega.6 (left)", true, 6.0, 3.0, 120.0},
    {dhd::kDeviceOmega7Right, "omega.7 (right)", true, 6.0, 3.0, 120.0},
    {dhd::kDeviceOmega7Left, "omega.7 (left)", true, 6.0, 3.0, 120.0},
    {dhd::kDeviceDelta3, "delta.3", false, 10.0, 3.0, 260.0},
    {dhd::kDeviceSigma3, "sigma.3", false, 10.0, 3.0, 150.0},
    {dhd::kDeviceSigma7Right, "sigma.7 (right)", true, 10.0, 3.0, 150.0},
    {dhd::kDeviceSigma7Left, "sigma.7 (left)", true, 10.0, 3.0, 150.0},
    {dhd::kDeviceLambda3, "lambda.3", false, 10.0, 3.0, 180.0},
    {dhd::kDeviceLambda7Right, "lambda.7 (right)", true, 10.0, 3.0, 180.0},
    {dhd::kDeviceLambda7Left, "lambda.7 (left)", true, 10.0, 3.0, 180.0},
    {dhd::kDeviceFalcon, "Novint Falcon", false, 4.0, 1.0, 80.0},
    {dhd::kDeviceController, "Force Dimension controller", false, 2.0, 1.0, 300.0},
    {dhd::kDeviceControllerHr, "Force Dimension controller (HR)", false, 2.0, 1.0, 300.0},
    {dhd::kDeviceCustom, "custom DHD device", false, 2.0, 1.0, 300.0},
}};

}  // namespace

DhdModel dhd_model(int system_type) {
  for (const DhdModel& model : kModels) {
    if (model.system_type == system_type) return model;
  }
  return DhdModel{};
}

DeviceLimits dhd_model_limits(const DhdModel& model) {
  DeviceLimits limits;
  limits.has_force_output = true;
  limits.max_force_N = model.max_force_N;
  limits.max_torque_N_mm = 0.0;
  limits.max_stiffness_N_per_mm = model.max_stiffness_N_per_mm;
  const double h = model.workspace_half_mm;
  limits.workspace_min_mm = {-h, -h, -h};
  limits.workspace_max_mm = {h, h, h};
  return limits;
}

}  // namespace hapticut::servo
