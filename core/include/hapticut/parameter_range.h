// The range of one number the engine accepts (a material parameter or an
// engine setting): finite, with a lower bound (inclusive or exclusive) and an
// upper bound, so that every value in range keeps the physics meaningful.
// The engine checks these itself (Space, TetMesh, materials); the scene
// readers check the same ranges with the same wording (docs/decisions.md).
#pragma once

#include <string>
#include <string_view>

namespace hapticut {

struct ParameterRange {
  std::string_view name;  // As in the scene file ("stiffness_N_per_mm").
  std::string_view unit;  // "mm", "N", "N/mm", "N s/mm", "Hz", "s", "N/N" (a ratio), "" (a count).
  double minimum = 0.0;
  bool minimum_exclusive = true;  // true: value > minimum; false: value >= minimum.
  double maximum = 0.0;           // Inclusive.
  double default_value = 0.0;
  std::string_view summary;  // One line, for help texts and the add-on.
};

enum class RangeViolation { None, NotFinite, BelowMinimum, AboveMaximum };

// Whether the value lies in the range (NaN fails every comparison); inline for
// checks on the hot path (RuntimeSettings::valid).
constexpr bool in_range(const ParameterRange& range, double value) {
  const bool above_minimum =
      range.minimum_exclusive ? value > range.minimum : value >= range.minimum;
  return above_minimum && value <= range.maximum;
}

RangeViolation range_violation(const ParameterRange& range, double value);

// A bound as both readers print it (C's "%g": 1000, 0.001, 1e+06).
std::string format_bound(double bound);
// A value as the engine prints it: the shortest text that reads back the same
// double ("0.1", "nan", "-inf", "1e+308").
std::string format_value(double value);

// "" when in range, else the reason: "not a finite number", "must be > 0, got
// -0.5", "must be <= 1000, got 5000" (the value printed with `value_text`).
std::string range_reason(const ParameterRange& range, double value, std::string_view value_text);
std::string range_reason(const ParameterRange& range, double value);

// Throws std::invalid_argument("<what>: <reason>") unless the value is in range.
void check_in_range(const ParameterRange& range, double value, std::string_view what);

// The one table of every number's range and default: the engine's settings
// here, the material parameters below. Default member initialisers (Scene,
// SafetyLimits, EngineSettings, RuntimeSettings, Material, the servo's
// SafetySettings) and the Python dataclasses (scenefile/model.py, through
// hapticut._core) read their defaults from it; the JSON Schema is checked
// against it by tests/python/test_material_table.py.

// The engine's settings (scene file: coupling, tolerance_mm, safety).
namespace setting_range {

inline constexpr ParameterRange kStiffness{
    "stiffness_N_per_mm",
    "N/mm",
    0.0,
    true,
    100.0,
    0.1,
    "coupling k in f = k (q - p), eq. (15); a haptic device renders a few N/mm at most"};
inline constexpr ParameterRange kServoRate{
    "servo_rate_Hz",
    "Hz",
    0.0,
    true,
    100000.0,
    1000.0,
    "servo ticks per second (haptic loops run at 0.5 to 10 kHz)"};
// 0 derives the tolerance from the mesh size (1e-9 x its bounding-box diagonal).
// The walk may sink 100 tolerances into rigid material (docs/decisions.md):
// 0.1 um keeps that at 10 um, below what a haptic device resolves.
inline constexpr ParameterRange kTolerance{
    "tolerance_mm",
    "mm",
    0.0,
    false,
    0.0001,
    0.0,
    "tolerance of the geometric tests; 0 derives it from the mesh size"};
inline constexpr ParameterRange kMaxForce{
    "max_force_N", "N", 0.0, true, 100.0, 5.0, "clamp on the summed blade force"};
inline constexpr ParameterRange kMaxTorque{"max_torque_N_mm",
                                           "N mm",
                                           0.0,
                                           true,
                                           100000.0,
                                           500.0,
                                           "clamp on the torque about the tool origin"};
inline constexpr ParameterRange kRampTime{
    "ramp_time_s", "s", 0.0, false, 60.0, 0.5, "force ramp after start or after a fault"};
inline constexpr ParameterRange kMaxTransitions{
    "max_transitions_per_tick",
    "",
    1.0,
    false,
    10000.0,
    64.0,
    "cap on one proxy's transitions in one tick (bounded work per tick)"};
inline constexpr ParameterRange kCappedTickForce{
    "capped_tick_force_N", "N", 0.0, true, 100.0, 1.0, "per-point force limit on a capped tick"};

}  // namespace setting_range

// The material parameters (scene file: materials; material_table.h says which
// model takes which). Upper bounds: a drag or viscous lag beyond a metre, a
// viscosity giving more than 1 kN at 0.1 m/s, a membrane needing more than
// 100 N to break are not tissue; they only overflow the physics. The lower
// bound is exclusive: a zero would make the model the free one under another
// name.
namespace material_range {

inline constexpr ParameterRange kDragDistance{
    "drag_distance_mm",
    "mm",
    0.0,
    true,
    1000.0,
    1.0,
    "the proxy trails the device point by at most this (eq. 16)"};
inline constexpr ParameterRange kViscosity{"viscosity_N_s_per_mm",
                                           "N s/mm",
                                           0.0,
                                           true,
                                           10.0,
                                           0.001,
                                           "resistance c in f = c v at stroke speed v"};
inline constexpr ParameterRange kMaxLag{
    "max_lag_mm", "mm", 0.0, true, 1000.0, 50.0, "cap on the speed-dependent lag c v / k"};
inline constexpr ParameterRange kBreakForce{
    "break_force_N",
    "N",
    0.0,
    true,
    100.0,
    1.0,
    "rigid until the push k |p - q| exceeds this, then free"};
// Friction at a rigid blade's contacts (docs/decisions.md, "Friction at rigid
// contacts"): 0 is the frictionless surface. Beyond 2 no tissue grips steel.
inline constexpr ParameterRange kStaticFriction{
    "static_friction",
    "N/N",
    0.0,
    false,
    2.0,
    0.0,
    "a rigid blade held on this material stays put until the pull along it exceeds this times "
    "the push"};
inline constexpr ParameterRange kDynamicFriction{
    "dynamic_friction",
    "N/N",
    0.0,
    false,
    2.0,
    0.0,
    "while it slides, the pull along it this times the push (at most the static friction)"};

}  // namespace material_range

// A count's default as the int its field holds (the table keeps doubles).
constexpr int default_count(const ParameterRange& range) {
  return static_cast<int>(range.default_value);
}

}  // namespace hapticut
