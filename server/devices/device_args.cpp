#include "devices/device_args.h"

#include <cmath>
#include <cstdlib>
#include <cstring>

namespace hapticut::servo {

double DeviceSpec::number(const std::string& key, double fallback) const {
  const auto found = options.find(key);
  if (found == options.end()) return fallback;
  const char* text_value = found->second.c_str();
  char* end = nullptr;
  const double value = std::strtod(text_value, &end);
  if (end == text_value || *end != '\0' || !std::isfinite(value)) {
    throw DeviceError(describe() + ": option " + key + "='" + found->second +
                      "' is not a finite number");
  }
  return value;
}

std::string DeviceSpec::string(const std::string& key, const std::string& fallback) const {
  const auto found = options.find(key);
  return found == options.end() ? fallback : found->second;
}

void DeviceSpec::check_options(std::initializer_list<const char*> known) const {
  for (const auto& [key, value] : options) {
    bool ok = false;
    for (const char* k : known) ok = ok || key == k;
    if (!ok) {
      std::string list;
      for (const char* k : known) list += std::string(list.empty() ? "" : ", ") + k;
      throw DeviceError(describe() + ": unknown option '" + key + "' (" + kind +
                        " takes: " + (list.empty() ? "none" : list) + ")");
    }
  }
}

std::string DeviceSpec::describe() const { return "device '" + text + "'"; }

DeviceSpec parse_device_spec(const std::string& text) {
  DeviceSpec spec;
  spec.text = text;
  const std::size_t colon = text.find(':');
  std::string head = text.substr(0, colon);
  const std::string args = colon == std::string::npos ? "" : text.substr(colon + 1);
  const std::size_t equals = head.find('=');
  if (equals != std::string::npos) {
    spec.blade = head.substr(0, equals);
    head = head.substr(equals + 1);
    if (spec.blade.empty()) throw DeviceError(spec.describe() + ": empty blade name before '='");
  }
  spec.kind = head;
  if (spec.kind.empty()) {
    throw DeviceError(spec.describe() + ": no device kind (expected NAME=KIND:ARGS)");
  }
  std::size_t start = 0;
  bool first = true;
  while (start <= args.size() && !args.empty()) {
    const std::size_t comma = args.find(',', start);
    const std::string item =
        args.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos) {
      if (!first || item.empty()) {
        throw DeviceError(spec.describe() + ": '" + item +
                          "' is not key=value (only the first argument may be bare)");
      }
      spec.value = item;
    } else {
      const std::string key = item.substr(0, eq);
      if (key.empty()) throw DeviceError(spec.describe() + ": option with no name: '" + item + "'");
      if (spec.options.count(key) != 0) {
        throw DeviceError(spec.describe() + ": option '" + key + "' given twice");
      }
      spec.options[key] = item.substr(eq + 1);
    }
    first = false;
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return spec;
}

}  // namespace hapticut::servo
