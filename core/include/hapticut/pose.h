// Rotations and poses, one definition for the engine and the servo's
// devices: a unit quaternion (w, x, y, z) and a position in mm.
#pragma once

#include "hapticut/geometry.h"

namespace hapticut {

// Quaternion (w, x, y, z) rotating the tool frame into the world; normalised
// on use. One whose norm is not finite or below kMinNorm is refused.
struct Quaternion {
  double w = 1.0;
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
  static constexpr double kMinNorm = 1e-6;
  Vec3 rotate(const Vec3& v) const;
  // The unit quaternion; only for a valid() one.
  Quaternion normalized() const;
  bool valid() const;
};

// The rotation b, then a (the Hamilton product a b).
Quaternion multiply(const Quaternion& a, const Quaternion& b);

// q, or -q (the same rotation) when that is nearer `last` (a dot product < 0).
inline Quaternion same_hemisphere(const Quaternion& q, const Quaternion& last) {
  const double d = q.w * last.w + q.x * last.x + q.y * last.y + q.z * last.z;
  return d < 0.0 ? Quaternion{-q.w, -q.x, -q.y, -q.z} : q;
}

struct Pose {
  Vec3 position_mm;  // The tool origin in the world.
  Quaternion rotation;
};

// The least rotation taking unit vector `from` onto unit vector `to` (half a
// turn about an axis across `from` when they are opposite).
Quaternion rotation_between(const Vec3& from, const Vec3& to);

// The rotation a fraction s of the way from a to b along the shorter way
// (normalised linear interpolation, b taken in a's hemisphere).
Quaternion nlerp(const Quaternion& a, const Quaternion& b, double s);

}  // namespace hapticut
