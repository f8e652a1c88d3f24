// PoseMapping: turns a puck's deflection (SpaceMouse: six axes in [-1, 1])
// into a tool pose, as rate control (deflection drives velocity, beyond a
// dead zone, times a gain) or position control (deflection is an offset
// from a home pose). Buttons: a press of the engage button toggles the
// engage request (DeviceSample bit kEngageRequestBit); a press of the
// re-home button puts the tool back at its home pose (rate control) or makes
// the pose now held the new home (position control: a clutch; the pose
// holds until the puck is let go, so a small puck reaches a large scene). The pose never leaves the
// workspace. Pure arithmetic, real-time safe.
#pragma once

#include <cstdint>

#include "devices/device.h"
#include "devices/profile.h"

namespace hapticut::servo {

// The engage request is DeviceSample bit kEngageRequestBit (devices/device.h).

struct PoseMappingSettings {
  bool rate_control = true;
  double dead_zone = 0.05;
  double translation_gain_mm_per_s = 150.0;
  double rotation_gain_rad_per_s = 1.5;
  double translation_range_mm = 40.0;
  double rotation_range_rad = 0.6;
  int engage_button = 0;  // -1: none.
  int rehome_button = 1;  // -1: none.
  Vec3 workspace_min_mm{-500, -500, -500};
  Vec3 workspace_max_mm{500, 500, 500};
};
PoseMappingSettings mapping_settings_from(const DeviceProfile& profile);

class PoseMapping {
 public:
  explicit PoseMapping(const PoseMappingSettings& settings = {}, const Pose& home = {});

  // One tick: deflection (tool frame, [-1, 1] per axis) and the raw buttons,
  // dt_s since the last update. Returns the pose; buttons() has the bits.
  const Pose& update(const Vec3& translation, const Vec3& rotation, std::uint32_t buttons,
                     double dt_s);

  void set_home(const Pose& home);
  const Pose& pose() const { return pose_; }
  const Pose& home() const { return home_; }
  bool engage_requested() const { return engage_requested_; }
  // Raw buttons with kEngageRequestBit.
  std::uint32_t buttons() const;
  const PoseMappingSettings& settings() const { return settings_; }

 private:
  PoseMappingSettings settings_;
  Pose home_;
  Pose pose_;
  std::uint32_t last_buttons_ = 0;
  bool engage_requested_ = false;
  bool clutch_held_ = false;  // Position control after a re-home: holds until the puck is let go.
};

// The dead zone applied to one axis: 0 inside, rescaled to reach 1 at full deflection.
double apply_dead_zone(double value, double dead_zone);

// exp of a rotation vector (rad) as a unit quaternion.
Quaternion rotation_vector_quaternion(const Vec3& rotation_rad);

}  // namespace hapticut::servo
