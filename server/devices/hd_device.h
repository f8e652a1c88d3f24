// HdDevice: a 3D Systems Touch, Touch X or Phantom driven through
// OpenHaptics's HD library loaded at run time (hd_library.h).
//
// Threads. OpenHaptics services the device from its own scheduler thread
// (started by hdStartScheduler); device state may be read and forces set
// only inside a haptic frame on that thread. So the callback this device
// schedules (hdScheduleAsynchronous) is its I/O thread in device.h's
// sense: each frame it reads the stylus's transform and buttons, publishes
// them newest-wins (LatestValue), and sets the newest force the servo's loop
// published. read() and write() on the loop's tick only copy through those
// two LatestValues: the loop keeps its own clock (docs/decisions.md).
//
// Safety that never waits for the loop: the callback itself sets a zero
// force when the loop's newest force is older than the watchdog (a stalled
// or ended loop), when the device is stopping, and in the frame that sees an
// HD error. An error makes the device Lost (read() says so at the next
// tick) and ends the callback after a frame that set a zero force; maintain()
// (housekeeping thread, about 2 Hz) then stops the scheduler, releases the
// device and opens it again, reading its calibration and limits before the
// force is enabled again. The library is called by one side at a time: the
// scheduler thread while it runs, open(), start(), stop() and maintain()
// while it does not (hdStopScheduler returns after the last frame).
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
#include "devices/hd_library.h"
#include "rt/histogram.h"
#include "rt/latest_value.h"

namespace hapticut::servo {

// OpenHaptics's frame (x right, y up, z towards the user) to the scene's
// (x right, y away, z up): scene = (x, -z, y).
inline constexpr Matrix3 kHdToSceneAxes{{{1, 0, 0}, {0, 0, -1}, {0, 1, 0}}};

struct HdDeviceOptions : ArmDeviceOptions {
  HdDeviceOptions() { mapping.axes = kHdToSceneAxes; }
  // hdInitDevice's device name, as Touch Setup configured it ("" : HD_DEFAULT_DEVICE).
  std::string name;
  // A loop force older than this is not rendered: the callback sets zero (the servo's
  // --watchdog-ms).
  double watchdog_s = 0.1;
};

struct HdDeviceCounters {
  std::atomic<std::uint64_t> frames{0};              // Callback frames run.
  std::atomic<std::uint64_t> samples{0};             // Samples the loop took.
  std::atomic<std::uint64_t> forces_written{0};      // Forces the loop handed over.
  std::atomic<std::uint64_t> stale_force_frames{0};  // Frames zeroed: the loop's force too old.
  std::atomic<std::uint64_t> faults{0};
  std::atomic<std::uint64_t> reconnects{0};
  std::atomic<std::uint64_t> reconnect_attempts{0};
};

class HdDevice final : public Device {
 public:
  HdDevice(std::shared_ptr<HdLibrary> library, HdDeviceOptions options);
  ~HdDevice() override;

  const char* kind() const override { return "openhaptics"; }
  // The scene's view of the device's limits (mapped workspace; stiffness / scale).
  DeviceLimits limits() const override { return limits_; }

  // hdInitDevice, the calibration (updated when the device can do it alone)
  // and the nominal limits. The factory calls it; throws std::runtime_error
  // saying what to do.
  void open();
  // Enables the force output and starts the scheduler with the callback.
  void start() override;
  // A zero force set by the callback, then hdUnschedule, hdStopScheduler, hdDisableDevice.
  void stop() override;
  DeviceStatus read(double now_s, DeviceSample& sample) override;
  void write(const Vec3& force_N, const Vec3& torque_N_mm) override;
  void maintain() override;
  // frames, samples, forces_written, stale_force_frames, faults, reconnects,
  // reconnect_attempts, sample_to_force_ns_p50, sample_to_force_ns_p99.
  std::vector<std::pair<std::string, std::uint64_t>> status_counters() const override;
  std::string last_error() const override;

  bool connected() const { return connection_.load(std::memory_order_acquire) == kConnected; }
  const HdDeviceCounters& counters() const { return counters_; }
  // From a sample's frame to the frame that set the force the loop computed from it.
  const LatencyHistogram& sample_to_force() const { return sample_to_force_; }

 private:
  enum : std::uint32_t { kConnected = 0, kLost = 1 };

  // What a frame hands the loop, and what the loop hands back.
  struct FrameSample {
    double transform[16];  // HD_CURRENT_TRANSFORM, column-major, mm.
    std::uint32_t buttons;
    double time_s;  // CLOCK_MONOTONIC at the frame.
  };
  struct ForceCommand {
    Vec3 device_force_N;   // In OpenHaptics's axes.
    double time_s;         // When the loop handed it over.
    double sample_time_s;  // The frame time of the sample it was computed from.
  };

  static hd::HDCallbackCode frame_callback(void* self);
  hd::HDCallbackCode frame();  // Scheduler thread.
  // Scheduler thread: keep the error for maintain(), then Lost.
  void fault(const char* call, const hd::HDErrorInfo& error);
  // Not real-time: init, calibration, limits (throws); `reopening` keeps the session's limits.
  void initialise(bool reopening);
  void start_scheduler();  // Throws.
  void release();          // Scheduler stopped, device disabled.
  void set_error(std::string error);

  std::shared_ptr<HdLibrary> library_;
  HdDeviceOptions options_;
  ArmPoseMapping mapping_;
  DeviceLimits limits_;
  hd::HHD handle_ = hd::kInvalidHandle;
  hd::HDSchedulerHandle callback_ = 0;
  bool open_ = false;
  bool running_ = false;  // The scheduler runs our callback.

  std::atomic<std::uint32_t> connection_{kLost};
  std::atomic<bool> stopping_{false};
  std::atomic<bool> callback_done_{false};  // The callback returned HD_CALLBACK_DONE.
  std::atomic<std::uint64_t> zeroed_while_stopping_{0};
  // The callback's failure, written before connection_ turns Lost and read by
  // maintain() after: a fixed buffer, no allocation on the scheduler thread.
  const char* fault_call_ = "";
  hd::HDErrorInfo fault_error_{};
  // Housekeeping thread: the device was released after a fault and is being reopened.
  bool reopen_pending_ = false;
  std::string fault_text_;

  LatestValue<FrameSample> samples_;          // Scheduler thread -> loop.
  LatestValue<ForceCommand> forces_;          // Loop -> scheduler thread.
  std::uint64_t samples_seen_ = 0;            // Loop thread.
  double last_sample_frame_time_s_ = 0.0;     // Loop thread.
  double last_applied_sample_time_s_ = -1.0;  // Scheduler thread.
  LatencyHistogram sample_to_force_;          // Written by the scheduler thread.
  DeviceSample last_sample_;
  HdDeviceCounters counters_;
  mutable std::mutex error_mutex_;  // Not real-time: open, maintain() and status lines.
  std::string last_error_;
};

// One device for --list-devices: the default one, or the one a name opens.
struct HdDeviceRow {
  std::string name;         // "" : the default device.
  std::string binding;      // "openhaptics" or "openhaptics:NAME"
  DeviceLimits limits;      // With the default mapping, as a binding without options gets.
  std::string calibration;  // "ok", "updated", or what the device needs.
  std::string error;
};
struct HdListing {
  bool library_found = false;
  std::string library;  // Its path, or why it was not loaded.
  std::vector<HdDeviceRow> devices;
};
// Loads the library and opens the default device (OpenHaptics has no
// enumeration: a configured name opens the others) to read its limits,
// releasing it again. Never throws.
HdListing list_hd_devices();
// Lines for --list-devices: where the library is (or why not), then the device.
std::string format_hd_listing(const HdListing& listing);

// `--device NAME=openhaptics[:[DEVICE][,options]]` (kHdDeviceUsage).
inline constexpr const char* kHdDeviceUsage =
    "  openhaptics:[DEVICE][,scale=S][,offset=X:Y:Z][,max_force=N][,max_stiffness=N_PER_MM]\n"
    "      a 3D Systems Touch, Touch X or Phantom through OpenHaptics's HD library, loaded at\n"
    "      run time ($HAPTICUT_OPENHAPTICS_LIB, else libHD.so; docs/devices.md)\n";
HdDeviceOptions hd_device_options(const std::string& bare_name, const DeviceOptions& options);
// Parses the options, loads the library and opens the device. Throws
// std::invalid_argument (bad option) or std::runtime_error (library, device).
std::unique_ptr<Device> make_hd_device(const std::string& bare_name, const DeviceOptions& options,
                                       double watchdog_s);

}  // namespace hapticut::servo
