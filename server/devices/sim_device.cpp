#include "devices/sim_device.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hapticut::servo {

SimDevice::SimDevice(SimPath path, const SimOptions& options)
    : path_(std::move(path)), options_(options), hand_(options.hand_parameters) {}

DeviceLimits sim_device_limits(const SimOptions& options) {
  DeviceLimits limits;
  limits.has_force_output = true;
  limits.max_force_N = options.max_force_N;
  limits.max_torque_N_mm = options.max_torque_N_mm;
  limits.max_stiffness_N_per_mm = options.max_stiffness_N_per_mm;
  return limits;
}

DeviceLimits SimDevice::limits() const { return sim_device_limits(options_); }

void SimDevice::start() {
  started_ = false;
  nan_left_ = options_.nan_ticks;
  far_left_ = options_.far_ticks;
  rendered_force_N_ = Vec3{};
  sample_ = DeviceSample{};
  finished_.store(false, std::memory_order_relaxed);
}

DeviceStatus SimDevice::read(double now_s, DeviceSample& sample) {
  if (!started_) {
    started_ = true;
    start_s_ = now_s;
    last_s_ = now_s;
    hand_.reset(path_.at(0.0).position_mm);
  }
  const double t = now_s - start_s_;
  const double dt = now_s - last_s_;
  last_s_ = now_s;
  if (t > path_.duration_s() + options_.hold_s) finished_.store(true, std::memory_order_relaxed);
  const bool failed = options_.fail_at_s >= 0.0 && t >= options_.fail_at_s &&
                      !(options_.recover_at_s >= 0.0 && t >= options_.recover_at_s);
  if (failed) return DeviceStatus::Lost;
  const Pose target = path_.at(t);
  if (options_.hand) {
    step_hand(t, dt);
    sample_.pose = {hand_.position_mm(), target.rotation};
  } else {
    sample_.pose = target;
  }
  sample_.time_s = now_s;
  ++sample_.sequence;
  sample = sample_;
  if (options_.nan_at_s >= 0.0 && t >= options_.nan_at_s && nan_left_ > 0) {
    --nan_left_;
    sample.pose.position_mm.x = std::numeric_limits<double>::quiet_NaN();
  }
  if (options_.far_at_s >= 0.0 && t >= options_.far_at_s && far_left_ > 0) {
    --far_left_;
    sample.pose.position_mm.x += 1e6;
  }
  return DeviceStatus::Fresh;
}

void SimDevice::step_hand(double t_s, double dt_s) {
  // The hand's integration is stable for steps up to kMaxHandStep_s
  // (virtual_hand.h); a longer gap (a stalled servo) is integrated in steps
  // that short, along the path, with the force last written held as a real
  // device would hold it. A gap too long to be worth integrating puts the hand
  // on its path, at rest.
  if (dt_s > kMaxHandCatchUp_s) {
    hand_.reset(path_.at(t_s).position_mm);
    return;
  }
  const int steps = std::max(1, static_cast<int>(std::ceil(dt_s / kMaxHandStep_s)));
  const double step_s = dt_s / steps;
  for (int i = steps - 1; i >= 0; --i) {
    hand_.step(path_.at(t_s - i * step_s).position_mm, rendered_force_N_, step_s);
  }
}

void SimDevice::write(const Vec3& force_N, const Vec3& /*torque_N_mm*/) {
  rendered_force_N_ = force_N;
}

std::unique_ptr<Device> make_sim_device(const DeviceSpec& spec, const DeviceContext& context) {
  spec.check_options({"stroke", "speed", "hand", "mass_kg", "damping_N_s_per_mm", "spring_N_per_mm",
                      "max_force_N", "max_torque_N_mm", "max_stiffness_N_per_mm", "hold_s",
                      "fail_at_s", "recover_at_s", "nan_at_s", "nan_ticks", "far_at_s",
                      "far_ticks"});
  SimOptions options;
  options.hand = spec.number("hand", 1.0) != 0.0;
  options.hand_parameters.mass_kg = spec.number("mass_kg", options.hand_parameters.mass_kg);
  options.hand_parameters.damping_N_s_per_mm =
      spec.number("damping_N_s_per_mm", options.hand_parameters.damping_N_s_per_mm);
  options.hand_parameters.spring_N_per_mm =
      spec.number("spring_N_per_mm", options.hand_parameters.spring_N_per_mm);
  if (!(options.hand_parameters.mass_kg >= 0.01)) {
    throw DeviceError(spec.describe() + ": mass_kg must be at least 0.01");
  }
  options.max_force_N = spec.number("max_force_N", options.max_force_N);
  options.max_torque_N_mm = spec.number("max_torque_N_mm", options.max_torque_N_mm);
  options.max_stiffness_N_per_mm = spec.number("max_stiffness_N_per_mm", 0.0);
  if (!(options.max_stiffness_N_per_mm >= 0.0)) {
    throw DeviceError(spec.describe() + ": max_stiffness_N_per_mm must be >= 0 (0: no limit)");
  }
  options.hold_s = spec.number("hold_s", options.hold_s);
  options.fail_at_s = spec.number("fail_at_s", -1.0);
  options.recover_at_s = spec.number("recover_at_s", -1.0);
  options.nan_at_s = spec.number("nan_at_s", -1.0);
  options.nan_ticks = static_cast<int>(spec.number("nan_ticks", 1.0));
  options.far_at_s = spec.number("far_at_s", -1.0);
  options.far_ticks = static_cast<int>(spec.number("far_ticks", 1.0));
  const double speed = spec.number("speed", 100.0);
  const bool builtin = spec.value.empty() || spec.has("stroke") || spec.value == "press-slide" ||
                       spec.value == "press";
  try {
    SimPath path = builtin
                       ? SimPath::builtin(
                             spec.string("stroke", spec.value.empty() ? "press-slide" : spec.value),
                             context.scene_min_mm, context.scene_max_mm, speed)
                       : SimPath::from_file(spec.value);
    return std::make_unique<SimDevice>(std::move(path), options);
  } catch (const DeviceError& e) {
    throw DeviceError(spec.describe() + ": " + e.what());
  }
}

}  // namespace hapticut::servo
