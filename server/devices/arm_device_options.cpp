#include "devices/arm_device_options.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace hapticut::servo {

const std::vector<std::string>& arm_device_option_keys() {
  static const std::vector<std::string> keys = {"scale", "offset", "max_force", "max_stiffness"};
  return keys;
}

void parse_arm_device_options(const DeviceOptions& options, const char* kind,
                              ArmDeviceOptions& out) {
  const std::string name = kind;
  out.mapping.scale = device_option_number(options, "scale", 1.0, kind);
  if (!(out.mapping.scale > 0.0) || out.mapping.scale > 100.0) {
    throw std::invalid_argument(name + ": option 'scale' must be in (0, 100]");
  }
  const auto offset = options.find("offset");
  if (offset != options.end()) {
    double xyz[3] = {0, 0, 0};
    char extra = 0;
    if (std::sscanf(offset->second.c_str(), "%lf:%lf:%lf%c", &xyz[0], &xyz[1], &xyz[2], &extra) !=
            3 ||
        !std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2])) {
      throw std::invalid_argument(name + ": option 'offset=" + offset->second +
                                  "' must be X:Y:Z in mm");
    }
    out.mapping.offset_mm = {xyz[0], xyz[1], xyz[2]};
  }
  out.max_force_N = device_option_number(options, "max_force", 0.0, kind);
  out.max_stiffness_N_per_mm = device_option_number(options, "max_stiffness", 0.0, kind);
  if (out.max_force_N < 0.0 || out.max_stiffness_N_per_mm < 0.0 ||
      !std::isfinite(out.max_force_N) || !std::isfinite(out.max_stiffness_N_per_mm)) {
    throw std::invalid_argument(name + ": max_force and max_stiffness must be positive");
  }
}

DeviceLimits with_arm_limit_options(DeviceLimits device, const ArmDeviceOptions& options) {
  if (options.max_force_N > 0.0) device.max_force_N = options.max_force_N;
  if (options.max_stiffness_N_per_mm > 0.0) {
    device.max_stiffness_N_per_mm = options.max_stiffness_N_per_mm;
  }
  return device;
}

}  // namespace hapticut::servo
