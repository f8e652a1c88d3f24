// The forcedimension kind against the DHD stand-in (dhd_standin.h), loaded as
// the real library would be: through $HAPTICUT_DHD_LIB and dlopen.
#include "devices/dhd_device.h"

#include <dlfcn.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "devices/arm_pose_mapping.h"
#include "dhd_standin.h"
#include "rt/clock.h"
#include "standin_test_support.h"

namespace hapticut::servo {
namespace {

class DhdDeviceTest : public StandinTest<DhdStandinCall> {
 protected:
  DhdDeviceTest()
      : StandinTest(kDhdLibraryVariable, HAPTICUT_DHD_STANDIN, "hapticut_dhd_standin") {}

  std::unique_ptr<DhdDevice> make(const std::string& script, const DeviceOptions& options = {},
                                  const std::string& id = "", double watchdog_s = 0.0) {
    configure(script);
    return make_dhd_device(id, options, watchdog_s);
  }

  // The stand-in's model of what the arm applies at `time_s` (SDK frame); whether forces are on.
  static bool applied_force(double time_s, Vec3& force) {
    void* handle = dlopen(HAPTICUT_DHD_STANDIN, RTLD_NOW | RTLD_NOLOAD);
    EXPECT_NE(handle, nullptr);
    if (handle == nullptr) return false;
    using Applied = int (*)(double, double*);
    const auto applied =
        reinterpret_cast<Applied>(dlsym(handle, "hapticut_dhd_standin_applied_force"));
    double out[3] = {0, 0, 0};
    const bool on = applied != nullptr && applied(time_s, out) != 0;
    dlclose(handle);
    force = {out[0], out[1], out[2]};
    return on;
  }
};

// The stand-in built without dhdSetWatchdog and dhdGetWatchdog (a libdhd before SDK 3.3.2).
class DhdDeviceWithoutWatchdogTest : public StandinTest<DhdStandinCall> {
 protected:
  DhdDeviceWithoutWatchdogTest()
      : StandinTest(kDhdLibraryVariable, HAPTICUT_DHD_STANDIN_NO_WATCHDOG, "hapticut_dhd_standin") {
  }
};

std::uint64_t counter(const Device& device, const std::string& name) {
  for (const auto& [key, value] : device.status_counters()) {
    if (key == name) return value;
  }
  ADD_FAILURE() << "no counter " << name;
  return 0;
}

// The servo's loop for `ticks` ticks at 1 kHz, as tick_blade calls a device:
// read, then write `force` (scene frame).
void loop(Device& device, int ticks, const Vec3& force) {
  double next = monotonic_now_s();
  for (int tick = 0; tick < ticks; ++tick) {
    DeviceSample sample;
    device.read(monotonic_now_s(), sample);
    device.write(force, {0, 0, 0});
    next += 0.001;
    sleep_until(next);
  }
}

// How long after `fault` (a failed call) the arm got a zero force: the
// record's ticks (dhdGetPosition calls start one) and its time.
void print_time_to_zero(const char* what, const std::vector<DhdStandinCall>& all,
                        std::size_t fault) {
  int ticks = 0;
  for (std::size_t i = fault + 1; i < all.size(); ++i) {
    const DhdStandinCall& call = all[i];
    if (std::string(call.name) == "dhdGetPosition") ++ticks;
    if (std::string(call.name) == "dhdSetForce" && is_zero_force(call)) {
      std::printf("time to zero force after %s: %d ticks, %.1f us\n", what, ticks,
                  (call.time_s - all[fault].time_s) * 1e6);
      return;
    }
  }
  ADD_FAILURE() << "no zero force after " << what;
}

TEST(DhdLibrary, AMissingFileNamesTheVariableAndTheLoadersReason) {
  setenv(kDhdLibraryVariable, "/nonexistent/libdhd.so.3", 1);
  std::string error;
  EXPECT_EQ(load_dhd_library(error), nullptr);
  unsetenv(kDhdLibraryVariable);
  EXPECT_NE(error.find("HAPTICUT_DHD_LIB=/nonexistent/libdhd.so.3"), std::string::npos) << error;
  EXPECT_NE(error.find("No such file"), std::string::npos) << error;  // dlerror()'s words.
  EXPECT_NE(error.find("install"), std::string::npos) << error;
}

TEST(DhdLibrary, ALibraryWithoutDhdsSymbolsIsRefusedNamingThem) {
  setenv(kDhdLibraryVariable, "libm.so.6", 1);
  std::string error;
  EXPECT_EQ(load_dhd_library(error), nullptr);
  unsetenv(kDhdLibraryVariable);
  EXPECT_NE(error.find("lacks dhdGetDeviceCount"), std::string::npos) << error;
  EXPECT_NE(error.find("dhdClose"), std::string::npos) << error;
}

TEST_F(DhdDeviceTest, NoDeviceConnectedIsAClearError) {
  try {
    make("devices=0");
    FAIL() << "opened a device that is not there";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no Force Dimension device found"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(first("dhdOpenID"), -1);
  EXPECT_THROW(make("devices=1", {}, "1"), std::runtime_error);  // Only ID 0 exists.
}

TEST_F(DhdDeviceTest, ADeviceAnotherProgramHoldsSaysSo) {
  try {
    make("open_error=20");
    FAIL() << "opened a device in use";
  } catch (const std::runtime_error& e) {
    const std::string text = e.what();
    EXPECT_NE(text.find("dhdOpenID failed: device in use (stand-in) (DHD error 20)"),
              std::string::npos)
        << text;
    EXPECT_NE(text.find("another program holds the device"), std::string::npos) << text;
  }
}

TEST_F(DhdDeviceTest, BadOptionsAreRefusedBeforeTheLibraryIsTouched) {
  EXPECT_THROW(make("", {{"scale", "0"}}), std::invalid_argument);
  EXPECT_THROW(make("", {{"offset", "1:2"}}), std::invalid_argument);
  EXPECT_THROW(make("", {{"colour", "red"}}), std::invalid_argument);
  EXPECT_THROW(make("", {}, "x"), std::invalid_argument);
  EXPECT_TRUE(calls().empty());
}

TEST_F(DhdDeviceTest, ForceIsEnabledOnlyAfterTheLimitsAreReadAndAtZero) {
  std::unique_ptr<Device> device = make("");
  EXPECT_EQ(first("dhdEnableForce"), -1) << "force enabled before start()";
  device->start();
  const long limit = first("dhdGetMaxForce");
  const long type = first("dhdGetSystemType");
  const long enable = first("dhdEnableForce");
  ASSERT_GE(limit, 0);
  ASSERT_GE(type, 0);
  ASSERT_GT(enable, limit);
  ASSERT_GT(enable, type);
  EXPECT_EQ(calls()[static_cast<std::size_t>(enable)].a, 1.0);  // DHD_ON
  for (const DhdStandinCall& call : calls()) {
    if (std::string(call.name) == "dhdSetForce") EXPECT_TRUE(is_zero_force(call));
  }
}

TEST_F(DhdDeviceTest, LimitsAreTheModelsLoweredByTheDevicesOwnAndMappedToTheScene) {
  const DeviceLimits falcon = make("type=60")->limits();
  EXPECT_TRUE(falcon.has_force_output);
  EXPECT_EQ(falcon.max_force_N, dhd_model(60).max_force_N);
  EXPECT_EQ(falcon.max_torque_N_mm, 0.0);
  EXPECT_EQ(make("type=60,max_force=1.5")->limits().max_force_N, 1.5);
  // A binding's own limit, never above the device's.
  EXPECT_EQ(make("type=60,max_force=1.5", {{"max_force", "3"}})->limits().max_force_N, 1.5);
  EXPECT_EQ(make("type=60", {{"max_force", "3"}})->limits().max_force_N, 3.0);
  // Scaled: a scene spring k is k * scale on the hand; the box moves with the offset.
  const DeviceLimits scaled = make("type=60", {{"scale", "2"}, {"offset", "10:0:-5"}})->limits();
  EXPECT_DOUBLE_EQ(scaled.max_stiffness_N_per_mm, falcon.max_stiffness_N_per_mm / 2.0);
  const double half = dhd_model(60).workspace_half_mm;
  EXPECT_DOUBLE_EQ(scaled.workspace_min_mm.x, 10.0 - 2.0 * half);
  EXPECT_DOUBLE_EQ(scaled.workspace_max_mm.z, -5.0 + 2.0 * half);
}

TEST_F(DhdDeviceTest, PoseIsMappedFromMetresInTheSdkAxesAndForceGoesBack) {
  std::unique_ptr<Device> device =
      make("from=0.01:0.02:0.03,to=0.01:0.02:0.03,buttons=3", {{"offset", "1:2:3"}});
  device->start();
  DeviceSample sample;
  ASSERT_EQ(device->read(5.0, sample), DeviceStatus::Fresh);
  // Scene = (y, -x, z) of the SDK's frame, in mm, plus the offset.
  EXPECT_NEAR(sample.pose.position_mm.x, 1.0 + 20.0, 1e-9);
  EXPECT_NEAR(sample.pose.position_mm.y, 2.0 - 10.0, 1e-9);
  EXPECT_NEAR(sample.pose.position_mm.z, 3.0 + 30.0, 1e-9);
  EXPECT_EQ(sample.buttons, 3U);
  EXPECT_EQ(sample.time_s, 5.0);
  EXPECT_EQ(first("dhdGetOrientationFrame"), -1) << "an omega.3 has no wrist";
  device->write({1.0, 2.0, 3.0}, {0, 0, 0});
  const std::vector<DhdStandinCall> all = calls();
  const DhdStandinCall& force = all.back();
  ASSERT_STREQ(force.name, "dhdSetForce");
  EXPECT_EQ(force.a, -2.0);  // SDK x towards the user: minus the scene's y.
  EXPECT_EQ(force.b, 1.0);
  EXPECT_EQ(force.c, 3.0);
}

TEST_F(DhdDeviceTest, AWristedModelReadsItsOrientationFrame) {
  std::unique_ptr<Device> device = make("type=35,yaw_deg=90");  // omega.7, right hand
  device->start();
  DeviceSample sample;
  ASSERT_EQ(device->read(0.0, sample), DeviceStatus::Fresh);
  EXPECT_GT(first("dhdGetOrientationFrame"), first("dhdGetPosition"));
  // 90 degrees about the SDK's z is 90 degrees about the scene's z (both up).
  EXPECT_NEAR(sample.pose.rotation.w, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(sample.pose.rotation.z, std::sqrt(0.5), 1e-12);
  // Without a wrist the handle's rotation is the identity, whatever the SDK would say.
  std::unique_ptr<Device> omega3 = make("type=33,yaw_deg=90");
  omega3->start();
  ASSERT_EQ(omega3->read(0.0, sample), DeviceStatus::Fresh);
  EXPECT_EQ(sample.pose.rotation.w, 1.0);
  EXPECT_EQ(first("dhdGetOrientationFrame"), -1);
}

TEST_F(DhdDeviceTest, AnUninitialisedDeviceIsRefusedSayingWhatToDo) {
  try {
    make("reset=1");
    FAIL() << "opened a device in RESET mode";
  } catch (const std::runtime_error& e) {
    const std::string text = e.what();
    EXPECT_NE(text.find("not initialised (dhdGetStatus: RESET mode"), std::string::npos) << text;
    EXPECT_NE(text.find("calibration position"), std::string::npos) << text;
  }
  EXPECT_EQ(first("dhdEnableForce"), -1);
  EXPECT_GT(first("dhdClose"), first("dhdGetStatus")) << "the refused device was not closed";

  // Powered off and on while lost: reopened only once initialised again.
  std::unique_ptr<Device> device = make("fail_position_at=1");
  device->start();
  DeviceSample sample;
  ASSERT_EQ(device->read(0.0, sample), DeviceStatus::Lost);
  configure("reset=1");
  device->maintain();
  EXPECT_NE(device->last_error().find("reopening: not initialised"), std::string::npos)
      << device->last_error();
  EXPECT_EQ(first("dhdEnableForce"), -1);
  EXPECT_EQ(device->read(0.001, sample), DeviceStatus::Lost);
  configure("");
  device->maintain();
  EXPECT_EQ(device->last_error(), "");
  EXPECT_EQ(device->read(0.002, sample), DeviceStatus::Fresh);
}

TEST_F(DhdDeviceTest, AnErrorMidSessionZeroesTheForceInTheSameTickThenReconnects) {
  std::unique_ptr<Device> device = make("fail_position_at=3");
  device->start();
  DeviceSample sample;
  for (int tick = 0; tick < 2; ++tick) {
    ASSERT_EQ(device->read(tick * 0.001, sample), DeviceStatus::Fresh);
    device->write({0.5, 0.0, 0.0}, {0, 0, 0});
  }
  const long before = static_cast<long>(calls().size());
  EXPECT_EQ(device->read(0.002, sample), DeviceStatus::Lost);
  // The failing read, then a zero force in the same call: nothing pushes after the fault.
  const std::vector<DhdStandinCall> fault = calls();
  ASSERT_EQ(static_cast<long>(fault.size()), before + 2);
  EXPECT_STREQ(fault[static_cast<std::size_t>(before)].name, "dhdGetPosition");
  EXPECT_EQ(fault[static_cast<std::size_t>(before)].result, -1);
  EXPECT_STREQ(fault[static_cast<std::size_t>(before) + 1].name, "dhdSetForce");
  EXPECT_TRUE(is_zero_force(fault[static_cast<std::size_t>(before) + 1]));
  print_time_to_zero("a failed dhdGetPosition", fault, static_cast<std::size_t>(before));
  // While lost the tick does not touch the library.
  device->write({0.5, 0.0, 0.0}, {0, 0, 0});
  EXPECT_EQ(device->read(0.003, sample), DeviceStatus::Lost);
  EXPECT_EQ(static_cast<long>(calls().size()), before + 2);

  device->maintain();
  EXPECT_EQ(device->last_error(), "");
  const long close = first("dhdClose", before);
  const long reopen = first("dhdOpenID", before);
  const long limit = first("dhdGetMaxForce", before);
  const long enable = first("dhdEnableForce", before);
  ASSERT_GE(close, 0);
  EXPECT_GT(reopen, close);
  EXPECT_GT(limit, reopen);
  EXPECT_GT(enable, limit);
  EXPECT_EQ(device->read(0.004, sample), DeviceStatus::Fresh);
  const auto counters = device->status_counters();
  EXPECT_EQ(counters[3], (std::pair<std::string, std::uint64_t>{"faults", 1}));
  EXPECT_EQ(counters[4], (std::pair<std::string, std::uint64_t>{"reconnects", 1}));
}

TEST_F(DhdDeviceTest, AReconnectionThatFailsKeepsTheFaultAndTheReason) {
  std::unique_ptr<Device> device = make("fail_position_at=1");
  device->start();
  DeviceSample sample;
  EXPECT_EQ(device->read(0.0, sample), DeviceStatus::Lost);
  configure("devices=0");  // Unplugged.
  device->maintain();
  const std::string error = device->last_error();
  EXPECT_NE(error.find("dhdGetPosition failed: communication error (stand-in) (DHD error 2)"),
            std::string::npos)
      << error;
  EXPECT_NE(error.find("dhdGetDeviceCount() = 0"), std::string::npos) << error;
  EXPECT_EQ(device->read(0.001, sample), DeviceStatus::Lost);
  EXPECT_EQ(first("dhdEnableForce"), -1);
}

TEST_F(DhdDeviceTest, AFailedForceWriteIsAFaultZeroedAtOnce) {
  // Call 1 is start()'s zero; call 3 is the second tick's force.
  std::unique_ptr<Device> device = make("fail_force_at=3");
  device->start();
  DeviceSample sample;
  ASSERT_EQ(device->read(0.0, sample), DeviceStatus::Fresh);
  device->write({0.2, 0.0, 0.0}, {0, 0, 0});
  ASSERT_EQ(device->read(0.001, sample), DeviceStatus::Fresh);
  device->write({0.3, 0.0, 0.0}, {0, 0, 0});
  const std::vector<DhdStandinCall> all = calls();
  ASSERT_GE(all.size(), 2U);
  EXPECT_EQ(all[all.size() - 2].result, -1);
  EXPECT_STREQ(all.back().name, "dhdSetForce");
  EXPECT_TRUE(is_zero_force(all.back()));
  print_time_to_zero("a failed dhdSetForce", all, all.size() - 2);
  EXPECT_EQ(device->read(0.002, sample), DeviceStatus::Lost);
}

TEST_F(DhdDeviceTest, TimeGuardAndMotorSaturatedAreSuccessesTheSecondCounted) {
  std::unique_ptr<Device> device = make("position_result=1,force_result=2");
  device->start();
  DeviceSample sample;
  for (int tick = 0; tick < 3; ++tick) {
    ASSERT_EQ(device->read(tick * 0.001, sample), DeviceStatus::Fresh);
    device->write({0.5, 0.0, 0.0}, {0, 0, 0});
  }
  const DhdDeviceCounters& counters = static_cast<DhdDevice&>(*device).counters();
  EXPECT_EQ(counters.faults.load(), 0U);
  EXPECT_EQ(counters.forces_written.load(), 3U);
  EXPECT_EQ(counters.motor_saturated.load(), 3U);
  EXPECT_TRUE(static_cast<DhdDevice&>(*device).connected());
}

TEST_F(DhdDeviceTest, StopLeavesTheArmWithoutForceAndClosed) {
  std::unique_ptr<Device> device = make("");
  device->start();
  device->stop();
  const std::vector<DhdStandinCall> all = calls();
  ASSERT_GE(all.size(), 3U);
  EXPECT_STREQ(all[all.size() - 3].name, "dhdSetForce");
  EXPECT_TRUE(is_zero_force(all[all.size() - 3]));
  EXPECT_STREQ(all[all.size() - 2].name, "dhdStop");
  EXPECT_STREQ(all.back().name, "dhdClose");
}

TEST_F(DhdDeviceTest, EachForceIsWrittenInTheTickOfItsSampleItsLatencyMeasured) {
  std::unique_ptr<Device> device = make("from=0:0:0,to=0:0:-0.02,reads=300");
  device->start();
  loop(*device, 300, {0.2, 0.0, 0.0});
  const auto& dhd = static_cast<DhdDevice&>(*device);
  const LatencyHistogram& latency = dhd.sample_to_force();
  // One measure a tick: each write follows its own tick's read.
  EXPECT_EQ(latency.count(), dhd.counters().samples.load());
  ASSERT_GT(latency.count(), 0U);
  std::printf(
      "sample to force through the DHD stand-in at 1 kHz (no engine between): "
      "median %.2f us, p99 %.2f us\n",
      latency.percentile_us(0.5), latency.percentile_us(0.99));
  // A write with no new sample since the last (a lost tick's) adds nothing.
  device->write({0.2, 0.0, 0.0}, {0, 0, 0});
  EXPECT_EQ(latency.count(), dhd.counters().samples.load());
  const auto counters = device->status_counters();
  EXPECT_EQ(counters[counters.size() - 2].first, "sample_to_force_ns_p50");
  EXPECT_EQ(counters.back().first, "sample_to_force_ns_p99");
}

TEST_F(DhdDeviceTest, TheListingNamesTheLibraryAndEachDeviceWithItsLimits) {
  configure("devices=2,type=60");
  const DhdListing listing = list_dhd_devices();
  EXPECT_TRUE(listing.library_found);
  EXPECT_NE(listing.library.find("hapticut-dhd-standin"), std::string::npos);
  ASSERT_EQ(listing.devices.size(), 2U);
  EXPECT_EQ(listing.devices[1].binding, "forcedimension:1");
  EXPECT_EQ(listing.devices[1].model, "Novint Falcon");
  EXPECT_EQ(listing.devices[1].limits.max_force_N, dhd_model(60).max_force_N);
  const std::string text = format_dhd_listing(listing);
  EXPECT_NE(text.find("forcedimension:0"), std::string::npos) << text;
  // Each device was closed again: a servo may open it next.
  EXPECT_GT(first("dhdClose", first("dhdOpenID", first("dhdOpenID") + 1)), 0);
}

TEST(DhdWatchdogUnits, WholeUnitsOf125UsNeverLongerThanAskedWithinOneTo255) {
  EXPECT_EQ(dhd_watchdog_units(0.005), 40);
  EXPECT_EQ(dhd_watchdog_units(0.002), 16);
  EXPECT_EQ(dhd_watchdog_units(0.00199), 15);
  EXPECT_EQ(dhd_watchdog_units(0.1), 255);  // The servo's default: the firmware's longest.
  EXPECT_EQ(dhd_watchdog_units(0.0001), 1);
  EXPECT_EQ(dhd_watchdog_units(0.031875), 255);
}

TEST_F(DhdDeviceTest, TheFirmwareWatchdogIsSetToTheServosBeforeForceIsEnabled) {
  std::unique_ptr<DhdDevice> device = make("fail_position_at=2", {}, "", 0.005);
  EXPECT_EQ(first("dhdSetWatchdog"), -1) << "set before start(): the listing opens devices too";
  device->start();
  const long watchdog = first("dhdSetWatchdog");
  const long enable = first("dhdEnableForce");
  ASSERT_GE(watchdog, 0);
  EXPECT_LT(watchdog, enable);
  EXPECT_EQ(calls()[static_cast<std::size_t>(watchdog)].a, 40.0);  // 5 ms in 125 us units.
  EXPECT_EQ(counter(*device, "firmware_watchdog_us"), 5000U);
  EXPECT_EQ(device->firmware_watchdog_warning(), "");

  // Reopened after a fault: set again before the force is enabled again.
  DeviceSample sample;
  ASSERT_EQ(device->read(0.0, sample), DeviceStatus::Fresh);
  ASSERT_EQ(device->read(0.001, sample), DeviceStatus::Lost);
  const long lost = static_cast<long>(calls().size());
  device->maintain();
  const long reopen = first("dhdOpenID", lost);
  const long again = first("dhdSetWatchdog", lost);
  ASSERT_GT(reopen, 0);
  EXPECT_GT(again, reopen);
  EXPECT_LT(again, first("dhdEnableForce", lost));
  EXPECT_EQ(calls()[static_cast<std::size_t>(again)].a, 40.0);

  // The servo's default --watchdog-ms (100) is beyond the firmware's longest: 255 units.
  std::unique_ptr<DhdDevice> other = make("", {}, "", 0.1);
  other->start();
  EXPECT_EQ(calls()[static_cast<std::size_t>(first("dhdSetWatchdog"))].a, 255.0);
  EXPECT_EQ(counter(*other, "firmware_watchdog_us"), 31875U);
}

TEST_F(DhdDeviceTest, AStalledLoopLeavesNoForceOnceTheFirmwareWatchdogExpires) {
  std::unique_ptr<DhdDevice> device = make("", {}, "", 0.02);  // 160 units
  device->start();
  loop(*device, 20, {0.0, 0.4, 0.0});  // The scene's y: the SDK's -x.
  std::vector<DhdStandinCall> all = calls();
  const DhdStandinCall last = all.back();
  ASSERT_STREQ(last.name, "dhdSetForce");
  ASSERT_EQ(last.a, -0.4);
  Vec3 force;
  // Within the duration the arm applies the last command; past it, nothing.
  EXPECT_TRUE(applied_force(last.time_s + 0.0199, force));
  EXPECT_EQ(force.x, -0.4);
  EXPECT_FALSE(applied_force(last.time_s + 0.0201, force));
  EXPECT_EQ(force.x, 0.0);
  // A tick of the loop above late past the watchdog (a loaded machine) enabled forces again.
  const std::uint64_t reenabled = counter(*device, "forces_reenabled");

  // The loop stalls: no call for 60 ms. The firmware's watchdog disabled forces.
  std::this_thread::sleep_for(std::chrono::milliseconds(60));
  all = calls();
  ASSERT_STREQ(all.back().name, "firmware_watchdog");
  EXPECT_EQ(all.back().a, -0.4);  // The force it dropped.
  std::printf("time to zero force on a stalled loop (firmware watchdog 20 ms): %.3f ms\n",
              (all.back().time_s - last.time_s) * 1e3);
  EXPECT_FALSE(applied_force(monotonic_now_s(), force));

  // The loop runs again: forces enabled again at zero, then the tick's force.
  const long before = static_cast<long>(all.size());
  DeviceSample sample;
  ASSERT_EQ(device->read(monotonic_now_s(), sample), DeviceStatus::Fresh);
  device->write({0.0, 0.1, 0.0}, {0, 0, 0});
  const long zero = first("dhdSetForce", before);
  const long enable = first("dhdEnableForce", before);
  ASSERT_GT(zero, 0);
  EXPECT_TRUE(is_zero_force(calls()[static_cast<std::size_t>(zero)]));
  EXPECT_GT(enable, zero);
  EXPECT_EQ(calls()[static_cast<std::size_t>(enable)].a, 1.0);
  EXPECT_STREQ(calls().back().name, "dhdSetForce");
  EXPECT_TRUE(applied_force(calls().back().time_s, force));
  EXPECT_EQ(force.x, -0.1);
  EXPECT_EQ(counter(*device, "forces_reenabled"), reenabled + 1);
}

TEST_F(DhdDeviceTest, ADeviceThatRefusesTheWatchdogIsAWarningNotARefusal) {
  std::unique_ptr<DhdDevice> device = make("watchdog_error=10", {}, "", 0.005);
  device->start();
  EXPECT_GE(first("dhdEnableForce"), 0);
  const std::string warning = device->firmware_watchdog_warning();
  EXPECT_NE(warning.find("dhdSetWatchdog failed: not available on this device (stand-in) (DHD "
                         "error 10)"),
            std::string::npos)
      << warning;
  EXPECT_NE(warning.find("the arm keeps its last force"), std::string::npos) << warning;
  EXPECT_EQ(counter(*device, "firmware_watchdog_us"), 0U);
  DeviceSample sample;
  EXPECT_EQ(device->read(0.0, sample), DeviceStatus::Fresh);
  device.reset();

  // The listing asks dhdGetWatchdog, which changes nothing on the device.
  configure("watchdog_error=10");
  const DhdListing listing = list_dhd_devices();
  ASSERT_EQ(listing.devices.size(), 1U);
  EXPECT_FALSE(listing.devices[0].firmware_watchdog);
  EXPECT_NE(listing.devices[0].firmware_watchdog_warning.find("dhdGetWatchdog failed"),
            std::string::npos);
  EXPECT_EQ(first("dhdSetWatchdog"), -1);
  configure("");
  const DhdListing supported = list_dhd_devices();
  EXPECT_TRUE(supported.devices[0].firmware_watchdog);
  EXPECT_NE(format_dhd_listing(supported).find("firmware watchdog: yes"), std::string::npos);
}

TEST_F(DhdDeviceWithoutWatchdogTest, ALibraryWithoutTheWatchdogOpensAndSaysWhatThatLeaves) {
  configure("");
  std::unique_ptr<DhdDevice> device = make_dhd_device("", {}, 0.005);
  device->start();
  EXPECT_GE(first("dhdEnableForce"), 0);
  const std::string warning = device->firmware_watchdog_warning();
  EXPECT_NE(warning.find("lacks dhdSetWatchdog (a Force Dimension SDK before 3.3.2"),
            std::string::npos)
      << warning;
  EXPECT_NE(warning.find("the arm keeps its last force until the loop runs again"),
            std::string::npos)
      << warning;
  EXPECT_EQ(counter(*device, "firmware_watchdog_us"), 0U);
  DeviceSample sample;
  EXPECT_EQ(device->read(0.0, sample), DeviceStatus::Fresh);
  device->write({0.1, 0.0, 0.0}, {0, 0, 0});
  EXPECT_EQ(counter(*device, "forces_reenabled"), 0U);
  device.reset();

  const DhdListing listing = list_dhd_devices();
  ASSERT_EQ(listing.devices.size(), 1U);
  EXPECT_FALSE(listing.devices[0].firmware_watchdog);
  const std::string text = format_dhd_listing(listing);
  EXPECT_NE(text.find("firmware watchdog: no firmware watchdog:"), std::string::npos) << text;
  EXPECT_NE(text.find("lacks dhdSetWatchdog"), std::string::npos) << text;
}

TEST(ArmPoseMapping, MatrixQuaternionAndBack) {
  // 90 degrees about z, and 180 degrees about x (the branch without the trace).
  const Matrix3 about_z{{{0, -1, 0}, {1, 0, 0}, {0, 0, 1}}};
  const Quaternion q = matrix_quaternion(about_z);
  EXPECT_NEAR(q.w, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(q.z, std::sqrt(0.5), 1e-12);
  const Vec3 turned = q.rotate({1, 0, 0});
  EXPECT_NEAR(turned.y, 1.0, 1e-12);
  const Quaternion flip = matrix_quaternion({{{1, 0, 0}, {0, -1, 0}, {0, 0, -1}}});
  EXPECT_NEAR(std::abs(flip.x), 1.0, 1e-12);
  // The SDK's axes: a rotation about the SDK's z stays one about the scene's z.
  const ArmPoseMapping mapping({kDhdToSceneAxes, 1.0, {}});
  const Quaternion mapped = mapping.rotation(about_z);
  EXPECT_NEAR(mapped.w, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(mapped.z, std::sqrt(0.5), 1e-12);
}

}  // namespace
}  // namespace hapticut::servo
