// DhdDevice: a Force Dimension arm (omega, delta, sigma, lambda, and the
// Novint Falcon through the same SDK) driven through the DHD library loaded
// at run time (dhd_library.h).
//
// Threads. DHD is made to be called from the application's haptic loop (its
// calls are short USB transfers, at several kHz), so this backend has no I/O
// thread: read() calls dhdGetPosition, dhdGetOrientationFrame (models with a
// wrist) and dhdGetButtonMask, write() calls dhdSetForce, both on the tick;
// neither allocates, locks or logs. The force is dhdSetForce's alone: the
// blade renders no torque to the hand, and the gripper is neither read nor
// pushed. The factory opens the device, refuses one still in RESET mode (not
// initialised), and reads its type and force limit (limits() holds them
// before start()); start() only then enables the force, at zero.
//
// A stalled loop. Nothing on the tick runs while the loop stalls, so the
// device's own firmware watchdog stands in (dhdSetWatchdog, SDK 3.3.2 and
// later, "on compatible devices"): set before each enabling of the force to
// the servo's --watchdog-ms, as far as the firmware's unit allows (at most
// 255 x 125 us), it disables forces when no force command arrives for that
// long. The SDK does not say whether the firmware lets forces back on with
// the next command, so a write() after a longer gap enables them again
// first (the servo's own watchdog has made that write's force zero when the
// gap outlasted it, and ramps back in). A library without the call, or a
// device that refuses it, is a warning (start log, listing), not a refusal:
// a stalled loop then leaves the arm its last force until the loop runs
// again and its first tick zeroes it.
//
// Faults. Any failed call on the tick is a fault: the same call site sets a
// zero force (best effort) and marks the device Lost, so read() says Lost in
// the same tick and the servo's safety layer renders nothing and ramps back
// in later. The tick keeps the SDK's error code and text in a fixed buffer;
// maintain() (housekeeping thread, about 2 Hz) reports it, closes the device
// and reopens it by its index; only one side calls the library at a time
// (the tick while Connected, maintain() while Lost).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "devices/arm_device_options.h"
#include "devices/arm_pose_mapping.h"
#include "devices/device.h"
#include "devices/device_options.h"
#include "devices/dhd_library.h"
#include "devices/dhd_models.h"
#include "rt/histogram.h"

namespace hapticut::servo {

// The SDK's frame (x towards the user, y right, z up) to the scene's (x right,
// y away, z up): scene = (y, -x, z).
inline constexpr Matrix3 kDhdToSceneAxes{{{0, 1, 0}, {-1, 0, 0}, {0, 0, 1}}};

struct DhdDeviceOptions : ArmDeviceOptions {
  DhdDeviceOptions() { mapping.axes = kDhdToSceneAxes; }
  int index = 0;  // dhdOpenID's enumeration index (the ID in forcedimension:ID).
  // The servo's watchdog (--watchdog-ms): the device firmware's is set to it, or to
  // its longest when this is longer.
  double watchdog_s = 0.1;
};

// dhdSetWatchdog's value for a watchdog of `watchdog_s`: whole 125 us units, never
// longer than asked, within 1..255 (0 would turn the firmware's watchdog off).
unsigned char dhd_watchdog_units(double watchdog_s);

struct DhdDeviceCounters {
  std::atomic<std::uint64_t> samples{0};
  std::atomic<std::uint64_t> forces_written{0};
  std::atomic<std::uint64_t> motor_saturated{0};  // dhdSetForce scaled the force down.
  std::atomic<std::uint64_t> faults{0};
  std::atomic<std::uint64_t> reconnects{0};
  std::atomic<std::uint64_t> reconnect_attempts{0};
  // The firmware's watchdog as set (us; 0: not set: no library call, or refused).
  std::atomic<std::uint64_t> firmware_watchdog_us{0};
  // Forces enabled again on the tick after a gap the firmware's watchdog outlasted.
  std::atomic<std::uint64_t> forces_reenabled{0};
};

class DhdDevice final : public Device {
 public:
  DhdDevice(std::shared_ptr<DhdLibrary> library, DhdDeviceOptions options);
  ~DhdDevice() override;

  const char* kind() const override { return "forcedimension"; }
  // The scene's view of the model's limits (mapped workspace; stiffness / scale).
  DeviceLimits limits() const override { return limits_; }

  // Opens the device at the options' index and reads its type and force
  // limit. The factory calls it; throws std::runtime_error saying what to do.
  void open();
  // Enables the force (the device pushes nothing until the servo writes).
  void start() override;
  // Zero force, dhdStop (forces off, brakes on), dhdClose.
  void stop() override;
  DeviceStatus read(double now_s, DeviceSample& sample) override;
  void write(const Vec3& force_N, const Vec3& torque_N_mm) override;
  void maintain() override;
  // samples, forces_written, motor_saturated, faults, reconnects, reconnect_attempts,
  // firmware_watchdog_us, forces_reenabled, sample_to_force_ns_p50, sample_to_force_ns_p99.
  std::vector<std::pair<std::string, std::uint64_t>> status_counters() const override;
  std::string last_error() const override;

  bool connected() const { return connection_.load(std::memory_order_acquire) == kConnected; }
  const DhdModel& model() const { return model_; }
  char sdk_id() const { return id_; }  // The SDK's ID while open.
  const DhdDeviceCounters& counters() const { return counters_; }
  // "" before start() and while the firmware's watchdog is set; else why it is not
  // and what a stalled loop then leaves on the arm. Not real-time.
  std::string firmware_watchdog_warning() const;
  // From dhdGetPosition's return to the dhdSetForce of the force the tick
  // computed from that sample: the tick's own compute between read and write.
  const LatencyHistogram& sample_to_force() const { return sample_to_force_; }

 private:
  enum : std::uint32_t { kConnected = 0, kLost = 1 };

  // Tick side: a failed call; zero force, keep the error, Lost.
  DeviceStatus fault(const char* call);
  // Before forces are enabled: sets the firmware's watchdog; "" or a warning.
  std::string set_firmware_watchdog();
  void set_error(std::string error);

  std::shared_ptr<DhdLibrary> library_;
  DhdDeviceOptions options_;
  ArmPoseMapping mapping_;
  DhdModel model_;
  DeviceLimits limits_;
  char id_ = -1;  // The SDK's device ID while open.
  bool open_ = false;
  bool force_enabled_ = false;

  std::atomic<std::uint32_t> connection_{kLost};
  // The tick's last failure, written before connection_ turns Lost and read
  // by maintain() after: a fixed buffer, no allocation on the tick.
  const char* fault_call_ = "";
  int fault_code_ = 0;
  char fault_text_[160] = {};

  DeviceSample last_sample_;
  double sample_read_s_ = 0.0;     // Tick: when dhdGetPosition returned the last sample.
  bool sample_unwritten_ = false;  // Tick: no force written since that sample.
  // The firmware's watchdog as set (s; 0: none) and the last force command's time:
  // written by start() and maintain() before connection_ turns Connected, then the tick's.
  double firmware_watchdog_s_ = 0.0;
  double last_force_command_s_ = 0.0;
  LatencyHistogram sample_to_force_;
  DhdDeviceCounters counters_;
  mutable std::mutex error_mutex_;  // Not real-time: open, maintain() and status lines.
  std::string last_error_;
  std::string watchdog_warning_;  // Under error_mutex_.
};

// One device the library sees, for --list-devices.
struct DhdDeviceRow {
  int index = 0;
  int system_type = -1;  // -1: could not be opened (error says why).
  std::string model;
  std::string binding;  // "forcedimension:INDEX"
  DeviceLimits limits;  // With the default mapping, as a binding without options gets.
  std::string error;
  // Whether the firmware's watchdog can be set (the library has dhdSetWatchdog and the
  // device answers dhdGetWatchdog); else the warning says why not and what it means.
  bool firmware_watchdog = false;
  std::string firmware_watchdog_warning;
};
struct DhdListing {
  bool library_found = false;
  std::string library;  // Its path, or why it was not loaded.
  std::string error;    // dhdGetDeviceCount's failure, if any.
  std::vector<DhdDeviceRow> devices;
};
// Loads the library (dhd_library.h) and opens each device in turn to read
// its type and limits, closing it again (a device another program holds is
// listed with the SDK's error). Never throws.
DhdListing list_dhd_devices();
// Lines for --list-devices: where the library is (or why not), then one line per device.
std::string format_dhd_listing(const DhdListing& listing);

// `--device NAME=forcedimension[:[ID][,options]]` (kDhdDeviceUsage).
inline constexpr const char* kDhdDeviceUsage =
    "  forcedimension:[ID][,scale=S][,offset=X:Y:Z][,max_force=N][,max_stiffness=N_PER_MM]\n"
    "      a Force Dimension arm or Novint Falcon through the DHD library, loaded at run time\n"
    "      ($HAPTICUT_DHD_LIB, else libdhd.so; docs/devices.md)\n";
// Parses the options, loads the library and opens the device. Throws
// std::invalid_argument (bad option) or std::runtime_error (library, device).
// `watchdog_s` (> 0): the servo's --watchdog-ms, for the firmware's watchdog.
std::unique_ptr<DhdDevice> make_dhd_device(const std::string& bare_id, const DeviceOptions& options,
                                           double watchdog_s = 0.0);
DhdDeviceOptions dhd_device_options(const std::string& bare_id, const DeviceOptions& options);

}  // namespace hapticut::servo
