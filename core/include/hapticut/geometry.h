// The numeric tests of the method, kept in one place with their tolerance
// (Geogram's predicates-apart-from-combinatorics habit): the mesh walk in
// proxy.cpp calls these and never compares floats itself.
#pragma once

#include "hapticut/tet_mesh.h"
#include "hapticut/vec3.h"

namespace hapticut {

// Eq. (6): p projected onto the (unbounded) plane.
inline Vec3 project_to_plane(const Vec3& p, const Plane& plane) {
  return p - plane.normal * plane.signed_distance(p);
}

// Eq. (9): p projected onto the line through origin with unit direction.
inline Vec3 project_to_line(const Vec3& p, const Vec3& origin, const Vec3& direction) {
  return origin + direction * dot(p - origin, direction);
}

// Repair 1 of eqs. (3)-(4): where along q->q' (parameter in [0, 1]) the
// segment leaves the half-space behind a plane, given the signed distances
// d0 of q and d1 of q'. Only a segment that really exits counts: d1 > eps and
// d1 > d0. A q already a rounding error outside gives 0. Returns a negative
// number when the segment does not exit.
inline double segment_exit_parameter(double d0, double d1, double eps) {
  if (!(d1 > eps && d1 > d0)) return -1.0;
  return d0 >= 0.0 ? 0.0 : d0 / (d0 - d1);
}

// Repair 3, the mirror of repair 1 for OUTSIDE: where q->p enters through a
// boundary plane from its front side (q in front within eps, p behind by more
// than eps). Negative when it does not enter.
inline double segment_entry_parameter(double d0, double d1, double eps) {
  if (!(d1 < -eps && d1 < d0 && d0 >= -eps)) return -1.0;
  return d0 <= 0.0 ? 0.0 : d0 / (d0 - d1);
}

// The point of triangle abc nearest to p (Ericson, Real-Time Collision Detection 5.1.5).
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace hapticut
