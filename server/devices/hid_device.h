// HidDevice: a HID device described by a profile (profile.h), read through a
// HidTransport (hidapi, or a scripted one in the tests).
//
// Threads. An I/O thread drains every pending input report (64-byte
// buffer) into the input state and publishes it through a LatestValue;
// it also writes the newest force report for force devices. The real-time
// read() only copies the newest state and maps it to a pose; write() only
// publishes the force. Nothing in the tick waits on the device.
//
// Reconnection is a state, not an error path (spacenavd's way): a failed
// read or write closes the device and marks it Lost (read() says so at the
// next tick, so the servo zeroes the force at once); maintain(), about 2 Hz,
// re-enumerates and reopens the device by vendor, product and serial (its
// hidraw node may have changed); the next read() is Fresh again and the
// servo's safety layer ramps the force back in. Only one side touches the
// transport at a time: the I/O thread while Connected, maintain() while Lost.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "devices/device_options.h"
#include "devices/hid_report.h"
#include "devices/hid_transport.h"
#include "devices/pose_mapping.h"
#include "devices/profile.h"
#include "rt/latest_value.h"

namespace hapticut::servo {

struct HidDeviceOptions {
  DeviceProfile profile;
  std::string path;    // Open this hidraw node (else the first interface the profile matches).
  std::string serial;  // Only this unit (else the profile's serial, if any).
  PoseMappingSettings mapping;  // Deflection devices; mapping_settings_from(profile) by default.
  Pose home;                    // Where the tool starts (deflection devices).
  bool io_thread = true;        // false: the caller runs pump() itself (tests).
  int read_timeout_ms = 2;      // The I/O thread's wait for the first report of a pass.
};
HidDeviceOptions hid_device_options(const DeviceProfile& profile);

// Counters (any thread may read them).
struct HidDeviceCounters {
  std::atomic<std::uint64_t> reports{0};          // Described reports applied.
  std::atomic<std::uint64_t> unknown_reports{0};  // Reports with an id no layout describes.
  std::atomic<std::uint64_t> wrong_length{0};     // Known id, unexpected length.
  std::atomic<std::uint64_t> disconnects{0};
  std::atomic<std::uint64_t> reconnects{0};
  std::atomic<std::uint64_t> reconnect_attempts{0};
  std::atomic<std::uint64_t> force_reports{0};  // Output reports written.
};

class HidDevice final : public Device {
 public:
  HidDevice(std::unique_ptr<HidTransport> transport, HidDeviceOptions options);
  ~HidDevice() override;

  const char* kind() const override { return "hid"; }
  DeviceLimits limits() const override { return options_.profile.limits; }

  // Finds and opens the device; throws std::runtime_error naming the profile
  // (nothing matches) or the hidraw path and the permission (cannot open).
  void start() override;
  void stop() override;
  DeviceStatus read(double now_s, DeviceSample& sample) override;
  void write(const Vec3& force_N, const Vec3& torque_N_mm) override;
  void maintain() override;
  // reports, unknown_reports, wrong_length, disconnects, reconnects,
  // reconnect_attempts, force_reports.
  std::vector<std::pair<std::string, std::uint64_t>> status_counters() const override;

  // One I/O pass: drain the pending reports (waiting up to timeout_ms for the
  // first), publish the state, write the newest force. The I/O thread's body.
  void pump(int timeout_ms);

  bool connected() const { return connection_.load(std::memory_order_acquire) == kConnected; }
  const std::string& opened_path() const { return opened_path_; }  // Not while the I/O thread runs.
  const HidDeviceCounters& counters() const { return counters_; }
  const DeviceProfile& profile() const { return options_.profile; }
  // The last open or reconnection failure, for status lines.
  std::string last_error() const override;

 private:
  enum : std::uint32_t { kConnected = 0, kLost = 1 };

  struct InputSnapshot {
    HidInputState state;
    std::uint64_t reports = 0;  // Described reports applied since this connection began.
    std::uint32_t connection = 0;
    double time_s = 0.0;
  };
  struct ForceCommand {
    Vec3 force_N;
    Vec3 torque_N_mm;
  };

  bool open_matching(std::string& error);  // Enumerates and opens; not while Connected.
  void mark_lost();
  void io_loop();
  void write_force_now(const ForceCommand& command);

  std::unique_ptr<HidTransport> transport_;
  HidDeviceOptions options_;

  // Who the device is, once opened: reconnection looks for these.
  std::uint16_t identity_product_id_ = 0;
  std::string identity_serial_;
  std::string opened_path_;

  std::atomic<std::uint32_t> connection_{kLost};
  std::atomic<std::uint32_t> connection_count_{0};  // Bumped at every (re)open.
  std::atomic<bool> running_{false};
  std::thread io_thread_;

  // I/O thread side.
  HidInputState io_state_;
  std::uint32_t io_connection_ = 0;
  std::uint64_t io_reports_ = 0;
  std::uint64_t io_force_sequence_ = 0;
  LatestValue<InputSnapshot> input_;
  LatestValue<ForceCommand> force_;

  // Real-time side.
  PoseMapping mapping_;
  DeviceSample last_sample_;
  std::uint64_t last_reports_seen_ = 0;
  std::uint32_t last_connection_seen_ = 0;
  double last_read_s_ = -1.0;

  HidDeviceCounters counters_;
  mutable std::mutex error_mutex_;  // Not real-time: start(), maintain() and status lines.
  std::string last_error_;
};

// One row of `hapticut-servo --list-devices`.
struct HidDeviceRow {
  HidDeviceInfo info;
  std::string profile;  // Name of the profile that matches, "" when none does.
};
std::vector<HidDeviceRow> list_hid_devices(HidTransport& transport,
                                           const std::vector<DeviceProfile>& profiles);
// Through the real hidapi library.
std::vector<HidDeviceRow> list_hid_devices(const std::vector<DeviceProfile>& profiles);
// The table --list-devices prints; "no HID devices found" when there are none.
std::string format_hid_device_list(const std::vector<HidDeviceRow>& rows);
// `hapticut-servo --list-devices` in one call: the shipped profiles (from
// find_profile_directory(profile_directory)), real hidapi, the table.
// Throws ProfileError or std::runtime_error with a message naming the problem.
std::string list_hid_devices_text(const std::string& profile_directory = "");

// A device kind besides hid that `--list-devices --json` offers (sim, viewport, bridge).
struct DeviceKindInfo {
  std::string kind;
  std::string binding;  // The --device text choosing it with its defaults ("bridge:port=47810").
  DeviceLimits limits;  // Its limits with those defaults.
};
// `--list-devices --json [--rate HZ]` (docs/devices.md): {"version": 1, "hidapi",
// "profile_directory", "rate_Hz", "devices": [{path, vendor_id, product_id, serial,
// manufacturer, product, usage_page, usage, interface_number, profile (null: none matches),
// binding ("hid:<profile>" or null)}], "profiles": [{name, model, binding, limits}], "kinds":
// [{kind, binding, limits}]}; limits: has_force_output, max_force_N, max_torque_N_mm,
// max_stiffness_N_per_mm (as stated, for 1 kHz; 0: none known),
// max_stiffness_N_per_mm_at_rate (the servo's limit at rate_Hz: stiffness_limit, device.h;
// 0: none known), workspace_min_mm, workspace_max_mm. rate_Hz must be positive (the
// command line checks its range).
std::string format_device_list_json(const std::vector<HidDeviceRow>& rows,
                                    const std::vector<DeviceProfile>& profiles,
                                    const std::vector<DeviceKindInfo>& kinds,
                                    const std::string& profile_directory, double rate_Hz);
// The same in one call through the real hidapi (throws as list_hid_devices_text).
std::string list_devices_json(const std::string& profile_directory,
                              const std::vector<DeviceKindInfo>& kinds, double rate_Hz);

// `--device NAME=hid:ARGS` (kHidDeviceUsage). ARGS, all optional: a bare
// first value is the profile (as profile=), then comma-separated options:
//   profile=NAME|FILE.json  the profile (else the first connected device any profile matches)
//   profiles=DIR            where profiles live (else find_profile_directory())
//   path=/dev/hidrawN       open this node
//   serial=S                only this unit
//   mode=rate|position      deflection mapping (else the profile's)
//   gain=MM_PER_S, range=MM, dead_zone=F  mapping overrides
//   home=X:Y:Z              start position of the tool (mm)
// Throws std::invalid_argument (bad option), ProfileError, std::runtime_error (no device).
inline constexpr const char* kHidDeviceUsage =
    "  hid:[PROFILE][,profile=NAME|FILE.json][,profiles=DIR][,path=/dev/hidrawN][,serial=S]\n"
    "      [,mode=rate|position][,gain=MM_PER_S][,range=MM][,dead_zone=F][,home=X:Y:Z]\n"
    "      a HID device a profile describes (SpaceMouse: docs/devices.md)\n";
std::unique_ptr<Device> make_hid_device(const std::string& bare_profile,
                                        const DeviceOptions& options);
// The same with a given transport (tests: a scripted one).
std::unique_ptr<Device> make_hid_device(const std::string& bare_profile,
                                        const DeviceOptions& options,
                                        std::unique_ptr<HidTransport> transport);
// From the ARGS text ("spacemouse-wireless,mode=position").
std::unique_ptr<Device> make_hid_device(const std::string& args);

}  // namespace hapticut::servo
