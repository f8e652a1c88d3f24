// The HID device over a scripted transport (recorded reports, a device that
// vanishes mid-stroke and comes back) and enumeration through real hidapi.
#include "devices/hid_device.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <thread>

#include "scripted_hid_transport.h"
#include "test_profiles.h"

namespace hapticut::servo {
namespace {

using testing::ScriptedHidTransport;
using testing::spacemouse_info;

// Combined SpaceMouse report: six int16 little-endian axes (device frame).
std::vector<std::uint8_t> combined(int x, int y, int z, int rx = 0, int ry = 0, int rz = 0) {
  std::vector<std::uint8_t> bytes{0x01};
  for (int v : {x, y, z, rx, ry, rz}) {
    bytes.push_back(static_cast<std::uint8_t>(v & 0xff));
    bytes.push_back(static_cast<std::uint8_t>((v >> 8) & 0xff));
  }
  return bytes;
}
std::vector<std::uint8_t> buttons(int bits) { return {0x03, static_cast<std::uint8_t>(bits), 0}; }

struct Rig {
  ScriptedHidTransport* transport = nullptr;
  std::unique_ptr<HidDevice> device;
  double now_s = 0.0;

  explicit Rig(const DeviceProfile& profile, bool rate_control = true,
               std::vector<HidDeviceInfo> present = {spacemouse_info("/dev/hidraw3")}) {
    auto scripted = std::make_unique<ScriptedHidTransport>();
    scripted->present = std::move(present);
    transport = scripted.get();
    HidDeviceOptions options = hid_device_options(profile);
    options.io_thread = false;
    options.mapping.rate_control = rate_control;
    device = std::make_unique<HidDevice>(std::move(scripted), std::move(options));
  }
  // One servo tick of dt_s: the I/O pass, then the real-time read.
  DeviceStatus tick(DeviceSample& sample, double dt_s = 0.001) {
    device->pump(0);
    now_s += dt_s;
    return device->read(now_s, sample);
  }
};

TEST(HidDevice, RateControlIntegratesDeflectionIntoThePose) {
  Rig rig(testing::shipped_profile("spacemouse-wireless"));
  rig.device->start();
  EXPECT_EQ(rig.transport->opened_path, "/dev/hidraw3");
  DeviceSample sample;
  // Full deflection towards the user (device +y): the tool moves along -y.
  rig.transport->pending.push_back(combined(0, 350, 0));
  EXPECT_EQ(rig.tick(sample), DeviceStatus::Fresh);
  for (int i = 0; i < 99; ++i) EXPECT_EQ(rig.tick(sample), DeviceStatus::Fresh);
  // 100 ticks of 1 ms at 150 mm/s (the first read has no elapsed time).
  EXPECT_NEAR(sample.pose.position_mm.y, -150.0 * 0.099, 1e-9);
  EXPECT_NEAR(sample.pose.position_mm.x, 0.0, 1e-12);
  // Inside the dead zone (5 %): nothing moves.
  rig.transport->pending.push_back(combined(0, 15, 0));
  const double y = sample.pose.position_mm.y;
  for (int i = 0; i < 50; ++i) rig.tick(sample);
  EXPECT_DOUBLE_EQ(sample.pose.position_mm.y, y);
  EXPECT_EQ(rig.device->counters().reports.load(), 2U);
}

TEST(HidDevice, DrainsEveryPendingReportAndKeepsTheNewest) {
  Rig rig(testing::shipped_profile("spacemouse-wireless"), /*rate_control=*/false);
  rig.device->start();
  for (int x = 10; x <= 350; x += 10) rig.transport->pending.push_back(combined(x, 0, 0));
  rig.transport->pending.push_back({0x17, 0x00});                          // Unknown id.
  rig.transport->pending.push_back({0x01, 0x00, 0x00, 0x00, 0x00, 0x00});  // Truncated.
  DeviceSample sample;
  rig.tick(sample);
  EXPECT_TRUE(rig.transport->pending.empty());
  // Position control: full deflection is the range, 40 mm.
  EXPECT_NEAR(sample.pose.position_mm.x, 40.0, 1e-9);
  EXPECT_EQ(rig.device->counters().reports.load(), 35U);
  EXPECT_EQ(rig.device->counters().unknown_reports.load(), 1U);
  EXPECT_EQ(rig.device->counters().wrong_length.load(), 1U);
}

TEST(HidDevice, PositionControlOffsetsFromHomeAndReturnsWhenLetGo) {
  Rig rig(testing::shipped_profile("spacemouse-wireless"), /*rate_control=*/false);
  rig.device->start();
  DeviceSample sample;
  const int pushes[] = {0, 175, 350, 175, 0};
  const double expected_z[] = {0.0, -40.0 * (0.5 - 0.05) / 0.95, -40.0, -40.0 * (0.45 / 0.95), 0.0};
  for (int i = 0; i < 5; ++i) {
    rig.transport->pending.push_back(combined(0, 0, pushes[i]));  // Pressing down: device +z.
    rig.tick(sample);
    EXPECT_NEAR(sample.pose.position_mm.z, expected_z[i], 1e-9) << i;
  }
}

TEST(HidDevice, EngageButtonTogglesAndRehomeButtonReturnsHome) {
  Rig rig(testing::shipped_profile("spacemouse-wireless"));
  rig.device->start();
  DeviceSample sample;
  rig.transport->pending.push_back(buttons(1));
  rig.tick(sample);
  EXPECT_EQ(sample.buttons, 1U | kEngageRequestBit);
  rig.transport->pending.push_back(buttons(0));
  rig.tick(sample);
  EXPECT_EQ(sample.buttons, kEngageRequestBit);  // Still engaged: a toggle, not a hold.
  rig.transport->pending.push_back(buttons(1));
  rig.tick(sample);
  rig.transport->pending.push_back(buttons(0));
  rig.tick(sample);
  EXPECT_EQ(sample.buttons, 0U);

  // Drift away under rate control, then re-home.
  rig.transport->pending.push_back(combined(350, 0, 0));
  for (int i = 0; i < 100; ++i) rig.tick(sample);
  EXPECT_GT(sample.pose.position_mm.x, 10.0);
  rig.transport->pending.push_back(combined(0, 0, 0));
  rig.transport->pending.push_back(buttons(2));
  rig.tick(sample);
  EXPECT_EQ(sample.pose.position_mm, Vec3{});
}

TEST(HidDevice, PositionControlRehomeIsAClutch) {
  Rig rig(testing::shipped_profile("spacemouse-wireless"), /*rate_control=*/false);
  rig.device->start();
  DeviceSample sample;
  rig.transport->pending.push_back(combined(350, 0, 0));
  rig.tick(sample);
  EXPECT_NEAR(sample.pose.position_mm.x, 40.0, 1e-9);
  rig.transport->pending.push_back(buttons(2));
  rig.tick(sample);
  EXPECT_NEAR(sample.pose.position_mm.x, 40.0, 1e-9);  // Held while the puck is still pushed.
  rig.transport->pending.push_back(combined(0, 0, 0));
  rig.tick(sample);
  EXPECT_NEAR(sample.pose.position_mm.x, 40.0, 1e-9);  // Let go: the new home.
  rig.transport->pending.push_back(combined(350, 0, 0));
  rig.tick(sample);
  EXPECT_NEAR(sample.pose.position_mm.x, 80.0, 1e-9);  // The next push moves on from there.
}

TEST(HidDevice, DisappearsMidStrokeAndComesBackOnAnotherNode) {
  Rig rig(testing::shipped_profile("spacemouse-wireless"));
  rig.device->start();
  DeviceSample sample;
  rig.transport->pending.push_back(combined(350, 0, 0));
  for (int i = 0; i < 50; ++i) ASSERT_EQ(rig.tick(sample), DeviceStatus::Fresh);
  const double x_at_loss = sample.pose.position_mm.x;
  EXPECT_GT(x_at_loss, 5.0);

  // Unplugged mid-stroke: the very next tick says Lost, and the pose stops.
  rig.transport->fail_next_read = true;
  EXPECT_EQ(rig.tick(sample), DeviceStatus::Lost);
  EXPECT_FALSE(rig.device->connected());
  for (int i = 0; i < 20; ++i) EXPECT_EQ(rig.tick(sample), DeviceStatus::Lost);
  EXPECT_DOUBLE_EQ(sample.pose.position_mm.x, x_at_loss);
  EXPECT_EQ(rig.device->counters().disconnects.load(), 1U);

  // Housekeeping while it is away: enumerations that find nothing.
  rig.device->maintain();
  rig.device->maintain();
  EXPECT_EQ(rig.tick(sample), DeviceStatus::Lost);
  EXPECT_EQ(rig.device->counters().reconnect_attempts.load(), 2U);
  EXPECT_NE(rig.device->last_error().find("no device matches profile 'spacemouse-wireless'"),
            std::string::npos);

  // Another unit of the same model is not it.
  rig.transport->present = {spacemouse_info("/dev/hidraw5", 0xc62e, "OTHER")};
  rig.device->maintain();
  EXPECT_FALSE(rig.device->connected());

  // Replugged: same vendor, product and serial, a new hidraw node.
  rig.transport->present.push_back(spacemouse_info("/dev/hidraw7"));
  rig.device->maintain();
  EXPECT_TRUE(rig.device->connected());
  EXPECT_EQ(rig.transport->opened_path, "/dev/hidraw7");
  EXPECT_EQ(rig.device->counters().reconnects.load(), 1U);
  // Fresh again, at rest until the puck reports (nothing held over from before).
  EXPECT_EQ(rig.tick(sample), DeviceStatus::Fresh);
  rig.tick(sample);
  EXPECT_DOUBLE_EQ(sample.pose.position_mm.x, x_at_loss);
  rig.transport->pending.push_back(combined(-350, 0, 0));
  for (int i = 0; i < 10; ++i) rig.tick(sample);
  EXPECT_LT(sample.pose.position_mm.x, x_at_loss);
}

TEST(HidDevice, StartErrorsNameTheProfileOrThePathAndPermission) {
  Rig absent(testing::shipped_profile("spacemouse-wireless"), true, {});
  try {
    absent.device->start();
    FAIL();
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what())
                  .find("no device matches profile 'spacemouse-wireless' (vendor 0x256f, "
                        "product 0xc62e, 0xc62f)"),
              std::string::npos)
        << error.what();
  }
  Rig unreadable(testing::shipped_profile("spacemouse-wireless"));
  unreadable.transport->unreadable_paths = {"/dev/hidraw3"};
  try {
    unreadable.device->start();
    FAIL();
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("/dev/hidraw3: permission denied"), std::string::npos)
        << error.what();
  }
  DeviceSample sample;
  EXPECT_EQ(unreadable.device->read(0.0, sample), DeviceStatus::Lost);
}

TEST(HidDevice, ForceDeviceReadsPositionsAndWritesForceReports) {
  HidDeviceInfo info;
  info.path = "/dev/hidraw9";
  info.vendor_id = 0x1209;
  info.product_id = 0x4841;
  info.usage_page = 0xff00;
  Rig rig(testing::force_device_profile(), true, {info});
  rig.device->start();
  EXPECT_TRUE(rig.device->limits().has_force_output);
  DeviceSample sample;
  EXPECT_EQ(rig.tick(sample), DeviceStatus::Stale);  // Nothing reported yet.
  // Device (12.5, 0, 10) mm -> tool frame through the profile's matrix (tool = M device).
  rig.transport->pending.push_back(
      {0x01, 0xd4, 0x30, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x10, 0x27, 0x00, 0x00});
  EXPECT_EQ(rig.tick(sample), DeviceStatus::Fresh);
  EXPECT_EQ(sample.pose.position_mm, (Vec3{0.0, -12.5, 10.0}));
  EXPECT_EQ(rig.tick(sample), DeviceStatus::Stale);

  // World force (0.5, 1, -2) N -> device frame (M^T f) = (-1, 0.5, -2) N -> mN.
  rig.device->write({0.5, 1.0, -2.0}, {});
  rig.device->pump(0);
  ASSERT_EQ(rig.transport->written.size(), 1U);
  const std::vector<std::uint8_t> expected{0x05, 0x18, 0xfc, 0xf4, 0x01, 0x30, 0xf8};
  EXPECT_EQ(rig.transport->written[0], expected);
  rig.device->pump(0);
  EXPECT_EQ(rig.transport->written.size(), 1U);  // Only a new force is written.

  // Stopping leaves the device pushing nothing.
  rig.device->stop();
  ASSERT_EQ(rig.transport->written.size(), 2U);
  EXPECT_EQ(rig.transport->written[1], (std::vector<std::uint8_t>{5, 0, 0, 0, 0, 0, 0}));
}

TEST(HidDevice, IoThreadDeliversTheNewestState) {
  auto scripted = std::make_unique<ScriptedHidTransport>();
  scripted->present = {spacemouse_info("/dev/hidraw3")};
  scripted->pending = {combined(100, 0, 0), combined(350, 0, 0)};
  HidDeviceOptions options = hid_device_options(testing::shipped_profile("spacemouse-wireless"));
  options.mapping.rate_control = false;
  HidDevice device(std::move(scripted), std::move(options));
  device.start();
  DeviceSample sample;
  for (int i = 0; i < 2000 && device.counters().reports.load() < 2; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ(device.read(1.0, sample), DeviceStatus::Fresh);
  EXPECT_NEAR(sample.pose.position_mm.x, 40.0, 1e-9);
  device.stop();
}

TEST(HidDeviceList, MarksTheDevicesAProfileMatches) {
  ScriptedHidTransport transport;
  HidDeviceInfo keyboard;
  keyboard.path = "/dev/hidraw0";
  keyboard.vendor_id = 0x046d;
  keyboard.product_id = 0xc31c;
  keyboard.product = "USB Keyboard";
  transport.present = {keyboard, spacemouse_info("/dev/hidraw3")};
  const auto rows = list_hid_devices(transport, load_profiles(HAPTICUT_PROFILE_DIR));
  ASSERT_EQ(rows.size(), 2U);
  EXPECT_EQ(rows[0].profile, "");
  EXPECT_EQ(rows[1].profile, "spacemouse-wireless");
  const std::string table = format_hid_device_list(rows);
  EXPECT_NE(table.find("/dev/hidraw3         256f:c62e  0x0001      SpaceMouse Wireless"),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("spacemouse-wireless"), std::string::npos);
  EXPECT_EQ(format_hid_device_list({}), "no HID devices found\n");

  // The same rows as JSON (--list-devices --json), with the profiles and the other kinds.
  DeviceLimits bridge_limits;
  bridge_limits.has_force_output = true;
  bridge_limits.max_force_N = 3.0;
  bridge_limits.max_stiffness_N_per_mm = 1.0;
  // The shipped profiles state no stiffness limit: the test profile with force output does.
  auto profiles = load_profiles(HAPTICUT_PROFILE_DIR);
  profiles.push_back(testing::force_device_profile());
  ASSERT_GT(profiles.back().limits.max_stiffness_N_per_mm, 0.0);
  const auto listing = nlohmann::json::parse(format_device_list_json(
      rows, profiles, {{"bridge", "bridge:port=47810", bridge_limits}}, "profiles/", 250.0));
  EXPECT_EQ(listing["version"], 1);
  EXPECT_EQ(listing["profile_directory"], "profiles/");
  EXPECT_EQ(listing["rate_Hz"], 250.0);
  ASSERT_EQ(listing["devices"].size(), 2U);
  EXPECT_TRUE(listing["devices"][0]["profile"].is_null());
  EXPECT_TRUE(listing["devices"][0]["binding"].is_null());
  EXPECT_EQ(listing["devices"][0]["product"], "USB Keyboard");
  EXPECT_EQ(listing["devices"][1]["path"], "/dev/hidraw3");
  EXPECT_EQ(listing["devices"][1]["vendor_id"], 0x256f);
  EXPECT_EQ(listing["devices"][1]["product_id"], 0xc62e);
  EXPECT_EQ(listing["devices"][1]["serial"], "A1B2");
  EXPECT_EQ(listing["devices"][1]["profile"], "spacemouse-wireless");
  EXPECT_EQ(listing["devices"][1]["binding"], "hid:spacemouse-wireless");
  ASSERT_EQ(listing["profiles"].size(), profiles.size());
  for (std::size_t i = 0; i < profiles.size(); ++i) {
    EXPECT_EQ(listing["profiles"][i]["name"], profiles[i].name);
    EXPECT_EQ(listing["profiles"][i]["binding"], "hid:" + profiles[i].name);
    EXPECT_EQ(listing["profiles"][i]["limits"]["max_force_N"], profiles[i].limits.max_force_N);
    EXPECT_EQ(listing["profiles"][i]["limits"]["has_force_output"],
              profiles[i].limits.has_force_output);
    // The stiffness limit at the listing's rate is the servo's own (stiffness_limit).
    EXPECT_EQ(listing["profiles"][i]["limits"]["max_stiffness_N_per_mm"],
              profiles[i].limits.max_stiffness_N_per_mm);
    EXPECT_EQ(listing["profiles"][i]["limits"]["max_stiffness_N_per_mm_at_rate"],
              stiffness_limit(profiles[i].limits, 250.0));
  }
  EXPECT_DOUBLE_EQ(listing["profiles"].back()["limits"]["max_stiffness_N_per_mm_at_rate"],
                   profiles.back().limits.max_stiffness_N_per_mm / 4);
  ASSERT_EQ(listing["kinds"].size(), 1U);
  EXPECT_EQ(listing["kinds"][0]["binding"], "bridge:port=47810");
  EXPECT_EQ(listing["kinds"][0]["limits"]["max_force_N"], 3.0);
  EXPECT_EQ(listing["kinds"][0]["limits"]["max_stiffness_N_per_mm"], 1.0);
  EXPECT_DOUBLE_EQ(listing["kinds"][0]["limits"]["max_stiffness_N_per_mm_at_rate"], 0.25);
  // At or above 1 kHz the limit is the stated one; a rate that is not positive is refused.
  const auto fast = nlohmann::json::parse(format_device_list_json(
      {}, {}, {{"bridge", "bridge:port=47810", bridge_limits}}, "", 4000.0));
  EXPECT_EQ(fast["kinds"][0]["limits"]["max_stiffness_N_per_mm_at_rate"], 1.0);
  for (const double bad : {0.0, -250.0, std::nan("")}) {
    EXPECT_THROW(format_device_list_json({}, {}, {}, "", bad), std::invalid_argument) << bad;
  }
}

// A product name that is not UTF-8 (the device's own bytes) still gives valid JSON.
TEST(HidDeviceList, JsonSurvivesAProductNameThatIsNotUtf8) {
  HidDeviceRow row;
  row.info.path = "/dev/hidraw1";
  row.info.product = "Pad \xff\xfe";
  const auto listing = nlohmann::json::parse(format_device_list_json({row}, {}, {}, "", 1000.0));
  EXPECT_EQ(listing["devices"][0]["path"], "/dev/hidraw1");
  EXPECT_EQ(listing["devices"][0]["product"].get<std::string>().rfind("Pad ", 0), 0U);
}

// Through the real hidapi library: finding nothing here is a valid result.
TEST(HidDeviceList, RealHidapiEnumerationPrintsWhatItFinds) {
  const auto rows = list_hid_devices(load_profiles(HAPTICUT_PROFILE_DIR));
  const std::string table = format_hid_device_list(rows);
  if (rows.empty()) {
    EXPECT_EQ(table, "no HID devices found\n");
  } else {
    EXPECT_EQ(table.rfind("path ", 0), 0U);
    for (const HidDeviceRow& row : rows) EXPECT_NE(table.find(row.info.path), std::string::npos);
  }
  EXPECT_EQ(list_hid_devices_text(HAPTICUT_PROFILE_DIR).rfind(rows.empty() ? "no HID" : "path ", 0),
            0U);
  EXPECT_FALSE(hidapi_version_string().empty());
  std::printf("hidapi %s: %s", hidapi_version_string().c_str(), table.c_str());

  // --list-devices --json through the same enumeration: the same devices, every profile.
  const auto listing = nlohmann::json::parse(list_devices_json(HAPTICUT_PROFILE_DIR, {}, 1000.0));
  ASSERT_EQ(listing["devices"].size(), rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(listing["devices"][i]["path"], rows[i].info.path);
    EXPECT_EQ(listing["devices"][i]["profile"].is_null(), rows[i].profile.empty());
  }
  EXPECT_EQ(listing["profiles"].size(), load_profiles(HAPTICUT_PROFILE_DIR).size());
  EXPECT_GT(listing["profiles"].size(), 0U);
  EXPECT_EQ(listing["hidapi"], hidapi_version_string());
  EXPECT_TRUE(listing["kinds"].empty());
}

TEST(HidDeviceFactory, ArgumentsAreCheckedAndNamed) {
  const auto error_of = [](const std::string& args) {
    try {
      std::string bare;
      const DeviceOptions options = parse_device_options(args, "hid", bare);
      make_hid_device(bare, options, std::make_unique<ScriptedHidTransport>());
    } catch (const std::exception& error) {
      return std::string(error.what());
    }
    return std::string();
  };
  const std::string dir = std::string(",profiles=") + HAPTICUT_PROFILE_DIR;
  EXPECT_EQ(error_of("profile=spacemouse-wireless" + dir), "");
  EXPECT_EQ(error_of("profile=spacemouse-wireless,mode=position,gain=80,home=0:0:20" + dir), "");
  EXPECT_EQ(error_of("prof=x").rfind("hid: unknown option 'prof' (known: profile,", 0), 0U);
  EXPECT_EQ(error_of("profile=nope" + dir).rfind("hid: no profile named 'nope' (shipped: ", 0), 0U);
  EXPECT_EQ(error_of("profile=spacenavigator,mode=fast" + dir),
            "hid: option 'mode=fast' must be rate or position");
  EXPECT_EQ(error_of("profile=spacenavigator,gain=x" + dir),
            "hid: option 'gain=x' is not a number");
  EXPECT_EQ(error_of("profile=spacenavigator,home=1:2" + dir),
            "hid: option 'home=1:2' must be X:Y:Z in mm");
  // No profile named and nothing connected: says so.
  EXPECT_EQ(
      error_of(dir.substr(1)).rfind("hid: no connected HID device matches a shipped profile", 0),
      0U);
  EXPECT_EQ(error_of("spacemouse-wireless,mode=position" + dir), "");  // Bare first value.
  EXPECT_EQ(error_of("spacenavigator,profile=spacenavigator" + dir)
                .rfind("hid: the profile is given twice", 0),
            0U);
  EXPECT_EQ(error_of("profile=a,profile=b"), "hid: option 'profile' given twice");
  // A profile file by path.
  const std::string file = std::string(HAPTICUT_DEVICES_TEST_DATA) + "/example-force-device.json";
  EXPECT_EQ(error_of("profile=" + file), "");
}

}  // namespace
}  // namespace hapticut::servo
