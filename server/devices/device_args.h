// The ARGS of `--device NAME=KIND:ARGS` for the HID and bridge devices:
// comma-separated key=value pairs ("profile=spacemouse-wireless,mode=position").
#pragma once

#include <map>
#include <string>
#include <vector>

namespace hapticut::servo {

// Throws std::invalid_argument naming the device kind and the bad pair
// ("hid: unknown option 'prof' (known: profile, path, ...)").
std::map<std::string, std::string> parse_device_args(const std::string& args, const char* kind,
                                                     const std::vector<std::string>& known_keys);

// Reads a number option; throws std::invalid_argument naming the key when it is not one.
double device_arg_number(const std::map<std::string, std::string>& args, const std::string& key,
                         double fallback, const char* kind);

}  // namespace hapticut::servo
