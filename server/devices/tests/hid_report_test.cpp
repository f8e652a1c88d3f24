// Report parsing and force encoding from recorded byte sequences.
#include "devices/hid_report.h"

#include <gtest/gtest.h>

#include <vector>

#include "test_profiles.h"

namespace hapticut::servo {
namespace {

ReportOutcome apply(const DeviceProfile& p, const std::vector<std::uint8_t>& bytes,
                    HidInputState& state) {
  return apply_input_report(p.input, bytes.data(), bytes.size(), state);
}

constexpr double kFull = 350.0;

// SpaceNavigator (split layout), as hidraw returns it.
TEST(HidReport, SplitTranslationRotationAndButtonReports) {
  const DeviceProfile p = testing::shipped_profile("spacenavigator");
  HidInputState state;
  // Translation: x = 300, y = -350, z = 94.
  EXPECT_EQ(apply(p, {0x01, 0x2c, 0x01, 0xa2, 0xfe, 0x5e, 0x00}, state), ReportOutcome::Applied);
  EXPECT_DOUBLE_EQ(state.axes[0], 300 / kFull);
  EXPECT_DOUBLE_EQ(state.axes[1], -1.0);
  EXPECT_DOUBLE_EQ(state.axes[2], 94 / kFull);
  // Rotation (about the second axis, as recorded from a real unit: 02 00 00 e2 ff 00 00).
  EXPECT_EQ(apply(p, {0x02, 0x00, 0x00, 0xe2, 0xff, 0x00, 0x00}, state), ReportOutcome::Applied);
  EXPECT_DOUBLE_EQ(state.axes[3], 0.0);
  EXPECT_DOUBLE_EQ(state.axes[4], -30 / kFull);
  EXPECT_DOUBLE_EQ(state.axes[0], 300 / kFull);  // Translation kept from its own report.
  // Buttons: 1, then 2, then both, then none.
  EXPECT_EQ(apply(p, {0x03, 0x01, 0x00}, state), ReportOutcome::Applied);
  EXPECT_EQ(state.buttons, 1U);
  apply(p, {0x03, 0x02, 0x00}, state);
  EXPECT_EQ(state.buttons, 2U);
  apply(p, {0x03, 0x03, 0x00}, state);
  EXPECT_EQ(state.buttons, 3U);
  apply(p, {0x03, 0x00, 0x00}, state);
  EXPECT_EQ(state.buttons, 0U);
}

TEST(HidReport, CombinedReportCarriesAllSixAxes) {
  const DeviceProfile p = testing::shipped_profile("spacemouse-wireless");
  HidInputState state;
  // x 10, y -20, z 350, rx -350, ry 1, rz -1.
  EXPECT_EQ(apply(p, {0x01, 0x0a, 0x00, 0xec, 0xff, 0x5e, 0x01, 0xa2, 0xfe, 0x01, 0x00, 0xff, 0xff},
                  state),
            ReportOutcome::Applied);
  const double expected[6] = {10, -20, 350, -350, 1, -1};
  for (int i = 0; i < 6; ++i) EXPECT_DOUBLE_EQ(state.axes[i], expected[i] / kFull) << i;
}

TEST(HidReport, OutOfRangeAxesAreClamped) {
  const DeviceProfile p = testing::shipped_profile("spacemouse-wireless");
  HidInputState state;
  // x 1000, y -32768, z 351.
  apply(p, {0x01, 0xe8, 0x03, 0x00, 0x80, 0x5f, 0x01, 0, 0, 0, 0, 0, 0}, state);
  EXPECT_DOUBLE_EQ(state.axes[0], 1.0);
  EXPECT_DOUBLE_EQ(state.axes[1], -1.0);
  EXPECT_DOUBLE_EQ(state.axes[2], 1.0);
}

TEST(HidReport, TruncatedUnknownAndShortReportsAreRefused) {
  const DeviceProfile wireless = testing::shipped_profile("spacemouse-wireless");
  HidInputState state;
  state.axes[0] = 0.5;
  // A combined report read with a 7-byte buffer: refused, not half-read.
  EXPECT_EQ(apply(wireless, {0x01, 0x2c, 0x01, 0xa2, 0xfe, 0x5e, 0x00}, state),
            ReportOutcome::WrongLength);
  EXPECT_EQ(apply(wireless, {0x17, 0x01, 0x02}, state), ReportOutcome::UnknownReport);
  EXPECT_EQ(apply(wireless, {}, state), ReportOutcome::UnknownReport);
  EXPECT_DOUBLE_EQ(state.axes[0], 0.5);  // Untouched.
  // Bigger models send longer button reports; their profiles accept them.
  const DeviceProfile pro = testing::shipped_profile("spacemouse-pro");
  EXPECT_EQ(apply(pro, {0x03, 0x00, 0x41, 0x00, 0x00}, state), ReportOutcome::Applied);
  EXPECT_EQ(state.buttons, (1U << 8) | (1U << 14));
}

TEST(HidReport, CompactAcceptsBothLayouts) {
  const DeviceProfile p = testing::shipped_profile("spacemouse-compact");
  HidInputState state;
  EXPECT_EQ(apply(p, {0x01, 0x5e, 0x01, 0, 0, 0, 0}, state), ReportOutcome::Applied);
  EXPECT_DOUBLE_EQ(state.axes[0], 1.0);
  EXPECT_EQ(apply(p, {0x01, 0, 0, 0, 0, 0, 0, 0x5e, 0x01, 0, 0, 0, 0}, state),
            ReportOutcome::Applied);
  EXPECT_DOUBLE_EQ(state.axes[0], 0.0);
  EXPECT_DOUBLE_EQ(state.axes[3], 1.0);
}

TEST(HidReport, DeviceAxesBecomeToolFrameAxes) {
  // SpaceMouse: x right, y towards the user, z down -> tool x right, y away, z up.
  const DeviceProfile p = testing::shipped_profile("spacemouse-wireless");
  HidInputState state;
  state.axes = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6};
  const ToolFrameAxes tool = to_tool_frame(p.input, state);
  EXPECT_EQ(tool.translation, (Vec3{0.1, -0.2, -0.3}));
  EXPECT_EQ(tool.rotation, (Vec3{0.4, -0.5, -0.6}));
}

TEST(HidReport, PositionReportAndForceReportOfAProfileDescribedDevice) {
  const DeviceProfile p = testing::force_device_profile();
  HidInputState state;
  // x = 12.5 mm, y = -0.001 mm, z = 300 mm (clamped to 200).
  EXPECT_EQ(apply(p, {0x01, 0xd4, 0x30, 0x00, 0x00, 0xff, 0xff, 0xff, 0xff, 0xe0, 0x93, 0x04, 0x00},
                  state),
            ReportOutcome::Applied);
  EXPECT_DOUBLE_EQ(state.axes[0], 12.5);
  EXPECT_DOUBLE_EQ(state.axes[1], -0.001);
  EXPECT_DOUBLE_EQ(state.axes[2], 200.0);
  EXPECT_EQ(apply(p, {0x02, 0x01}, state), ReportOutcome::Applied);
  EXPECT_EQ(state.buttons, 1U);

  std::array<std::uint8_t, kHidReportBufferBytes> out{};
  // 0.25 N -> 250 mN, -1.5 N -> -1500 mN, 9 N -> 9000 mN clamped to 4000.
  ASSERT_EQ(encode_output_report(p.output, {0.25, -1.5, 9.0}, {}, out), 7U);
  const std::vector<std::uint8_t> expected{0x05, 0xfa, 0x00, 0x24, 0xfa, 0xa0, 0x0f};
  EXPECT_EQ(std::vector<std::uint8_t>(out.begin(), out.begin() + 7), expected);
  // NaN never reaches the device.
  encode_output_report(p.output, {NAN, 1.0, 0.0}, {}, out);
  EXPECT_EQ(out[1], 0);
  EXPECT_EQ(out[2], 0);
  // An input-only profile writes nothing.
  EXPECT_EQ(
      encode_output_report(testing::shipped_profile("spacenavigator").output, {1, 1, 1}, {}, out),
      0U);
}

TEST(HidReport, BigEndianAndUnsignedFields) {
  ReportField field;
  field.byte_offset = 1;
  field.width_bytes = 2;
  field.little_endian = false;
  field.is_signed = false;
  const std::uint8_t bytes[] = {0x00, 0xff, 0x01};
  EXPECT_EQ(read_raw_field(field, bytes), 65281.0);
  field.is_signed = true;
  EXPECT_EQ(read_raw_field(field, bytes), -255.0);
}

}  // namespace
}  // namespace hapticut::servo
