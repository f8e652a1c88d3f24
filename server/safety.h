// SafetyChannel: the layer between the engine and one device, on by default.
// Per tick, in this order:
//   before the engine steps (admit): the tick's own lateness and the device's
//     status and sample are checked: a tick that starts more than the watchdog
//     time after the last one (a stall: SIGSTOP, a swap storm), lost, watchdog
//     (no new sample for N ticks), a pose that is not finite or lies outside
//     the device's workspace. Any of these is a fault:
//     the engine does not step and the force is zero in this same tick. The
//     engine's own refusal of a sample (outside the scene's workspace, zero
//     rotation) is reported by engine_refused as the same kind of fault.
//   after it steps (render): a tick whose compute itself outlasted the watchdog
//     time (late_in_tick) and a force or torque that is not finite are faults;
//     then the passivity controller (if any), the clamp to the limits (the
//     device's, lowered by the scene or a control message), and the ramp
//     (0 -> 1 over ramp_time_s at start, at engage and after every fault;
//     1 -> 0 while stopping). No force unless engaged.
// Every flag that turns on is an event, counted and reported.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>

#include "devices/device.h"
#include "hapticut/parameter_range.h"
#include "hapticut/scene.h"
#include "passivity.h"

namespace hapticut::servo {

enum SafetyFlag : std::uint32_t {
  kSafetyEngaged = 1U << 0,
  kSafetyRamping = 1U << 1,  // Ramp factor below 1 while engaged.
  kSafetyForceClamped = 1U << 2,
  kSafetyTorqueClamped = 1U << 3,
  kSafetyDeviceLost = 1U << 4,        // Fault.
  kSafetyWatchdog = 1U << 5,          // Fault: no new sample for watchdog_ticks.
  kSafetyNonFinitePose = 1U << 6,     // Fault.
  kSafetyOutsideWorkspace = 1U << 7,  // Fault.
  kSafetyNonFiniteForce = 1U << 8,    // Fault (engine or passivity output).
  kSafetyPassivity = 1U << 9,         // The passivity controller changed the force.
  kSafetyNoForceOutput = 1U << 10,    // Input-only device: nothing is rendered.
  kSafetyStale = 1U << 11,            // No new sample this tick (not yet a fault).
  kSafetyWaiting = 1U << 12,          // No sample yet since start.
  kSafetyStopping = 1U << 13,         // Ramping down before the loop ends.
  // Fault: the engine refused the sample for a reason of its own (a rotation
  // of zero norm, settings out of range). A sample outside the scene's
  // workspace, which the engine also refuses, is kSafetyOutsideWorkspace.
  kSafetyEngineRejected = 1U << 14,
  // Fault: the tick started more than late_tick_s after the last one, or its
  // device sample spans more than that (a replayed late tick), or its compute
  // lasted longer. The engine does not step across such a gap.
  kSafetyLateTick = 1U << 15,
};
inline constexpr int kSafetyFlagCount = 16;
inline constexpr std::uint32_t kSafetyFaults =
    kSafetyDeviceLost | kSafetyWatchdog | kSafetyNonFinitePose | kSafetyOutsideWorkspace |
    kSafetyNonFiniteForce | kSafetyEngineRejected | kSafetyLateTick;
// Names in bit order, for messages and the protocol's status.
const char* safety_flag_name(int bit);

struct SafetySettings {
  // The scene file's defaults (parameter_range.h, setting_range).
  double max_force_N = setting_range::kMaxForce.default_value;
  double max_torque_N_mm = setting_range::kMaxTorque.default_value;
  double ramp_time_s = setting_range::kRampTime.default_value;
  double stop_ramp_time_s = 0.1;  // Ramp down on stop, SIGINT, SIGTERM.
  int watchdog_ticks = 50;
  // A tick later than this after the last one is a fault, and no engine step
  // spans more (--watchdog-ms).
  double late_tick_s = 0.1;
  std::uint32_t engage_buttons = 0;  // Device buttons that engage while held (0: none).
};

// Limits in force: the device's, lowered (never raised) by `requested`.
SafetySettings limit_to_device(const SafetySettings& requested, const DeviceLimits& device);

// The coupling stiffness a blade steps with: `requested`, lowered to `limit`
// when a limit is known (limit > 0). Never raises it.
inline double stiffness_in_force(double requested_N_per_mm, double limit_N_per_mm) {
  return limit_N_per_mm > 0.0 && requested_N_per_mm > limit_N_per_mm ? limit_N_per_mm
                                                                     : requested_N_per_mm;
}

// The coupling springs a blade renders in parallel at its tool: a rigid
// blade's points all hold one pose, so pressed on a wall it pushes back with
// the sum of its springs, n k, whatever length of edge touches; independent
// points each carry their own spring, so one point's k is what a device's
// limit (stated for one spring, f = k (q - p)) is about.
inline int rendered_springs(BladeCoupling coupling, int points) {
  return coupling == BladeCoupling::Rigid ? std::max(points, 1) : 1;
}

// The limit on a blade's coupling stiffness k (each point's spring): the
// device's limit on what the blade renders (stiffness_limit) shared among its
// rendered springs, so that springs x k stays within it. 0: none known.
inline double point_stiffness_limit(double device_limit_N_per_mm, int springs) {
  return device_limit_N_per_mm > 0.0 ? device_limit_N_per_mm / std::max(springs, 1) : 0.0;
}

struct SafetyOutput {
  Vec3 force_N;
  Vec3 torque_N_mm;
  double ramp = 0.0;
  std::uint32_t flags = 0;
  std::uint32_t events = 0;  // Flags that turned on this tick.
};

class SafetyChannel {
 public:
  SafetyChannel(const SafetySettings& settings, const DeviceLimits& limits);

  // New run: waiting for a first sample, ramp at 0, passivity reset.
  void restart();
  // Limits changed by a control message (already limited to the device's).
  void set_settings(const SafetySettings& settings) { settings_ = settings; }
  const SafetySettings& settings() const { return settings_; }
  void set_passivity(std::unique_ptr<PassivityController> controller) {
    passivity_ = std::move(controller);
  }

  // Before the engine steps: may it step with this sample, `tick_gap_s` after
  // the last tick? A gap (or the sample's own dt_s) over late_tick_s is a fault.
  bool admit(DeviceStatus status, const DeviceSample& sample, double tick_gap_s = 0.0);
  // After admit, before render: the tick's compute outlasted late_tick_s, so
  // the force it computed is stale (a fault: zero force this tick).
  void late_in_tick() { tick_flags_ |= kSafetyLateTick; }
  // After admit: the engine refused the sample (a fault flag: kSafetyOutsideWorkspace
  // or kSafetyEngineRejected); render then makes the force zero this tick.
  void engine_refused(std::uint32_t fault_flag) { tick_flags_ |= fault_flag; }
  // After: the force and torque to write. engine_ok false when the engine did
  // not step (the force is then zero).
  SafetyOutput render(const Vec3& engine_force_N, const Vec3& engine_torque_N_mm, bool engine_ok,
                      double dt_s, bool engage_requested, bool stopping);

  // Rising edges of every flag since restart (index: bit number).
  const std::array<std::uint64_t, kSafetyFlagCount>& event_counts() const { return events_; }
  std::uint64_t fault_count() const { return faults_; }

 private:
  SafetySettings settings_;
  DeviceLimits limits_;
  std::unique_ptr<PassivityController> passivity_;
  std::uint32_t tick_flags_ = 0;  // Flags found by admit() this tick.
  std::uint32_t last_flags_ = 0;
  bool has_sample_ = false;
  int stale_ticks_ = 0;
  std::uint32_t buttons_ = 0;
  Vec3 last_position_mm_;
  Vec3 velocity_mm_per_s_;
  double last_sample_time_s_ = 0.0;
  double ramp_ = 0.0;
  std::array<std::uint64_t, kSafetyFlagCount> events_{};
  std::uint64_t faults_ = 0;
};

}  // namespace hapticut::servo
