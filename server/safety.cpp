#include "safety.h"

#include <algorithm>
#include <cmath>

namespace hapticut::servo {

namespace {

constexpr const char* kFlagNames[kSafetyFlagCount] = {
    "engaged",          "ramping",   "force_clamped",   "torque_clamped",
    "device_lost",      "watchdog",  "non_finite_pose", "outside_workspace",
    "non_finite_force", "passivity", "no_force_output", "stale",
    "waiting",          "stopping",  "engine_rejected", "late_tick"};

bool pose_is_finite(const Pose& pose) {
  const Quaternion& r = pose.rotation;
  return is_finite(pose.position_mm) && std::isfinite(r.w) && std::isfinite(r.x) &&
         std::isfinite(r.y) && std::isfinite(r.z);
}

bool has_workspace(const DeviceLimits& limits) {
  return limits.workspace_min_mm.x < limits.workspace_max_mm.x ||
         limits.workspace_min_mm.y < limits.workspace_max_mm.y ||
         limits.workspace_min_mm.z < limits.workspace_max_mm.z;
}

bool inside(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  return p.x >= lo.x && p.y >= lo.y && p.z >= lo.z && p.x <= hi.x && p.y <= hi.y && p.z <= hi.z;
}

// Scales v down to length `limit` when longer; says whether it did.
bool clamp_length(Vec3& v, double limit) {
  const double length = norm(v);
  if (length <= limit) return false;
  v = length > 0.0 ? v * (limit / length) : Vec3{};
  return true;
}

}  // namespace

const char* safety_flag_name(int bit) {
  return bit >= 0 && bit < kSafetyFlagCount ? kFlagNames[bit] : "unknown";
}

SafetySettings limit_to_device(const SafetySettings& requested, const DeviceLimits& device) {
  SafetySettings s = requested;
  if (device.has_force_output) {
    s.max_force_N = std::min(s.max_force_N, device.max_force_N);
    s.max_torque_N_mm = std::min(s.max_torque_N_mm, device.max_torque_N_mm);
  }
  s.max_force_N = std::max(0.0, s.max_force_N);
  s.max_torque_N_mm = std::max(0.0, s.max_torque_N_mm);
  s.ramp_time_s = std::max(0.0, s.ramp_time_s);
  s.stop_ramp_time_s = std::max(0.0, s.stop_ramp_time_s);
  s.watchdog_ticks = std::max(1, s.watchdog_ticks);
  if (!(s.late_tick_s > 0.0)) s.late_tick_s = SafetySettings{}.late_tick_s;
  return s;
}

SafetyChannel::SafetyChannel(const SafetySettings& settings, const DeviceLimits& limits)
    : settings_(limit_to_device(settings, limits)), limits_(limits) {}

void SafetyChannel::restart() {
  tick_flags_ = 0;
  last_flags_ = 0;
  has_sample_ = false;
  stale_ticks_ = 0;
  buttons_ = 0;
  velocity_mm_per_s_ = Vec3{};
  ramp_ = 0.0;
  if (passivity_) passivity_->reset();
}

bool SafetyChannel::admit(DeviceStatus status, const DeviceSample& sample, double tick_gap_s) {
  tick_flags_ = 0;
  // Whatever the device says, nothing it reported across a stall is current,
  // and a device with force output has held the last force all along.
  if (tick_gap_s > settings_.late_tick_s || sample.dt_s > settings_.late_tick_s) {
    tick_flags_ |= kSafetyLateTick;
    return false;
  }
  if (status == DeviceStatus::Lost) {
    // Before the first sample a device is only waiting (a viewport client not
    // yet sending); after it, losing it is a fault.
    tick_flags_ |= has_sample_ ? kSafetyDeviceLost : kSafetyWaiting;
    stale_ticks_ = 0;
    return false;
  }
  if (status == DeviceStatus::Stale) {
    if (!has_sample_) {
      tick_flags_ |= kSafetyWaiting;
      return false;
    }
    tick_flags_ |= kSafetyStale;
    if (++stale_ticks_ > settings_.watchdog_ticks) {
      tick_flags_ |= kSafetyWatchdog;
      return false;
    }
  } else {
    stale_ticks_ = 0;
  }
  if (!pose_is_finite(sample.pose)) {
    tick_flags_ |= kSafetyNonFinitePose;
    return false;
  }
  if (has_workspace(limits_) &&
      !inside(sample.pose.position_mm, limits_.workspace_min_mm, limits_.workspace_max_mm)) {
    tick_flags_ |= kSafetyOutsideWorkspace;
    return false;
  }
  if (status == DeviceStatus::Fresh) {
    if (has_sample_ && sample.time_s > last_sample_time_s_) {
      velocity_mm_per_s_ =
          (sample.pose.position_mm - last_position_mm_) / (sample.time_s - last_sample_time_s_);
    }
    last_position_mm_ = sample.pose.position_mm;
    last_sample_time_s_ = sample.time_s;
  }
  buttons_ = sample.buttons;
  has_sample_ = true;
  return true;
}

SafetyOutput SafetyChannel::render(const Vec3& engine_force_N, const Vec3& engine_torque_N_mm,
                                   bool engine_ok, double dt_s, bool engage_requested,
                                   bool stopping) {
  SafetyOutput out;
  std::uint32_t flags = tick_flags_;
  Vec3 force = engine_ok ? engine_force_N : Vec3{};
  Vec3 torque = engine_ok ? engine_torque_N_mm : Vec3{};
  if (!is_finite(force) || !is_finite(torque)) {
    flags |= kSafetyNonFiniteForce;
    force = Vec3{};
    torque = Vec3{};
  }
  if (passivity_ && engine_ok && (flags & kSafetyFaults) == 0) {
    const Vec3 adjusted = passivity_->observe(force, velocity_mm_per_s_, dt_s);
    if (!is_finite(adjusted)) {
      flags |= kSafetyNonFiniteForce;
      force = Vec3{};
    } else {
      if (!(adjusted == force)) flags |= kSafetyPassivity;
      force = adjusted;
    }
  }
  if (clamp_length(force, settings_.max_force_N)) flags |= kSafetyForceClamped;
  if (clamp_length(torque, settings_.max_torque_N_mm)) flags |= kSafetyTorqueClamped;

  const bool engaged =
      engage_requested || (settings_.engage_buttons != 0 && (buttons_ & settings_.engage_buttons));
  if (engaged) flags |= kSafetyEngaged;
  const bool fault = (flags & kSafetyFaults) != 0;
  if (fault || !engaged || !engine_ok) {
    ramp_ = 0.0;  // The next force after a fault or engage ramps up from zero.
  } else if (stopping) {
    flags |= kSafetyStopping;
    ramp_ = settings_.stop_ramp_time_s > 0.0
                ? std::max(0.0, ramp_ - dt_s / settings_.stop_ramp_time_s)
                : 0.0;
  } else {
    ramp_ = settings_.ramp_time_s > 0.0 ? std::min(1.0, ramp_ + dt_s / settings_.ramp_time_s) : 1.0;
  }
  if (stopping) flags |= kSafetyStopping;
  if (engaged && ramp_ < 1.0) flags |= kSafetyRamping;
  if (!limits_.has_force_output) flags |= kSafetyNoForceOutput;
  const double gain = limits_.has_force_output ? ramp_ : 0.0;
  out.force_N = force * gain;
  out.torque_N_mm = torque * gain;
  out.ramp = ramp_;
  out.flags = flags;
  out.events = flags & ~last_flags_;
  for (int bit = 0; bit < kSafetyFlagCount; ++bit) {
    if (out.events & (1U << bit)) ++events_[bit];
  }
  if (out.events & kSafetyFaults) ++faults_;
  last_flags_ = flags;
  return out;
}

}  // namespace hapticut::servo
