// Reading input reports and writing output reports as a profile describes
// them: small pure functions on bytes, tested with recorded reports. No
// allocation: the HID device calls them for every report it drains.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "devices/profile.h"
#include "hapticut/vec3.h"

namespace hapticut::servo {

// Every report is read into a buffer this big: reading fewer bytes would
// truncate a long report (a 13-byte combined SpaceMouse report read with 7).
inline constexpr std::size_t kHidReportBufferBytes = 64;

// What the reports said so far: split layouts fill it one report at a time.
struct HidInputState {
  std::array<double, kDeviceAxisCount> axes{};  // Scaled, device frame (profile's axis order).
  std::uint32_t buttons = 0;
};

enum class ReportOutcome : std::uint8_t {
  Applied,        // A described report: its axes and buttons are in the state.
  UnknownReport,  // No report with this id is described (ignored, counted).
  WrongLength,    // The id is described, but for other lengths (rejected, counted).
};

// Reads one report (as hidapi returns it: the id first when numbered) into `state`.
ReportOutcome apply_input_report(const InputProfile& profile, const std::uint8_t* bytes,
                                 std::size_t length, HidInputState& state);

// The raw field as an integer (no clamping or scaling).
double read_raw_field(const ReportField& field, const std::uint8_t* bytes);

// Translation (x, y, z) and rotation (rx, ry, rz) in the tool frame, through the profile's
// matrices.
struct ToolFrameAxes {
  Vec3 translation;
  Vec3 rotation;
};
ToolFrameAxes to_tool_frame(const InputProfile& profile, const HidInputState& state);

// Encodes force (N) and torque (N mm), tool frame, as the output report.
// Returns the bytes written to `out` (profile.length), 0 for an input-only profile.
std::size_t encode_output_report(const OutputProfile& profile, const Vec3& force_N,
                                 const Vec3& torque_N_mm,
                                 std::array<std::uint8_t, kHidReportBufferBytes>& out);

}  // namespace hapticut::servo
