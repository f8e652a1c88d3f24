#include "devices/arm_pose_mapping.h"

#include <algorithm>
#include <cmath>

namespace hapticut::servo {

Vec3 multiply(const Matrix3& m, const Vec3& v) {
  return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
          m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
          m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
}

Vec3 multiply_transposed(const Matrix3& m, const Vec3& v) {
  return {m[0][0] * v.x + m[1][0] * v.y + m[2][0] * v.z,
          m[0][1] * v.x + m[1][1] * v.y + m[2][1] * v.z,
          m[0][2] * v.x + m[1][2] * v.y + m[2][2] * v.z};
}

Quaternion matrix_quaternion(const Matrix3& m) {
  const double trace = m[0][0] + m[1][1] + m[2][2];
  Quaternion q;
  if (trace >= m[0][0] && trace >= m[1][1] && trace >= m[2][2]) {
    const double s = 2.0 * std::sqrt(std::max(0.0, 1.0 + trace));
    q = {0.25 * s, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s};
  } else if (m[0][0] >= m[1][1] && m[0][0] >= m[2][2]) {
    const double s = 2.0 * std::sqrt(std::max(0.0, 1.0 + m[0][0] - m[1][1] - m[2][2]));
    q = {(m[2][1] - m[1][2]) / s, 0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s};
  } else if (m[1][1] >= m[2][2]) {
    const double s = 2.0 * std::sqrt(std::max(0.0, 1.0 + m[1][1] - m[0][0] - m[2][2]));
    q = {(m[0][2] - m[2][0]) / s, (m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s};
  } else {
    const double s = 2.0 * std::sqrt(std::max(0.0, 1.0 + m[2][2] - m[0][0] - m[1][1]));
    q = {(m[1][0] - m[0][1]) / s, (m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s};
  }
  // A matrix that is no rotation (NaN, all zero) gives a quaternion the safety layer refuses.
  return q;
}

Vec3 ArmPoseMapping::position_mm(const Vec3& device_position_m) const {
  const Vec3 axes = multiply(settings_.axes, device_position_m);
  const double mm = 1000.0 * settings_.scale;
  return {settings_.offset_mm.x + mm * axes.x, settings_.offset_mm.y + mm * axes.y,
          settings_.offset_mm.z + mm * axes.z};
}

Quaternion ArmPoseMapping::rotation(const Matrix3& device_rotation) const {
  const Matrix3& a = settings_.axes;
  Matrix3 product{};  // A R A^T
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      double sum = 0.0;
      for (int k = 0; k < 3; ++k) {
        for (int l = 0; l < 3; ++l) sum += a[i][k] * device_rotation[k][l] * a[j][l];
      }
      product[i][j] = sum;
    }
  }
  return matrix_quaternion(product);
}

Vec3 ArmPoseMapping::device_force_N(const Vec3& scene_force_N) const {
  return multiply_transposed(settings_.axes, scene_force_N);
}

DeviceLimits ArmPoseMapping::scene_limits(DeviceLimits device) const {
  const double s = settings_.scale;
  // The box's eight corners mapped; a signed permutation keeps it a box.
  Vec3 low{1e300, 1e300, 1e300};
  Vec3 high{-1e300, -1e300, -1e300};
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 c{(corner & 1) ? device.workspace_max_mm.x : device.workspace_min_mm.x,
                 (corner & 2) ? device.workspace_max_mm.y : device.workspace_min_mm.y,
                 (corner & 4) ? device.workspace_max_mm.z : device.workspace_min_mm.z};
    const Vec3 mapped = position_mm({c.x / 1000.0, c.y / 1000.0, c.z / 1000.0});
    low = {std::min(low.x, mapped.x), std::min(low.y, mapped.y), std::min(low.z, mapped.z)};
    high = {std::max(high.x, mapped.x), std::max(high.y, mapped.y), std::max(high.z, mapped.z)};
  }
  device.workspace_min_mm = low;
  device.workspace_max_mm = high;
  if (s > 0.0) device.max_stiffness_N_per_mm /= s;
  return device;
}

}  // namespace hapticut::servo
