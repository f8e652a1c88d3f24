// The openhaptics kind against the OpenHaptics stand-in (hd_standin.h), loaded
// as the real library would be: through $HAPTICUT_OPENHAPTICS_LIB and dlopen.
// The stand-in's scheduler thread calls the device's callback at 1 kHz; the
// test thread plays the servo's loop.
#include "devices/hd_device.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "hd_standin.h"
#include "rt/clock.h"
#include "standin_test_support.h"

namespace hapticut::servo {
namespace {

class HdDeviceTest : public StandinTest<HdStandinCall> {
 protected:
  HdDeviceTest() : StandinTest(kHdLibraryVariable, HAPTICUT_HD_STANDIN, "hapticut_hd_standin") {}

  std::vector<HdStandinCall> forces() const {
    std::vector<HdStandinCall> out;
    for (const HdStandinCall& call : calls()) {
      if (std::string(call.name) == "hdSetDoublev(FORCE)") out.push_back(call);
    }
    return out;
  }
  std::unique_ptr<Device> make(const std::string& script, const DeviceOptions& options = {},
                               double watchdog_s = 0.1) {
    configure(script);
    return make_hd_device("", options, watchdog_s);
  }
  // The servo's loop for `seconds` at 1 kHz: read, then write `force` (scene frame).
  static std::vector<DeviceStatus> loop(Device& device, double seconds, const Vec3& force) {
    std::vector<DeviceStatus> statuses;
    const double start = monotonic_now_s();
    double next = start;
    while (monotonic_now_s() - start < seconds) {
      DeviceSample sample;
      statuses.push_back(device.read(monotonic_now_s(), sample));
      device.write(force, {0, 0, 0});
      next += 0.001;
      sleep_until(next);
    }
    return statuses;
  }
};

// How long after `from` (a call in the record) the first zero force `zero`
// was set: the scheduler's frames and the record's time.
void print_time_to_zero(const char* what, const HdStandinCall& from, const HdStandinCall& zero) {
  std::printf("time to zero force after %s: %ld frames, %.3f ms\n", what, zero.frame - from.frame,
              (zero.time_s - from.time_s) * 1e3);
}

TEST(HdLibrary, AMissingFileNamesTheVariableTheLoadersReasonAndOldNcurses) {
  setenv(kHdLibraryVariable, "/nonexistent/libHD.so.3.4", 1);
  std::string error;
  EXPECT_EQ(load_hd_library(error), nullptr);
  unsetenv(kHdLibraryVariable);
  EXPECT_NE(error.find("HAPTICUT_OPENHAPTICS_LIB=/nonexistent/libHD.so.3.4"), std::string::npos)
      << error;
  EXPECT_NE(error.find("No such file"), std::string::npos) << error;  // dlerror()'s words.
  EXPECT_NE(error.find("libncurses.so.5"), std::string::npos) << error;
}

TEST(HdLibrary, ALibraryWithoutHdsSymbolsIsRefusedNamingThem) {
  setenv(kHdLibraryVariable, "libm.so.6", 1);
  std::string error;
  EXPECT_EQ(load_hd_library(error), nullptr);
  unsetenv(kHdLibraryVariable);
  EXPECT_NE(error.find("lacks hdInitDevice"), std::string::npos) << error;
  EXPECT_NE(error.find("hdGetErrorString"), std::string::npos) << error;
}

TEST_F(HdDeviceTest, NoDeviceIsAClearErrorNamingWhatToCheck) {
  try {
    make("devices=0");
    FAIL() << "opened a device that is not there";
  } catch (const std::runtime_error& e) {
    const std::string text = e.what();
    EXPECT_NE(text.find("hdInitDevice failed: Communication error (stand-in) (HD error 0x302"),
              std::string::npos)
        << text;
    EXPECT_NE(text.find("/dev/ttyACM"), std::string::npos) << text;
  }
  EXPECT_EQ(first("hdEnable"), -1);
}

TEST_F(HdDeviceTest, ADeviceAnotherProgramHoldsSaysSo) {
  try {
    make("init_error=0x301");
    FAIL() << "opened a device in use";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("another program"), std::string::npos) << e.what();
  }
}

TEST_F(HdDeviceTest, AnUncalibratedDeviceIsUpdatedOrRefusedSayingWhatToDo) {
  std::unique_ptr<Device> updated = make("calibration=update");
  EXPECT_GT(first("hdUpdateCalibration"), first("hdCheckCalibration"));
  updated.reset();
  try {
    make("calibration=manual");
    FAIL() << "opened an uncalibrated device";
  } catch (const std::runtime_error& e) {
    const std::string text = e.what();
    EXPECT_NE(text.find("not calibrated"), std::string::npos) << text;
    EXPECT_NE(text.find("inkwell"), std::string::npos) << text;
  }
  EXPECT_EQ(first("hdEnable"), -1);
  EXPECT_GE(first("hdDisableDevice"), 0) << "the refused device was not released";
}

TEST_F(HdDeviceTest, BadOptionsAreRefusedBeforeTheLibraryIsTouched) {
  EXPECT_THROW(make("", {{"scale", "0"}}), std::invalid_argument);
  EXPECT_THROW(make("", {{"offset", "1:2"}}), std::invalid_argument);
  EXPECT_THROW(make("", {{"colour", "red"}}), std::invalid_argument);
  EXPECT_TRUE(calls().empty());
}

TEST_F(HdDeviceTest, ANamedDeviceIsOpenedByItsNameTheDefaultByNone) {
  configure("");
  make_hd_device("", {}, 0.1).reset();
  EXPECT_EQ(calls()[static_cast<std::size_t>(first("hdInitDevice"))].a, 0.0);  // HD_DEFAULT_DEVICE
  configure("");
  make_hd_device("", {{"device", "Right"}}, 0.1).reset();
  EXPECT_EQ(calls()[static_cast<std::size_t>(first("hdInitDevice"))].a, 1.0);
  EXPECT_THROW(make_hd_device("Left", {{"device", "Right"}}, 0.1), std::invalid_argument);
  EXPECT_EQ(hd_device_options("Left", {}).name, "Left");
}

TEST_F(HdDeviceTest, ForceOutputIsEnabledOnlyAfterTheLimitsAreReadAndNeverSetOutsideAFrame) {
  std::unique_ptr<Device> device = make("");
  EXPECT_EQ(first("hdEnable"), -1) << "force enabled before start()";
  device->start();
  loop(*device, 0.05, {0.1, 0.0, 0.0});
  device->stop();
  const long enable = first("hdEnable");
  ASSERT_GT(enable, 0);
  EXPECT_EQ(calls()[static_cast<std::size_t>(enable)].a, 0x4000);  // HD_FORCE_OUTPUT
  for (const double limit : {0x2602, 0x2603, 0x2604, 0x2551}) {
    const long read = first("hdGetDoublev", 0, limit);
    ASSERT_GE(read, 0) << limit;
    EXPECT_LT(read, enable) << limit;
  }
  EXPECT_GT(first("hdScheduleAsynchronous"), enable);
  EXPECT_GT(first("hdStartScheduler"), first("hdScheduleAsynchronous"));
  const std::vector<HdStandinCall> set = forces();
  ASSERT_GT(set.size(), 20U);
  for (const HdStandinCall& call : set) {
    EXPECT_EQ(call.in_frame, 1);
    EXPECT_EQ(call.result, 0);
  }
}

TEST_F(HdDeviceTest, LimitsAreTheDevicesContinuousForceStiffnessAndWorkspaceMapped) {
  const DeviceLimits touch =
      make("max_force=3.3,continuous=0.88,stiffness=1.2,ws_min=-80:-60:-35,ws_max=80:60:35")
          ->limits();
  EXPECT_TRUE(touch.has_force_output);
  EXPECT_EQ(touch.max_force_N, 0.88);
  EXPECT_EQ(touch.max_stiffness_N_per_mm, 1.2);
  // Scene = (x, -z, y) of OpenHaptics's frame.
  EXPECT_EQ(touch.workspace_min_mm.x, -80.0);
  EXPECT_EQ(touch.workspace_min_mm.y, -35.0);
  EXPECT_EQ(touch.workspace_min_mm.z, -60.0);
  EXPECT_EQ(touch.workspace_max_mm.z, 60.0);
  // A binding may lower the device's limits, never raise them.
  EXPECT_EQ(make("continuous=0.88", {{"max_force", "0.5"}})->limits().max_force_N, 0.5);
  EXPECT_EQ(make("continuous=0.88", {{"max_force", "3"}})->limits().max_force_N, 0.88);
  EXPECT_EQ(make("stiffness=1.2", {{"max_stiffness", "5"}})->limits().max_stiffness_N_per_mm, 1.2);
  EXPECT_DOUBLE_EQ(make("stiffness=1.2", {{"scale", "2"}})->limits().max_stiffness_N_per_mm, 0.6);
}

TEST_F(HdDeviceTest, PoseIsMappedFromTheDevicesFrameAndForceGoesBack) {
  std::unique_ptr<Device> device =
      make("from=10:20:30,to=10:20:30,buttons=3", {{"offset", "1:2:3"}});
  device->start();
  const std::vector<DeviceStatus> statuses = loop(*device, 0.05, {1.0, 2.0, 3.0});
  DeviceSample sample;
  device->read(0.0, sample);
  device->stop();
  EXPECT_EQ(std::count(statuses.begin(), statuses.end(), DeviceStatus::Lost), 0);
  EXPECT_GT(std::count(statuses.begin(), statuses.end(), DeviceStatus::Fresh), 20);
  EXPECT_NEAR(sample.pose.position_mm.x, 1.0 + 10.0, 1e-9);
  EXPECT_NEAR(sample.pose.position_mm.y, 2.0 - 30.0, 1e-9);
  EXPECT_NEAR(sample.pose.position_mm.z, 3.0 + 20.0, 1e-9);
  EXPECT_NEAR(sample.pose.rotation.w, 1.0, 1e-12);
  EXPECT_EQ(sample.buttons, 3U);
  // The device's frame: (x, z, -y) of the scene's force.
  bool pushed = false;
  for (const HdStandinCall& call : forces()) {
    if (is_zero_force(call)) continue;
    pushed = true;
    EXPECT_EQ(call.a, 1.0);
    EXPECT_EQ(call.b, 3.0);
    EXPECT_EQ(call.c, -2.0);
  }
  EXPECT_TRUE(pushed);
}

TEST_F(HdDeviceTest, TheCallbackZeroesALoopForceOlderThanTheWatchdog) {
  std::unique_ptr<Device> device = make("", {}, 0.02);
  device->start();
  loop(*device, 0.05, {0.3, 0.0, 0.0});
  const double stalled_s = monotonic_now_s();
  const long written = static_cast<long>(forces().size());
  // The loop stalls: it neither reads nor writes.
  std::this_thread::sleep_for(std::chrono::milliseconds(80));
  const std::vector<HdStandinCall> after = forces();
  device->stop();
  ASSERT_GT(static_cast<long>(after.size()), written + 50);
  ASSERT_FALSE(is_zero_force(after[static_cast<std::size_t>(written) - 1]));
  // Pushing until the watchdog's 20 ms are up (a frame or two of slack), then zero.
  long first_zero = -1;
  for (long i = written; i < static_cast<long>(after.size()); ++i) {
    if (is_zero_force(after[static_cast<std::size_t>(i)])) {
      first_zero = i;
      break;
    }
  }
  ASSERT_GE(first_zero, 0);
  const HdStandinCall& last_pushed = after[static_cast<std::size_t>(written) - 1];
  const HdStandinCall& zero = after[static_cast<std::size_t>(first_zero)];
  EXPECT_LE(zero.frame - last_pushed.frame, 23);
  std::printf("time to zero force after the loop stalled (watchdog 20 ms): %ld frames, %.2f ms\n",
              zero.frame - last_pushed.frame, (zero.time_s - stalled_s) * 1e3);
  for (long i = first_zero; i < static_cast<long>(after.size()); ++i) {
    EXPECT_TRUE(is_zero_force(after[static_cast<std::size_t>(i)]));
  }
  const auto counters = device->status_counters();
  EXPECT_EQ(counters[3].first, "stale_force_frames");
  EXPECT_GT(counters[3].second, 40U);
}

TEST_F(HdDeviceTest, AnErrorInAFrameZeroesTheForceInThatFrameThenMaintainReopens) {
  std::unique_ptr<Device> device = make("fail_frame_at=40");
  device->start();
  const std::vector<DeviceStatus> statuses = loop(*device, 0.1, {0.3, 0.0, 0.0});
  EXPECT_GT(std::count(statuses.begin(), statuses.end(), DeviceStatus::Lost), 20);
  const std::vector<HdStandinCall> all = calls();
  long failed = -1;
  for (long i = 0; i < static_cast<long>(all.size()) && failed < 0; ++i) {
    const HdStandinCall& call = all[static_cast<std::size_t>(i)];
    if (std::string(call.name) == "hdGetDoublev(TRANSFORM)" && call.result != 0) failed = i;
  }
  ASSERT_GT(failed, 0);
  const long zero = first("hdSetDoublev(FORCE)", failed);
  ASSERT_GT(zero, failed);
  EXPECT_EQ(all[static_cast<std::size_t>(zero)].frame, all[static_cast<std::size_t>(failed)].frame);
  EXPECT_TRUE(is_zero_force(all[static_cast<std::size_t>(zero)]));
  print_time_to_zero("an HD error in the callback", all[static_cast<std::size_t>(failed)],
                     all[static_cast<std::size_t>(zero)]);
  // The frame before pushed: the zero is the fault's doing.
  const std::vector<HdStandinCall> set = forces();
  std::size_t k = 0;
  while (k < set.size() && set[k].frame < all[static_cast<std::size_t>(failed)].frame) ++k;
  ASSERT_GT(k, 0U);
  EXPECT_FALSE(is_zero_force(set[k - 1]));
  EXPECT_EQ(set.size(), k + 1) << "the callback set forces after the fault's frame";

  device->maintain();
  EXPECT_EQ(device->last_error(), "");
  const long stopped = first("hdStopScheduler", zero);
  const long disabled = first("hdDisableDevice", zero);
  const long reopened = first("hdInitDevice", zero);
  const long limits = first("hdGetDoublev", reopened, 0x2604);
  const long enabled = first("hdEnable", zero);
  const long started = first("hdStartScheduler", zero);
  ASSERT_GT(stopped, zero);
  EXPECT_GT(disabled, stopped);
  EXPECT_GT(reopened, disabled);
  EXPECT_GT(limits, reopened);
  EXPECT_GT(enabled, limits);
  EXPECT_GT(started, enabled);
  const std::vector<DeviceStatus> again = loop(*device, 0.05, {0.3, 0.0, 0.0});
  device->stop();
  EXPECT_EQ(std::count(again.begin(), again.end(), DeviceStatus::Lost), 0);
  const auto counters = device->status_counters();
  EXPECT_EQ(counters[4], (std::pair<std::string, std::uint64_t>{"faults", 1}));
  EXPECT_EQ(counters[5], (std::pair<std::string, std::uint64_t>{"reconnects", 1}));
}

TEST_F(HdDeviceTest, AFailedEndOfFrameIsZeroedInTheNextFrame) {
  std::unique_ptr<Device> device = make("fail_end_at=30");
  device->start();
  loop(*device, 0.08, {0.3, 0.0, 0.0});
  const std::vector<HdStandinCall> set = forces();
  ASSERT_FALSE(set.empty());
  EXPECT_EQ(set.back().frame, 31);
  EXPECT_TRUE(is_zero_force(set.back()));
  EXPECT_FALSE(is_zero_force(set[set.size() - 2]));
  const std::vector<HdStandinCall> all = calls();
  long failed = -1;
  for (long i = 0; i < static_cast<long>(all.size()) && failed < 0; ++i) {
    if (std::string(all[static_cast<std::size_t>(i)].name) == "hdEndFrame" &&
        all[static_cast<std::size_t>(i)].result != 0) {
      failed = i;
    }
  }
  ASSERT_GE(failed, 0);
  print_time_to_zero("a failed hdEndFrame", all[static_cast<std::size_t>(failed)], set.back());
  EXPECT_FALSE(static_cast<HdDevice&>(*device).connected());
  device->maintain();
  EXPECT_TRUE(static_cast<HdDevice&>(*device).connected());
  device->stop();
}

TEST_F(HdDeviceTest, AReconnectionThatFailsKeepsTheFaultAndTheReason) {
  std::unique_ptr<Device> device = make("fail_frame_at=5");
  device->start();
  loop(*device, 0.03, {0.0, 0.0, 0.0});
  configure("devices=0");  // Unplugged.
  device->maintain();
  const std::string error = device->last_error();
  EXPECT_NE(error.find("hdGetDoublev(HD_CURRENT_TRANSFORM) failed: Communication error"),
            std::string::npos)
      << error;
  EXPECT_NE(error.find("reopening: openhaptics: the default device: hdInitDevice failed"),
            std::string::npos)
      << error;
  EXPECT_EQ(first("hdEnable"), -1);
  configure("");  // Plugged in again.
  device->maintain();
  EXPECT_EQ(device->last_error(), "");
  EXPECT_TRUE(static_cast<HdDevice&>(*device).connected());
  device->stop();
}

TEST_F(HdDeviceTest, ASchedulerStallLeavesTheLoopStaleSamplesThenFreshOnes) {
  std::unique_ptr<Device> device = make("stall_at=20,stall_ms=60");
  device->start();
  const std::vector<DeviceStatus> statuses = loop(*device, 0.15, {0.1, 0.0, 0.0});
  device->stop();
  // The longest run of ticks without a new sample spans the stall, and fresh
  // samples come after it (not necessarily at the very last tick: on a loaded
  // machine a tick may find no new frame yet).
  int run = 0;
  int longest = 0;
  std::size_t longest_end = 0;
  for (std::size_t i = 0; i < statuses.size(); ++i) {
    run = statuses[i] == DeviceStatus::Stale ? run + 1 : 0;
    if (run > longest) {
      longest = run;
      longest_end = i;
    }
  }
  EXPECT_GE(longest, 45);
  EXPECT_NE(std::find(statuses.begin() + static_cast<std::ptrdiff_t>(longest_end), statuses.end(),
                      DeviceStatus::Fresh),
            statuses.end());
  EXPECT_EQ(std::count(statuses.begin(), statuses.end(), DeviceStatus::Lost), 0);
}

TEST_F(HdDeviceTest, StopSetsAZeroForceThenUnschedulesStopsAndReleases) {
  std::unique_ptr<Device> device = make("");
  device->start();
  loop(*device, 0.03, {0.3, 0.0, 0.0});
  device->stop();
  const std::vector<HdStandinCall> set = forces();
  ASSERT_FALSE(set.empty());
  EXPECT_TRUE(is_zero_force(set.back()));
  const long unschedule = first("hdUnschedule");
  ASSERT_GT(unschedule, 0);
  EXPECT_GT(first("hdStopScheduler"), unschedule);
  EXPECT_GT(first("hdDisableDevice"), first("hdStopScheduler"));
  EXPECT_EQ(first("hdSetDoublev(FORCE)", first("hdDisableDevice")), -1);
}

TEST_F(HdDeviceTest, TheLoopsForcesReachTheDeviceWithinAboutAFrameOfTheirSample) {
  std::unique_ptr<Device> device = make("from=0:0:0,to=0:-20:0,frames=300");
  device->start();
  loop(*device, 0.3, {0.2, 0.0, 0.0});
  const auto& latency = static_cast<HdDevice&>(*device).sample_to_force();
  device->stop();
  ASSERT_GT(latency.count(), 50U);
  std::printf("sample to force through the stand-in at 1 kHz: median %.0f us, p99 %.0f us\n",
              latency.percentile_us(0.5), latency.percentile_us(0.99));
}

TEST_F(HdDeviceTest, TheListingNamesTheLibraryAndTheDefaultDeviceWithItsLimits) {
  configure("continuous=0.88,stiffness=1.2");
  const HdListing listing = list_hd_devices();
  EXPECT_TRUE(listing.library_found);
  EXPECT_NE(listing.library.find("hapticut-hd-standin"), std::string::npos);
  ASSERT_EQ(listing.devices.size(), 1U);
  EXPECT_EQ(listing.devices[0].binding, "openhaptics");
  EXPECT_EQ(listing.devices[0].limits.max_force_N, 0.88);
  const std::string text = format_hd_listing(listing);
  EXPECT_NE(text.find("max continuous force 0.88 N"), std::string::npos) << text;
  // Released again: a servo may open it next; the force was never enabled.
  EXPECT_GE(first("hdDisableDevice"), 0);
  EXPECT_EQ(first("hdEnable"), -1);
}

}  // namespace
}  // namespace hapticut::servo
