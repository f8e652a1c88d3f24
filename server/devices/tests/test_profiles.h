// Shared helpers of the device tests: the shipped and test profiles.
#pragma once

#include <string>

#include "devices/profile.h"

namespace hapticut::servo::testing {

inline DeviceProfile shipped_profile(const std::string& name) {
  return load_profile(std::string(HAPTICUT_PROFILE_DIR) + "/" + name + ".json");
}

inline DeviceProfile force_device_profile() {
  return load_profile(std::string(HAPTICUT_DEVICES_TEST_DATA) + "/example-force-device.json");
}

}  // namespace hapticut::servo::testing
