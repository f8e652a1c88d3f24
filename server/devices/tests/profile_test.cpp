#include "devices/profile.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include "test_profiles.h"

namespace hapticut::servo {
namespace {

// A minimal valid profile, edited by each error case.
std::string minimal(const std::string& input_report, const std::string& output = "\"none\"") {
  return R"({"name": "t", "model": "T", "match": {"vendor_id": "0x256f", "product_ids": ["0xc62e"]},
    "input": {"kind": "deflection", "reports": [)" +
         input_report + R"(]}, "output": )" + output + R"(,
    "limits": {"max_force_N": 0, "max_torque_N_mm": 0, "max_stiffness_N_per_mm": 0,
               "workspace_min_mm": [-1, -1, -1], "workspace_max_mm": [1, 1, 1]}})";
}
const std::string kGoodReport =
    R"({"report_id": 1, "length": 7, "axes": [{"axis": "x", "byte_offset": 1, "width": 2,
        "logical_min": -350, "logical_max": 350}]})";

std::string error_of(const std::string& text) {
  try {
    parse_profile(text, "t.json");
  } catch (const ProfileError& error) {
    return error.what();
  }
  return "";
}

TEST(Profile, EveryShippedProfileLoadsUnderItsOwnName) {
  const std::vector<DeviceProfile> profiles = load_profiles(HAPTICUT_PROFILE_DIR);
  ASSERT_GE(profiles.size(), 6U);
  std::set<std::string> names;
  for (const DeviceProfile& p : profiles) {
    EXPECT_EQ(std::filesystem::path(p.source).stem().string(), p.name);
    EXPECT_TRUE(names.insert(p.name).second) << p.name;
    EXPECT_FALSE(p.limits.has_force_output) << p.name;  // Every SpaceMouse is input only.
    EXPECT_EQ(p.input.kind, InputKind::Deflection);
  }
}

TEST(Profile, SplitAndCombinedLayoutsAreDescribed) {
  const DeviceProfile navigator = testing::shipped_profile("spacenavigator");
  EXPECT_EQ(navigator.match.vendor_id, 0x046d);
  EXPECT_EQ(navigator.match.product_ids.front(), 0xc626);
  ASSERT_EQ(navigator.input.reports.size(), 3U);
  EXPECT_EQ(navigator.input.reports[0].length, 7);
  EXPECT_EQ(navigator.input.reports[1].axes[0].axis, DeviceAxis::Rx);
  const DeviceProfile wireless = testing::shipped_profile("spacemouse-wireless");
  EXPECT_EQ(wireless.match.vendor_id, 0x256f);
  EXPECT_EQ(wireless.input.reports[0].length, 13);
  EXPECT_EQ(wireless.input.reports[0].axes.size(), 6U);
}

TEST(Profile, ForceDeviceProfileHasItsOutputAndLimits) {
  const DeviceProfile p = testing::force_device_profile();
  EXPECT_TRUE(p.limits.has_force_output);
  EXPECT_EQ(p.limits.max_force_N, 4.0);
  EXPECT_EQ(p.limits.max_stiffness_N_per_mm, 2.0);
  ASSERT_TRUE(p.output.has_report);
  EXPECT_EQ(p.output.fields.size(), 3U);
  EXPECT_EQ(p.match.usage_page, 0xff00);
}

TEST(Profile, ErrorsNameTheFile) {
  EXPECT_EQ(error_of(minimal(kGoodReport)), "");
  EXPECT_NE(error_of("{").find("t.json: not JSON"), std::string::npos);
}

TEST(Profile, ErrorsNameTheField) {
  const struct {
    std::string text;
    std::string message;
  } cases[] = {
      {R"({"model": "T"})", "t.json: /name: missing"},
      {minimal(R"({"report_id": 1, "length": 7, "axes": [{"axis": "x", "byte_offset": 1,
          "width": 3, "logical_min": 0, "logical_max": 1}]})"),
       "t.json: /input/reports/0/axes/0/width: must be 1, 2 or 4 bytes"},
      {minimal(R"({"report_id": 1, "length": 7, "axes": [{"axis": "x", "byte_offset": 6,
          "width": 2, "logical_min": 0, "logical_max": 1}]})"),
       "t.json: /input/reports/0/axes/0/byte_offset: field ends at byte 8, past the report's "
       "length 7"},
      {minimal(R"({"report_id": 1, "length": 7, "axes": [{"axis": "w", "byte_offset": 1,
          "width": 2, "logical_min": 0, "logical_max": 1}]})"),
       "t.json: /input/reports/0/axes/0/axis: \"w\" is not one of x, y, z, rx, ry, rz"},
      {minimal(R"({"report_id": 1, "length": 7, "axes": [{"axis": "x", "byte_offset": 1,
          "width": 1, "logical_min": -300, "logical_max": 1}]})"),
       "t.json: /input/reports/0/axes/0/logical_min: must be in [-128, 127], is -300"},
      {minimal(R"({"report_id": 1, "length": 7, "colour": 1, "axes": []})"),
       "t.json: /input/reports/0/colour: unknown field"},
      {minimal(R"({"report_id": 1, "length": 7})"), "t.json: /input/reports/0: has neither axes"},
      {minimal(kGoodReport + "," + kGoodReport), "t.json: /input/reports/1: a report with id 1"},
      {minimal(kGoodReport, R"("some")"), "t.json: /output: must be \"none\" or an output report"},
      {minimal(kGoodReport, R"({"report_id": 5, "length": 3, "fields": [{"component": "fx",
          "byte_offset": 0, "width": 2, "logical_min": -10, "logical_max": 10}]})"),
       "t.json: /output/fields/0/byte_offset: byte 0 holds the report id"},
      {minimal(kGoodReport, R"({"report_id": 5, "length": 3, "fields": [{"component": "fx",
          "byte_offset": 1, "width": 2, "logical_min": -10, "logical_max": 10}]})"),
       "t.json: /limits/max_force_N: must be positive for a device with force output"},
  };
  for (const auto& c : cases) {
    const std::string message = error_of(c.text);
    EXPECT_EQ(message.rfind(c.message, 0), 0U) << "got: " << message << "\nwanted: " << c.message;
  }
  std::string bad_id = minimal(kGoodReport);
  bad_id.replace(bad_id.find("\"0x256f\""), 8, "\"vendor\"");
  EXPECT_EQ(error_of(bad_id), "t.json: /match/vendor_id: must be a 16-bit id like \"0x046d\"");
}

TEST(Profile, MatchesByVendorProductSerialInterfaceAndUsagePage) {
  DeviceProfile p = testing::shipped_profile("spacemouse-wireless");
  HidInterfaceId id{0x256f, 0xc62f, "S1", 0, 0x01};
  EXPECT_TRUE(profile_matches(p, id));
  id.product_id = 0xc635;
  EXPECT_FALSE(profile_matches(p, id));
  id.product_id = 0xc62e;
  p.match.serial = "S2";
  EXPECT_FALSE(profile_matches(p, id));
  p.match.serial = "S1";
  p.match.usage_page = 0xff00;
  EXPECT_FALSE(profile_matches(p, id));
  p.match.usage_page.reset();
  p.match.interface_number = 1;
  EXPECT_FALSE(profile_matches(p, id));
}

TEST(Profile, DirectoryIsFoundOrTheErrorSaysWhereItLooked) {
  EXPECT_EQ(find_profile_directory(HAPTICUT_PROFILE_DIR), HAPTICUT_PROFILE_DIR);
  try {
    find_profile_directory("/nonexistent/profiles");
    FAIL();
  } catch (const ProfileError& error) {
    EXPECT_NE(std::string(error.what()).find("/nonexistent/profiles"), std::string::npos);
  }
}

}  // namespace
}  // namespace hapticut::servo
