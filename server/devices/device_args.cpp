#include "devices/device_args.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hapticut::servo {

std::map<std::string, std::string> parse_device_args(const std::string& args, const char* kind,
                                                     const std::vector<std::string>& known_keys) {
  std::map<std::string, std::string> out;
  std::size_t start = 0;
  while (start < args.size()) {
    std::size_t end = args.find(',', start);
    if (end == std::string::npos) end = args.size();
    const std::string pair = args.substr(start, end - start);
    start = end + 1;
    if (pair.empty()) continue;
    const std::size_t equals = pair.find('=');
    if (equals == std::string::npos || equals == 0) {
      throw std::invalid_argument(std::string(kind) + ": option '" + pair + "' is not key=value");
    }
    const std::string key = pair.substr(0, equals);
    if (std::find(known_keys.begin(), known_keys.end(), key) == known_keys.end()) {
      std::string known;
      for (const std::string& k : known_keys) known += (known.empty() ? "" : ", ") + k;
      std::string message = kind;
      message += ": unknown option '" + key;
      message += "' (known: " + known;
      message += ")";
      throw std::invalid_argument(message);
    }
    if (out.count(key) != 0) {
      throw std::invalid_argument(std::string(kind) + ": option '" + key + "' given twice");
    }
    out[key] = pair.substr(equals + 1);
  }
  return out;
}

double device_arg_number(const std::map<std::string, std::string>& args, const std::string& key,
                         double fallback, const char* kind) {
  const auto found = args.find(key);
  if (found == args.end()) return fallback;
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
