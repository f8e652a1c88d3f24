// The table of device kinds: `--device NAME=KIND:ARGS` finds KIND here. A
// new backend is one row in device_factory.cpp: its name, a usage line for
// --help, and the function that makes it from the parsed spec.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "devices/device.h"
#include "devices/device_args.h"
#include "hapticut/scene.h"

namespace hapticut::servo {

// What a backend may need beyond its own arguments.
struct DeviceContext {
  const Scene* scene = nullptr;
  std::string blade;        // The blade the device drives.
  double rate_Hz = 1000.0;  // The loop's rate.
  bool as_fast_as_possible = false;
  double watchdog_s = 0.1;  // A sample older than this is a lost device.
  Vec3 scene_min_mm;        // The scene's bounding box.
  Vec3 scene_max_mm;
  // The device text is the operator's (the command line's) and the servo has
  // a token: a bridge may bind beyond loopback.
  bool remote_bridge_allowed = false;
};

struct DeviceKind {
  const char* name;
  const char* usage;  // One or more lines for --help.
  std::unique_ptr<Device> (*make)(const DeviceSpec& spec, const DeviceContext& context);
};

const std::vector<DeviceKind>& device_kinds();
// Throws DeviceError naming the known kinds when spec.kind is not one of them.
std::unique_ptr<Device> make_device(const DeviceSpec& spec, const DeviceContext& context);
// Every kind's usage, for --help.
std::string device_usage();

}  // namespace hapticut::servo
