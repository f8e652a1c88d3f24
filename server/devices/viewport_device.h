// The viewport device: tool poses sent by a client over the control channel
// (a knife dragged in Blender's viewport). No force output. The newest pose
// holds while it is younger than the timeout; an older one is a lost device.
#pragma once

#include <memory>

#include "devices/device_args.h"
#include "devices/device_factory.h"
#include "rt/latest_value.h"

namespace hapticut::servo {

inline constexpr const char* kViewportDeviceUsage =
    "  viewport[:timeout_ms=MS]            poses from the control channel's \"pose\"\n"
    "      message; lost when the newest is older than MS (default: --watchdog-ms)\n";

// Input only: no force output, no limits.
inline DeviceLimits viewport_device_limits() { return {}; }

class ViewportDevice : public Device {
 public:
  explicit ViewportDevice(double timeout_s) : timeout_s_(timeout_s) {}

  const char* kind() const override { return "viewport"; }
  DeviceLimits limits() const override { return viewport_device_limits(); }
  DeviceStatus read(double now_s, DeviceSample& sample) override;
  void write(const Vec3& /*force_N*/, const Vec3& /*torque_N_mm*/) override {}

  // Network thread: a new pose (time stamped on arrival).
  void push(const Pose& pose, std::uint32_t buttons, double now_s);

 private:
  double timeout_s_;
  LatestValue<DeviceSample> latest_;
  std::uint64_t pushed_ = 0;  // Network thread only.
};

std::unique_ptr<Device> make_viewport_device(const DeviceSpec& spec, const DeviceContext& context);

}  // namespace hapticut::servo
