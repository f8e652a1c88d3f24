#include "devices/device_factory.h"

#include <arpa/inet.h>
#include <netinet/in.h>

#include <exception>

#include "devices/replay_device.h"
#include "devices/sim_device.h"
#include "devices/viewport_device.h"
#ifdef HAPTICUT_WITH_DEVICES
#include "devices/bridge_device.h"
#include "devices/dhd_device.h"
#include "devices/hd_device.h"
#include "devices/hid_device.h"
#endif

namespace hapticut::servo {

namespace {

#ifdef HAPTICUT_WITH_DEVICES
// The hid and bridge factories throw std::invalid_argument, ProfileError or
// std::runtime_error; the servo reports a DeviceError naming the binding.
template <typename Make>
std::unique_ptr<Device> as_device_error(const DeviceSpec& spec, Make make) {
  try {
    return make();
  } catch (const DeviceError&) {
    throw;
  } catch (const std::exception& e) {
    throw DeviceError(spec.describe() + ": " + e.what());
  }
}

std::unique_ptr<Device> make_hid(const DeviceSpec& spec, const DeviceContext& /*context*/) {
  return as_device_error(spec, [&] { return make_hid_device(spec.value, spec.options); });
}

std::unique_ptr<Device> make_bridge(const DeviceSpec& spec, const DeviceContext& context) {
  if (!spec.value.empty()) {
    throw DeviceError(spec.describe() + ": bridge: option '" + spec.value + "' is not key=value");
  }
  // Bridge datagrams carry no token: beyond loopback, any host could steer the
  // blade. Only the operator may open that, on a servo that asks for a token.
  const auto bind = spec.options.find("bind");
  in_addr address{};
  if (bind != spec.options.end() && inet_pton(AF_INET, bind->second.c_str(), &address) == 1 &&
      (ntohl(address.s_addr) >> 24) != 127 && !context.remote_bridge_allowed) {
    throw DeviceError(spec.describe() + ": bind=" + bind->second +
                      ": a bridge binds only to loopback (127.x.x.x) unless the servo's own "
                      "command line gives the address (--device) and a token (--token-file)");
  }
  return as_device_error(spec, [&] { return make_bridge_device(spec.options); });
}

std::unique_ptr<Device> make_forcedimension(const DeviceSpec& spec, const DeviceContext& context) {
  // The device firmware's watchdog is set to the servo's own (as far as it goes).
  return as_device_error(spec, [&]() -> std::unique_ptr<Device> {
    return make_dhd_device(spec.value, spec.options, context.watchdog_s);
  });
}

std::unique_ptr<Device> make_openhaptics(const DeviceSpec& spec, const DeviceContext& context) {
  // The scheduler's callback zeroes a loop force older than the servo's own watchdog.
  return as_device_error(
      spec, [&] { return make_hd_device(spec.value, spec.options, context.watchdog_s); });
}
#endif

}  // namespace

const std::vector<DeviceKind>& device_kinds() {
  // One row per backend.
  static const std::vector<DeviceKind> kinds = {
      {"sim", kSimDeviceUsage, make_sim_device},
      {"replay", kReplayDeviceUsage, make_replay_device},
      {"viewport", kViewportDeviceUsage, make_viewport_device},
#ifdef HAPTICUT_WITH_DEVICES
      {"hid", kHidDeviceUsage, make_hid},
      {"bridge", kBridgeDeviceUsage, make_bridge},
      {"forcedimension", kDhdDeviceUsage, make_forcedimension},
      {"openhaptics", kHdDeviceUsage, make_openhaptics},
#endif
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
