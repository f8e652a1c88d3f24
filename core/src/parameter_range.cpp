#include "hapticut/parameter_range.h"

#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace hapticut {

RangeViolation range_violation(const ParameterRange& range, double value) {
  if (!std::isfinite(value)) return RangeViolation::NotFinite;
  const bool above_minimum =
      range.minimum_exclusive ? value > range.minimum : value >= range.minimum;
  if (!above_minimum) return RangeViolation::BelowMinimum;
  if (!(value <= range.maximum)) return RangeViolation::AboveMaximum;
  return RangeViolation::None;
}

std::string format_bound(double bound) {
  std::array<char, 32> text{};
  std::snprintf(text.data(), text.size(), "%g", bound);
  return text.data();
}

std::string format_value(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  std::array<char, 32> text{};
  const auto result = std::to_chars(text.data(), text.data() + text.size(), value);
  return {text.data(), result.ptr};
}

std::string range_reason(const ParameterRange& range, double value, std::string_view value_text) {
  switch (range_violation(range, value)) {
    case RangeViolation::None:
      return {};
    case RangeViolation::NotFinite:
      return "not a finite number";
    case RangeViolation::BelowMinimum:
      return std::string(range.minimum_exclusive ? "must be > " : "must be >= ") +
             format_bound(range.minimum) + ", got " + std::string(value_text);
    case RangeViolation::AboveMaximum:
      return "must be <= " + format_bound(range.maximum) + ", got " + std::string(value_text);
  }
  return {};
}

std::string range_reason(const ParameterRange& range, double value) {
  return range_reason(range, value, format_value(value));
}

void check_in_range(const ParameterRange& range, double value, std::string_view what) {
  const std::string reason = range_reason(range, value);
  if (!reason.empty()) throw std::invalid_argument(std::string(what) + ": " + reason);
}

}  // namespace hapticut
