// Device: what the servo loop reads a tool pose from and writes a force to.
// One small interface for every backend (sim, replay, viewport, HID, UDP
// bridge, Force Dimension, OpenHaptics), one file each in server/devices/.
// The loop calls read() and write() once per tick on the real-time thread;
// they must not block, allocate, lock or log. A backend that talks to
// hardware or a socket does its I/O on its own thread at its own rate and
// hands the newest sample over through a LatestValue (rt/latest_value.h);
// read() then only copies it.
// A vendor library that runs its own servicing thread and calls us back on
// it (OpenHaptics's scheduler, hd_device.h) makes that callback the I/O thread.
// The exception is a vendor library made to be called from the haptic loop
// itself, with short non-blocking transfers (Force Dimension's DHD,
// dhd_device.h): read() and write() call it directly.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "hapticut/pose.h"
#include "hapticut/vec3.h"

namespace hapticut::servo {

// DeviceSample::buttons: bits 0-15 are the device's own buttons; this bit is
// set while the device's engage request is on (a HID puck toggles it with its
// engage button, pose_mapping.h; a bridge may set it). Each change of it sets
// the servo's engage state (servo_loop.cpp).
inline constexpr std::uint32_t kEngageRequestBit = 1U << 31;

// One sample of the tool: its pose in the scene's world frame (mm), the
// button bits, and when it was taken (seconds on CLOCK_MONOTONIC).
struct DeviceSample {
  Pose pose;
  std::uint32_t buttons = 0;
  double time_s = 0.0;
  // Increments with every new sample; the same number again means no new sample.
  std::uint64_t sequence = 0;
  // > 0: the engine steps with this dt instead of the measured tick's (replay
  // gives the recorded dt, so a replay is bit-identical). 0 for live devices.
  double dt_s = 0.0;
};

// How read() went this tick.
enum class DeviceStatus : std::uint8_t {
  Fresh,  // A new sample since the last read.
  Stale,  // No new sample; `sample` holds the last one (the watchdog counts these).
  Lost,   // The device is gone (unplugged, bridge silent, told to fail): zero force.
};

// What the device can take. The safety layer clamps to these; a scene or a
// control message may only lower them.
struct DeviceLimits {
  bool has_force_output = false;        // false: input only (viewport, SpaceMouse).
  double max_force_N = 0.0;             // Continuous force the device can render.
  double max_torque_N_mm = 0.0;         // 0 when it renders no torque.
  double max_stiffness_N_per_mm = 0.0;  // Stable stiffness at 1 kHz; 0: no limit known.
  Vec3 workspace_min_mm;                // Samples outside [min, max] are device faults.
  Vec3 workspace_max_mm;
};

// The rate a device's max_stiffness_N_per_mm is stated for.
inline constexpr double kStiffnessLimitRate_Hz = 1000.0;

// The coupling stiffness limit of `device` at a servo rate (N/mm; 0: none
// known): its max_stiffness_N_per_mm times min(1, rate_Hz / 1000). A sampled
// spring k stays passive while the device's damping exceeds k T / 2 (Colgate
// and Schenkel), so at a slower rate the same margin needs k lowered in
// proportion to the rate; a faster rate does not raise it (the profile states
// only 1 kHz). docs/servo.md, "Stiffness limit". Beside the limits it reads,
// inline, so that the servo's safety layer, the device listing and the
// stability bench (which links no servo) run the same rule.
inline double stiffness_limit(const DeviceLimits& device, double rate_Hz) {
  if (!(device.max_stiffness_N_per_mm > 0.0) || !(rate_Hz > 0.0)) return 0.0;
  return device.max_stiffness_N_per_mm * std::min(1.0, rate_Hz / kStiffnessLimitRate_Hz);
}

class Device {
 public:
  virtual ~Device() = default;
  Device() = default;
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  // The backend's name for messages ("sim", "replay", "viewport", "hid", "bridge",
  // "forcedimension", "openhaptics").
  virtual const char* kind() const = 0;
  virtual DeviceLimits limits() const = 0;

  // Opens the device and starts any I/O thread. Not real-time; may throw
  // std::runtime_error with a message naming what is wrong.
  virtual void start() {}
  // Stops the I/O thread and leaves the device pushing nothing.
  virtual void stop() {}

  // Real-time thread, once per tick: the newest sample. now_s is the tick's
  // time on CLOCK_MONOTONIC.
  virtual DeviceStatus read(double now_s, DeviceSample& sample) = 0;
  // Real-time thread, once per tick after read (zero while not engaged or on
  // a fault): the force on the hand and the torque about the tool origin,
  // world frame, already clamped by the safety layer.
  virtual void write(const Vec3& force_N, const Vec3& torque_N_mm) = 0;

  // Non-real-time housekeeping thread, about 2 Hz: reconnection attempts.
  virtual void maintain() {}

  // A scripted device (sim, replay) that has played its whole path. The
  // servo may then end the run (--exit-when-done). Any thread.
  virtual bool finished() const { return false; }
  // The tets cut before the device's first sample, in their order (a replay:
  // the recording's); the session starts from them. Empty for live devices.
  virtual std::span<const std::int32_t> initial_cuts() const { return {}; }
  // Asked at the start of every tick, before any blade reads: whether the
  // scene's cuts are reset before this tick's steps (a replay, at the tick
  // where the recorded run's were reset).
  virtual bool cut_reset_due() { return false; }

  // The backend's own counters (garbage refused, reconnections...) by name,
  // for the servo's status and statistics. Not real-time; any thread.
  virtual std::vector<std::pair<std::string, std::uint64_t>> status_counters() const { return {}; }
  // The last open or reconnection failure ("" when none), for status. Any thread.
  virtual std::string last_error() const { return {}; }
};

}  // namespace hapticut::servo
