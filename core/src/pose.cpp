#include "hapticut/pose.h"

#include <cmath>

namespace hapticut {

Vec3 Quaternion::rotate(const Vec3& v) const {
  const Vec3 u{x, y, z};
  const Vec3 t = cross(u, v) * 2.0;
  return v + t * w + cross(u, t);
}

bool Quaternion::valid() const {
  const double n = std::sqrt(w * w + x * x + y * y + z * z);
  return std::isfinite(n) && n >= kMinNorm;
}

Quaternion multiply(const Quaternion& a, const Quaternion& b) {
  return {
      a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
      a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

Quaternion Quaternion::normalized() const {
  const double n = std::sqrt(w * w + x * x + y * y + z * z);
  return {w / n, x / n, y / n, z / n};
}

Quaternion rotation_between(const Vec3& from, const Vec3& to) {
  const double c = dot(from, to);
  if (c < -1.0 + 1e-12) {
    Vec3 across1;
    Vec3 across2;
    frame_across(from, across1, across2);
    return {0.0, across1.x, across1.y, across1.z};  // Half a turn about an axis across.
  }
  const Vec3 axis = cross(from, to);
  return Quaternion{1.0 + c, axis.x, axis.y, axis.z}.normalized();
}

Quaternion nlerp(const Quaternion& a, const Quaternion& b, double s) {
  const Quaternion near = same_hemisphere(b, a);
  return Quaternion{a.w + (near.w - a.w) * s, a.x + (near.x - a.x) * s, a.y + (near.y - a.y) * s,
                    a.z + (near.z - a.z) * s}
      .normalized();
}

}  // namespace hapticut
