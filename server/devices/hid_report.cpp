#include "devices/hid_report.h"

#include <algorithm>
#include <cmath>

namespace hapticut::servo {
namespace {

Vec3 multiply(const std::array<std::array<double, 3>, 3>& m, const Vec3& v) {
  return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
          m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
          m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
}

void write_raw_field(const ReportField& field, std::int64_t raw, std::uint8_t* bytes) {
  const auto value = static_cast<std::uint64_t>(raw);
  for (int i = 0; i < field.width_bytes; ++i) {
    const int shift = 8 * (field.little_endian ? i : field.width_bytes - 1 - i);
    bytes[field.byte_offset + i] = static_cast<std::uint8_t>((value >> shift) & 0xffU);
  }
}

}  // namespace

double read_raw_field(const ReportField& field, const std::uint8_t* bytes) {
  std::uint64_t value = 0;
  for (int i = 0; i < field.width_bytes; ++i) {
    const int shift = 8 * (field.little_endian ? i : field.width_bytes - 1 - i);
    value |= static_cast<std::uint64_t>(bytes[field.byte_offset + i]) << shift;
  }
  const int bits = 8 * field.width_bytes;
  if (field.is_signed && (value >> (bits - 1)) != 0U) {
    return static_cast<double>(static_cast<std::int64_t>(value) - (std::int64_t{1} << bits));
  }
  return static_cast<double>(value);
}

ReportOutcome apply_input_report(const InputProfile& profile, const std::uint8_t* bytes,
                                 std::size_t length, HidInputState& state) {
  if (length == 0) return ReportOutcome::UnknownReport;
  bool id_known = false;
  for (const InputReport& report : profile.reports) {
    // Unnumbered reports (id 0) carry no id byte: recognised by length alone.
    if (report.report_id != 0 && bytes[0] != report.report_id) continue;
    id_known = true;
    const auto expected = static_cast<std::size_t>(report.length);
    if (length != expected && !(report.accept_longer && length > expected)) continue;
    for (const AxisField& axis : report.axes) {
      const double raw = std::clamp(read_raw_field(axis.field, bytes), axis.field.logical_min,
                                    axis.field.logical_max);
      state.axes[static_cast<int>(axis.axis)] = raw * axis.field.scale;
    }
    if (!report.buttons.empty()) {
      std::uint32_t buttons = 0;
      for (const ButtonBit& button : report.buttons) {
        if ((bytes[button.byte_offset] >> button.bit) & 1U) buttons |= 1U << button.index;
      }
      state.buttons = buttons;
    }
    return ReportOutcome::Applied;
  }
  return id_known ? ReportOutcome::WrongLength : ReportOutcome::UnknownReport;
}

ToolFrameAxes to_tool_frame(const InputProfile& profile, const HidInputState& state) {
  const Vec3 translation{state.axes[0], state.axes[1], state.axes[2]};
  const Vec3 rotation{state.axes[3], state.axes[4], state.axes[5]};
  return {multiply(profile.translation_matrix, translation),
          multiply(profile.rotation_matrix, rotation)};
}

std::size_t encode_output_report(const OutputProfile& profile, const Vec3& force_N,
                                 const Vec3& torque_N_mm,
                                 std::array<std::uint8_t, kHidReportBufferBytes>& out) {
  if (!profile.has_report) return 0;
  out.fill(0);
  out[0] = static_cast<std::uint8_t>(profile.report_id);
  const std::array<double, 6> values{force_N.x,     force_N.y,     force_N.z,
                                     torque_N_mm.x, torque_N_mm.y, torque_N_mm.z};
  for (const OutputField& field : profile.fields) {
    double value = values[static_cast<int>(field.component)] * field.field.scale;
    // NaN never reaches the device: it encodes as zero.
    if (!std::isfinite(value)) value = 0.0;
    value = std::clamp(std::round(value), field.field.logical_min, field.field.logical_max);
    write_raw_field(field.field, static_cast<std::int64_t>(value), out.data());
  }
  return static_cast<std::size_t>(profile.length);
}

}  // namespace hapticut::servo
