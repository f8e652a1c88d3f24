// The sim device: a scripted path (a file or a built-in stroke) pulling a
// virtual hand (mass, damping, a spring to the path) that also feels the
// force the servo renders, so the loop is closed as with a real hand. Its
// time is the loop's: real time, or the virtual time of --as-fast-as-possible.
// Fault injection for the tests: fail_at_s (lost from then on, until
// recover_at_s), nan_at_s (nan_ticks samples with a NaN pose), far_at_s
// (far_ticks finite but absurd samples, 1e6 mm off: the engine refuses them).
#pragma once

#include <atomic>
#include <memory>

#include "devices/device_args.h"
#include "devices/device_factory.h"
#include "devices/sim_path.h"
#include "devices/virtual_hand.h"

namespace hapticut::servo {

inline constexpr const char* kSimDeviceUsage =
    "  sim[:PATH|BUILTIN][,key=value...]   scripted path pulling a virtual hand\n"
    "      PATH: JSON {\"poses\": [[t_s, x, y, z, qw, qx, qy, qz], ...]};\n"
    "      BUILTIN: press-slide (default), press; speed=MM_PER_S (100)\n"
    "      hand=0|1 (1: virtual hand feels the force; 0: pose = path)\n"
    "      mass_kg=0.2 damping_N_s_per_mm=0.002 spring_N_per_mm=0.3\n"
    "      max_force_N=10 max_torque_N_mm=1000 hold_s=0.2 (time at the end)\n"
    "      max_stiffness_N_per_mm=K (a stiffness limit, as a profile's; 0: none)\n"
    "      fail_at_s=T recover_at_s=T nan_at_s=T nan_ticks=1 far_at_s=T far_ticks=1\n"
    "      (fault injection; far: a sample 1e6 mm off, outside the scene's workspace)\n";

struct SimOptions {
  bool hand = true;
  VirtualHandParameters hand_parameters;
  double max_force_N = 10.0;
  double max_torque_N_mm = 1000.0;
  double max_stiffness_N_per_mm = 0.0;  // 0: no limit (the default sim).
  double hold_s = 0.2;
  double fail_at_s = -1.0;  // < 0: never.
  double recover_at_s = -1.0;
  double nan_at_s = -1.0;
  int nan_ticks = 1;
  double far_at_s = -1.0;
  int far_ticks = 1;
};

// A sim device's limits with these options (force output; a stiffness limit
// only when max_stiffness_N_per_mm is given).
DeviceLimits sim_device_limits(const SimOptions& options);

// The virtual hand's longest stable step, and the longest gap between two
// reads it catches up on step by step (beyond it, it is put on its path).
inline constexpr double kMaxHandStep_s = 0.004;
inline constexpr double kMaxHandCatchUp_s = 10.0;

class SimDevice : public Device {
 public:
  SimDevice(SimPath path, const SimOptions& options);

  const char* kind() const override { return "sim"; }
  DeviceLimits limits() const override;
  void start() override;
  DeviceStatus read(double now_s, DeviceSample& sample) override;
  void write(const Vec3& force_N, const Vec3& torque_N_mm) override;
  bool finished() const override { return finished_.load(std::memory_order_relaxed); }

 private:
  // Advances the hand by dt_s to the path's time t_s.
  void step_hand(double t_s, double dt_s);

  SimPath path_;
  SimOptions options_;
  VirtualHand hand_;
  bool started_ = false;
  double start_s_ = 0.0;
  double last_s_ = 0.0;
  int nan_left_ = 0;
  int far_left_ = 0;
  Vec3 rendered_force_N_;
  DeviceSample sample_;
  std::atomic<bool> finished_{false};
};

std::unique_ptr<Device> make_sim_device(const DeviceSpec& spec, const DeviceContext& context);

}  // namespace hapticut::servo
