// The options every positional arm kind takes after its own first value
// (forcedimension:ID, openhaptics:NAME): scale=S, offset=X:Y:Z (mm),
// max_force=N and max_stiffness=N_PER_MM, and how the two limits replace the
// device's own defaults. One parser, so the kinds refuse and name the same
// mistakes the same way.
#pragma once

#include <string>
#include <vector>

#include "devices/arm_pose_mapping.h"
#include "devices/device_options.h"

namespace hapticut::servo {

struct ArmDeviceOptions {
  ArmPoseMappingSettings mapping;       // Axes from the kind; scale and offset from the text.
  double max_force_N = 0.0;             // > 0: instead of the device's default.
  double max_stiffness_N_per_mm = 0.0;  // > 0: instead of the device's default.
};

// The option keys parse_arm_device_options reads.
const std::vector<std::string>& arm_device_option_keys();

// Reads scale, offset, max_force and max_stiffness into `out` (its axes are
// kept). Throws std::invalid_argument naming `kind` and the option.
void parse_arm_device_options(const DeviceOptions& options, const char* kind,
                              ArmDeviceOptions& out);

// `device` with the options' limits in place of its force and stiffness.
DeviceLimits with_arm_limit_options(DeviceLimits device, const ArmDeviceOptions& options);

}  // namespace hapticut::servo
