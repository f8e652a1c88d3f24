#include "devices/viewport_device.h"

namespace hapticut::servo {

DeviceStatus ViewportDevice::read(double now_s, DeviceSample& sample) {
  DeviceSample newest;
  if (latest_.read(newest) == 0) return DeviceStatus::Lost;
  if (now_s - newest.time_s > timeout_s_) return DeviceStatus::Lost;
  sample = newest;
  // The newest pose holds while it is young: a hand resting is not a fault.
  return DeviceStatus::Fresh;
}

void ViewportDevice::push(const Pose& pose, std::uint32_t buttons, double now_s) {
  DeviceSample sample;
  sample.pose = pose;
  sample.buttons = buttons;
  sample.time_s = now_s;
  sample.sequence = ++pushed_;
  latest_.publish(sample);
}

std::unique_ptr<Device> make_viewport_device(const DeviceSpec& spec, const DeviceContext& context) {
  spec.check_options({"timeout_ms"});
  if (!spec.value.empty()) throw DeviceError(spec.describe() + ": viewport takes no file");
  const double timeout_s = spec.number("timeout_ms", context.watchdog_s * 1000.0) / 1000.0;
  if (!(timeout_s > 0.0)) throw DeviceError(spec.describe() + ": timeout_ms must be positive");
  return std::make_unique<ViewportDevice>(timeout_s);
}

}  // namespace hapticut::servo
