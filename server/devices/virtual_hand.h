// VirtualHand: a simulated hand holding the tool, for the sim device and the
// stability bench. A point mass pulled by a spring and a damper towards the
// path's target position, that also feels the force the servo renders, so
// the loop is closed as with a real hand (a stiff wall stops it, a drag
// slows it). Orientation follows the path directly: the hand is assumed
// stiff in rotation. Semi-implicit Euler, stable for the documented ranges
// (mass >= 0.01 kg, dt <= 4 ms, spring <= 2 N/mm).
#pragma once

#include "hapticut/vec3.h"

namespace hapticut::servo {

struct VirtualHandParameters {
  double mass_kg = 0.2;               // Hand and tool together.
  double damping_N_s_per_mm = 0.002;  // Viscous damping of the arm (2 N s/m).
  double spring_N_per_mm = 0.3;       // Grip stiffness towards the intended path (300 N/m).
};

class VirtualHand {
 public:
  explicit VirtualHand(const VirtualHandParameters& parameters = {}) : parameters_(parameters) {}

  void reset(const Vec3& position_mm) {
    position_mm_ = position_mm;
    velocity_mm_per_s_ = Vec3{};
  }

  // Advances by dt_s towards `target_mm` while the device pushes the hand
  // with `rendered_force_N` (the force the servo wrote, world frame).
  void step(const Vec3& target_mm, const Vec3& rendered_force_N, double dt_s) {
    const Vec3 spring = (target_mm - position_mm_) * parameters_.spring_N_per_mm;
    const Vec3 damping = velocity_mm_per_s_ * parameters_.damping_N_s_per_mm;
    // N / kg = m/s^2 = 1000 mm/s^2.
    const Vec3 acceleration_mm_per_s2 =
        (spring - damping + rendered_force_N) * (1000.0 / parameters_.mass_kg);
    velocity_mm_per_s_ = velocity_mm_per_s_ + acceleration_mm_per_s2 * dt_s;
    position_mm_ = position_mm_ + velocity_mm_per_s_ * dt_s;
  }

  const Vec3& position_mm() const { return position_mm_; }
  const Vec3& velocity_mm_per_s() const { return velocity_mm_per_s_; }
  const VirtualHandParameters& parameters() const { return parameters_; }

 private:
  VirtualHandParameters parameters_;
  Vec3 position_mm_;
  Vec3 velocity_mm_per_s_;
};

}  // namespace hapticut::servo
