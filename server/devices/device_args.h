// DeviceSpec: one `--device NAME=KIND:ARGS` binding, parsed.
//   NAME  the blade it drives (may be left out when the scene has one blade)
//   KIND  a row of the device table (device_factory.cpp)
//   ARGS  comma-separated: an optional first bare value (a file, a built-in
//         name), then key=value options, e.g. sim:stroke.json,fail_at_s=0.2
#pragma once

#include <initializer_list>
#include <map>
#include <stdexcept>
#include <string>

namespace hapticut::servo {

// A bad binding or option; the message names the binding and the option.
class DeviceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct DeviceSpec {
  std::string text;   // As given, for messages.
  std::string blade;  // "" when left out.
  std::string kind;
  std::string value;  // The bare first argument, "" when none.
  std::map<std::string, std::string> options;

  bool has(const std::string& key) const { return options.count(key) != 0; }
  // The option as a number; `fallback` when absent; DeviceError when not a finite number.
  double number(const std::string& key, double fallback) const;
  std::string string(const std::string& key, const std::string& fallback) const;
  // DeviceError naming the first option not in `known`.
  void check_options(std::initializer_list<const char*> known) const;
  std::string describe() const;  // "device 'scalpel=sim:...'" for messages.
};

// Throws DeviceError when the text has no kind or an option is malformed.
DeviceSpec parse_device_spec(const std::string& text);

}  // namespace hapticut::servo
