// Where a per-device passivity controller plugs into the safety layer
// (SafetyChannel::set_passivity). The controller sees the force about to be
// rendered and the device point's velocity each tick and returns the force to
// render instead (an observer that damps out energy the loop would add).
// Real-time thread: no allocation, lock or system call.
#pragma once

#include "hapticut/vec3.h"

namespace hapticut::servo {

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

}  // namespace hapticut::servo
