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
// The servo's safety layer runs one per force device through its passivity
// hook: observe() and reset() have that interface's signatures, so an adapter
// (or deriving from the hook's interface) is all the wiring it needs.
#pragma once

#include <array>
#include <cstdint>

#include "hapticut/vec3.h"

namespace hapticut::servo {

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

class HannafordRyuPassivity {
 public:
  static constexpr double kMaxLinkDelayTicks = 62.0;

  explicit HannafordRyuPassivity(const PassivitySettings& settings = {});

  // One tick: the force the environment asks for (N, on the hand), the
  // hand's velocity measured over the last tick (mm/s) and the tick (s).
  // Returns the force to render. Non-finite input: zero force, nothing counted.
  Vec3 observe(const Vec3& force_N, const Vec3& velocity_mm_per_s, double dt_s);

  void reset();
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

}  // namespace hapticut::servo
