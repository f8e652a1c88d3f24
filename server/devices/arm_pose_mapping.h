// ArmPoseMapping: a positional arm's own frame to the scene's world frame and
// back. The device gives a position in m and a rotation matrix in its axes;
// the scene wants mm in its axes (x right, y away from the user, z up):
//   position_mm = offset_mm + scale * A (1000 * position_m),
//   rotation    = A R A^T,
// and a force on the hand goes back as A^T f (N, unscaled: the hand feels
// what the blade meets). A is a signed permutation (orthonormal), `scale`
// enlarges the hand's motion in the scene. Pure arithmetic, real-time safe.
#pragma once

#include <array>

#include "devices/device.h"

namespace hapticut::servo {

using Matrix3 = std::array<std::array<double, 3>, 3>;

struct ArmPoseMappingSettings {
  Matrix3 axes{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};  // A: device axes to scene axes.
  double scale = 1.0;                               // Scene mm per device mm.
  Vec3 offset_mm;                                   // Where the device's origin sits in the scene.
};

class ArmPoseMapping {
 public:
  explicit ArmPoseMapping(const ArmPoseMappingSettings& settings = {}) : settings_(settings) {}

  Vec3 position_mm(const Vec3& device_position_m) const;
  Quaternion rotation(const Matrix3& device_rotation) const;
  Vec3 device_force_N(const Vec3& scene_force_N) const;
  // The device's limits in scene terms: the workspace box (device mm, about
  // its origin) mapped, and the stiffness divided by the scale (a scene
  // spring k is a spring k * scale on the hand).
  DeviceLimits scene_limits(DeviceLimits device) const;

  const ArmPoseMappingSettings& settings() const { return settings_; }

 private:
  ArmPoseMappingSettings settings_;
};

// The unit quaternion of a rotation matrix (Shepperd's method: the largest
// of the four candidates divides, so no precision is lost near 180 degrees).
Quaternion matrix_quaternion(const Matrix3& m);
Vec3 multiply(const Matrix3& m, const Vec3& v);
Vec3 multiply_transposed(const Matrix3& m, const Vec3& v);

}  // namespace hapticut::servo
