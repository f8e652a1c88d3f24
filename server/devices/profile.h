// DeviceProfile: what a HID device is and how to read and drive it, as data
// (one JSON file per model in core/hapticut/devices/profiles/, checked by
// core/hapticut/devices/profile.schema.json). Parsing names the offending
// field ("spacemouse-wireless.json: /input/reports/0/axes/2/width: ...").
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "devices/device.h"

namespace hapticut::servo {

class ProfileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// How to find the device among the enumerated HID interfaces.
struct ProfileMatch {
  std::uint16_t vendor_id = 0;
  std::vector<std::uint16_t> product_ids;   // Any of these (cabled and receiver ids of one model).
  std::optional<std::string> serial;        // Only this unit.
  std::optional<int> interface_number;      // Only this USB interface.
  std::optional<std::uint16_t> usage_page;  // Only this HID usage page (1: generic desktop).
};

// The six device axes, in the order of the profile's "axis" names.
enum class DeviceAxis : std::uint8_t { X, Y, Z, Rx, Ry, Rz };
inline constexpr int kDeviceAxisCount = 6;

// One integer field of a report.
struct ReportField {
  int byte_offset = 0;  // From the first byte hidapi returns (the report id when numbered).
  int width_bytes = 2;  // 1, 2 or 4.
  bool is_signed = true;
  bool little_endian = true;
  double logical_min = -350.0;  // Raw values are clamped to [min, max] ...
  double logical_max = 350.0;
  double scale = 1.0 / 350.0;  // ... then multiplied by this.
};

struct AxisField {
  DeviceAxis axis = DeviceAxis::X;
  ReportField field;
};

struct ButtonBit {
  int byte_offset = 1;
  int bit = 0;    // 0 = least significant.
  int index = 0;  // Bit of DeviceSample::buttons it sets (0-15).
};

// One input report layout: recognised by its id and its length.
struct InputReport {
  int report_id = 1;           // First byte; 0 for devices without numbered reports (no id byte).
  int length = 7;              // Bytes hidapi returns for it, id included.
  bool accept_longer = false;  // Also accept longer reports (button reports of bigger models).
  std::vector<AxisField> axes;
  std::vector<ButtonBit> buttons;  // A report that carries buttons sets them all (others 0).
};

// What the axes mean after scaling.
enum class InputKind : std::uint8_t {
  Deflection,  // A puck's deflection in [-1, 1] (SpaceMouse): pose_mapping makes a pose of it.
  Position,    // The tool position (mm) and rotation (rad) of a positional device.
};

struct InputProfile {
  InputKind kind = InputKind::Deflection;
  std::vector<InputReport> reports;
  // Device axes to the tool frame: translation' = M_t (x, y, z), rotation' = M_r (rx, ry, rz).
  std::array<std::array<double, 3>, 3> translation_matrix{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  std::array<std::array<double, 3>, 3> rotation_matrix{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
};

// Force and torque components an output report carries.
enum class OutputComponent : std::uint8_t { Fx, Fy, Fz, Tx, Ty, Tz };

struct OutputField {
  OutputComponent component = OutputComponent::Fx;
  // Tool-frame N (force) or N mm (torque) times scale gives the raw value,
  // rounded and clamped to [logical_min, logical_max].
  ReportField field;
};

struct OutputProfile {
  bool has_report = false;  // false: "none", an input-only device.
  int report_id = 0;
  int length = 0;  // Bytes written, id included.
  std::vector<OutputField> fields;
};

// How a deflection device becomes a pose (pose_mapping.h): the profile's defaults.
struct MappingDefaults {
  bool rate_control = true;                  // false: position control.
  double dead_zone = 0.05;                   // Fraction of full deflection ignored.
  double translation_gain_mm_per_s = 150.0;  // Rate control: full deflection speed.
  double rotation_gain_rad_per_s = 1.5;
  double translation_range_mm = 40.0;  // Position control: full deflection offset.
  double rotation_range_rad = 0.6;
  int engage_button = 0;  // DeviceSample button index toggling engage; -1: none.
  int rehome_button = 1;  // Button index re-homing the pose; -1: none.
};

struct DeviceProfile {
  std::string name;    // Unique id, the file name without .json ("spacemouse-wireless").
  std::string model;   // Human-readable model name.
  std::string source;  // Where it was read from (for messages).
  ProfileMatch match;
  InputProfile input;
  OutputProfile output;
  MappingDefaults mapping;
  DeviceLimits limits;
};

// Parses one profile; `source` names it in errors. Throws ProfileError
// "<source>: <json pointer>: <reason>".
DeviceProfile parse_profile(const std::string& json_text, const std::string& source);
DeviceProfile load_profile(const std::string& path);
// Every *.json in `directory`, sorted by name. Throws ProfileError on the first bad file.
std::vector<DeviceProfile> load_profiles(const std::string& directory);

// The shipped profiles' directory: `explicit_directory` if given, else
// $HAPTICUT_PROFILE_DIR, else devices/profiles next to or above the running
// executable (the installed package), else the source tree's. Throws
// ProfileError listing where it looked.
std::string find_profile_directory(const std::string& explicit_directory = "");

// The enumerated interface a profile may match.
struct HidInterfaceId {
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::string serial;
  int interface_number = -1;
  std::uint16_t usage_page = 0;
};
bool profile_matches(const DeviceProfile& profile, const HidInterfaceId& id);

}  // namespace hapticut::servo
