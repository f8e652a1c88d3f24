#include "devices/device_factory.h"

#include "devices/replay_device.h"
#include "devices/sim_device.h"
#include "devices/viewport_device.h"

namespace hapticut::servo {

const std::vector<DeviceKind>& device_kinds() {
  // One row per backend (the HID and UDP-bridge devices add theirs here).
  static const std::vector<DeviceKind> kinds = {
      {"sim", kSimDeviceUsage, make_sim_device},
      {"replay", kReplayDeviceUsage, make_replay_device},
      {"viewport", kViewportDeviceUsage, make_viewport_device},
  };
  return kinds;
}

std::unique_ptr<Device> make_device(const DeviceSpec& spec, const DeviceContext& context) {
  std::string names;
  for (const DeviceKind& kind : device_kinds()) {
    if (spec.kind == kind.name) return kind.make(spec, context);
    names += std::string(names.empty() ? "" : ", ") + kind.name;
  }
  throw DeviceError(spec.describe() + ": unknown device kind '" + spec.kind + "' (known: " + names +
                    ")");
}

std::string device_usage() {
  std::string text;
  for (const DeviceKind& kind : device_kinds()) text += kind.usage;
  return text;
}

}  // namespace hapticut::servo
