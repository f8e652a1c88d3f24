// HannafordRyuPassivity: Hannaford and Ryu's time-domain passivity observer
// and controller ("Time-domain passivity control of haptic interfaces",
// IEEE Trans. Robotics and Automation 18(1), 2002), one per force device.
//
// The observer sums the energy the virtual environment has taken from the
// hand, W = -sum f . v dt (f the force on the hand, v the hand's velocity).
// A passive environment never has W < 0; a stiff wall behind a slow or
// late link does, and then buzzes. When the observed W would turn negative,
// the controller adds just enough damping, f' = f - alpha v with
// alpha = -W / (|v|^2 dt), to bring it back to zero.
//
// Three details beyond the paper's single-sample form, all for a sampled,
// late link (docs/stability.md):
// - the work of an interval is counted with the force actually rendered
//   during it: the force output link_delay_ticks + 1 ticks ago, not the one
//   being computed (the device holds a force until the next one arrives);
// - the force already sent but not yet observed ("in flight") is counted as
//   doing work at the newest velocity, so the controller acts before the
//   hand has been given the energy, not a link delay after;
// - lag compensation: once the energy left runs below a margin, a force
//   pushing along the motion is first damped by the environment's stiffness
//   (measured from the asked forces) times the loop's lag, which takes off
//   what a spring seen delay + 1 ticks late adds on the hand's way out. It
//   acts smoothly, before the reactive damping above has to cut the force.
//
// The safety layer (SafetyChannel::set_passivity) holds one per force device
// behind PassivityController; the session plugs one into every device with
// force output unless --no-passivity.
#pragma once

#include <array>
#include <cstdint>
#include <memory>

#include "hapticut/vec3.h"

namespace hapticut::servo {

// Where a per-device passivity controller plugs into the safety layer. The
// controller sees the force about to be rendered and the device point's
// velocity each tick and returns the force to render instead (an observer
// that damps out energy the loop would add).
// Real-time thread: no allocation, lock or system call.
class PassivityController {
 public:
  virtual ~PassivityController() = default;
  PassivityController() = default;
  PassivityController(const PassivityController&) = delete;
  PassivityController& operator=(const PassivityController&) = delete;

  // force_N: the clamped engine force; velocity_mm_per_s: the tool origin's
  // velocity from the last two samples; dt_s: the tick's duration.
  virtual Vec3 observe(const Vec3& force_N, const Vec3& velocity_mm_per_s, double dt_s) = 0;
  // After a fault or a new start: forget the energy seen so far.
  virtual void reset() {}
};

struct PassivitySettings {
  bool enabled = true;
  // Ticks between a force leaving the servo and the pose that shows its
  // effect arriving, beyond the one-tick hold (0 for a local device).
  // Fractions count: 2 ms at 500 Hz is 1.0, 1 ms at 250 Hz is 0.25.
  double link_delay_ticks = 0.0;
  // Cap on the added damping (N s/mm): a near-still hand would otherwise
  // ask for an unbounded alpha. What the cap leaves is carried as a deficit.
  double max_damping_N_s_per_mm = 0.5;
};

class HannafordRyuPassivity final : public PassivityController {
 public:
  static constexpr double kMaxLinkDelayTicks = 62.0;

  explicit HannafordRyuPassivity(const PassivitySettings& settings = {});

  // One tick: the force the environment asks for (N, on the hand), the
  // hand's velocity measured over the last tick (mm/s) and the tick (s).
  // Returns the force to render. Non-finite input: zero force, nothing counted.
  Vec3 observe(const Vec3& force_N, const Vec3& velocity_mm_per_s, double dt_s) override;

  void reset() override;
  // W: energy taken from the hand so far (mJ = N mm); >= 0 while passive.
  double observed_energy_mJ() const { return observed_energy_mJ_; }
  double last_damping_N_s_per_mm() const { return last_damping_; }
  // Ticks whose force the controller changed (lag compensation or damping).
  std::uint64_t active_ticks() const { return active_ticks_; }
  double stiffness_N_per_mm() const { return stiffness_N_per_mm_; }
  const PassivitySettings& settings() const { return settings_; }

 private:
  PassivitySettings settings_;
  std::array<Vec3, 64> outputs_{};  // Ring of rendered forces, newest at head_.
  int head_ = 0;
  int filled_ = 0;
  double observed_energy_mJ_ = 0.0;
  double last_damping_ = 0.0;
  std::uint64_t active_ticks_ = 0;
  Vec3 last_velocity_;
  bool has_velocity_ = false;
  Vec3 last_asked_N_;                // The force asked for last tick.
  double stiffness_N_per_mm_ = 0.0;  // The environment's, as last measured.
};

// link_delay_s: the device link's delay beyond the one-tick hold (0 for a
// local device), turned into ticks at rate_Hz and capped at the controller's maximum.
std::unique_ptr<PassivityController> make_passivity_controller(double link_delay_s, double rate_Hz);

}  // namespace hapticut::servo
