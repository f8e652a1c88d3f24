#include "devices/device_options.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hapticut::servo {

DeviceOptions parse_device_options(const std::string& text, const char* kind, std::string& bare) {
  DeviceOptions out;
  bare.clear();
  std::size_t start = 0;
  bool first = true;
  while (start < text.size()) {
    std::size_t end = text.find(',', start);
    if (end == std::string::npos) end = text.size();
    const std::string pair = text.substr(start, end - start);
    start = end + 1;
    const bool was_first = first;
    first = false;
    if (pair.empty()) continue;
    const std::size_t equals = pair.find('=');
    if (equals == std::string::npos && was_first) {
      bare = pair;
      continue;
    }
    if (equals == std::string::npos || equals == 0) {
      throw std::invalid_argument(std::string(kind) + ": option '" + pair + "' is not key=value");
    }
    const std::string key = pair.substr(0, equals);
    if (out.count(key) != 0) {
      throw std::invalid_argument(std::string(kind) + ": option '" + key + "' given twice");
    }
    out[key] = pair.substr(equals + 1);
  }
  return out;
}

void check_device_options(const DeviceOptions& options, const char* kind,
                          const std::vector<std::string>& known) {
  for (const auto& entry : options) {
    if (std::find(known.begin(), known.end(), entry.first) != known.end()) continue;
    std::string names;
    for (const std::string& k : known) {
      if (!names.empty()) names += ", ";
      names += k;
    }
    std::string message = kind;
    message += ": unknown option '" + entry.first;
    message += "' (known: " + names;
    message += ")";
    throw std::invalid_argument(message);
  }
}

double device_option_number(const DeviceOptions& options, const std::string& key, double fallback,
                            const char* kind) {
  const auto found = options.find(key);
  if (found == options.end()) return fallback;
  std::size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(found->second, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != found->second.size() || !std::isfinite(value)) {
    throw std::invalid_argument(std::string(kind) + ": option '" + key + "=" + found->second +
                                "' is not a number");
  }
  return value;
}

}  // namespace hapticut::servo
