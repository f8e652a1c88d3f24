// The options of the hid and bridge devices: the key=value pairs after
// `--device NAME=hid:` or `bridge:` (the servo's own parser splits the
// binding; make_hid_device and make_bridge_device take the pairs as a map).
#pragma once

#include <map>
#include <string>
#include <vector>

namespace hapticut::servo {

using DeviceOptions = std::map<std::string, std::string>;

// "key=value,key=value" -> pairs; a bare first value (no '=') is returned in
// `bare` ("hid:spacemouse-wireless,mode=position"). Throws
// std::invalid_argument naming the device kind and the bad pair.
DeviceOptions parse_device_options(const std::string& text, const char* kind, std::string& bare);

// Throws std::invalid_argument naming the first key not in `known`
// ("hid: unknown option 'prof' (known: profile, path, ...)").
void check_device_options(const DeviceOptions& options, const char* kind,
                          const std::vector<std::string>& known);

// The option as a number; `fallback` when absent; std::invalid_argument naming it when not one.
double device_option_number(const DeviceOptions& options, const std::string& key, double fallback,
                            const char* kind);

}  // namespace hapticut::servo
