// A device's limits as the listing's JSON object (--list-devices --json,
// docs/devices.md): one writer for the HID profiles, the other kinds and the
// vendor libraries' devices (Force Dimension, OpenHaptics).
#pragma once

#include <nlohmann/json.hpp>

#include "devices/device.h"

namespace hapticut::servo {

// has_force_output, max_force_N, max_torque_N_mm, max_stiffness_N_per_mm (as
// stated, for kStiffnessLimitRate_Hz), max_stiffness_stated_rate_Hz,
// max_stiffness_N_per_mm_at_rate (stiffness_limit at rate_Hz),
// workspace_min_mm, workspace_max_mm.
nlohmann::json device_limits_json(const DeviceLimits& limits, double rate_Hz);

}  // namespace hapticut::servo
