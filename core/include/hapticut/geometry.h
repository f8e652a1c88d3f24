// The numeric tests of the method, kept in one place with their tolerance
// (Geogram's predicates-apart-from-combinatorics habit): the mesh walk in
// proxy.cpp calls these and never compares a float with a tolerance itself.
// What it still compares is order only: which entry or exit parameter is
// nearest and which candidate's score is widest (ties keep the first).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "hapticut/aabb_tree.h"
#include "hapticut/vec3.h"

namespace hapticut {

// An oriented plane: signed_distance(x) = dot(normal, x) - offset, normal unit
// and pointing out of the tet that owns it (eq. 2: outside when >= 0).
struct Plane {
  Vec3 normal;
  double offset = 0.0;
  double signed_distance(const Vec3& x) const { return dot(normal, x) - offset; }
};

// A fixed order of planes (normal, then offset): where several planes within
// rounding of one another could serve, the least is taken, so the answer does
// not depend on the order they were met in (a scene stored in another tet order).
inline bool plane_before(const Plane& a, const Plane& b) {
  if (a.normal.x != b.normal.x) return a.normal.x < b.normal.x;
  if (a.normal.y != b.normal.y) return a.normal.y < b.normal.y;
  if (a.normal.z != b.normal.z) return a.normal.z < b.normal.z;
  return a.offset < b.offset;
}

// Eq. (6): p projected onto the (unbounded) plane.
inline Vec3 project_to_plane(const Vec3& p, const Plane& plane) {
  return p - plane.normal * plane.signed_distance(p);
}

// Eq. (9): p projected onto the line through origin with unit direction.
inline Vec3 project_to_line(const Vec3& p, const Vec3& origin, const Vec3& direction) {
  return origin + direction * dot(p - origin, direction);
}

// Repair 1 of eqs. (3)-(4) (docs/method.md): where along q->q' (parameter in [0, 1]) the
// segment leaves the half-space behind a plane, given the signed distances
// d0 of q and d1 of q'. Only a segment that really exits counts: d1 > eps and
// d1 > d0. A q already a rounding error outside gives 0. Returns a negative
// number when the segment does not exit.
inline double segment_exit_parameter(double d0, double d1, double eps) {
  if (!(d1 > eps && d1 > d0)) return -1.0;
  return d0 >= 0.0 ? 0.0 : d0 / (d0 - d1);
}

// Repair 3 (docs/method.md), the mirror of repair 1 for OUTSIDE: where q->p enters through a
// boundary plane from its front side (q in front within eps, p behind by more
// than eps). Negative when it does not enter. (d1 < -eps <= d0 makes d1 < d0.)
inline double segment_entry_parameter(double d0, double d1, double eps) {
  if (!(d1 < -eps && d0 >= -eps)) return -1.0;
  return d0 <= 0.0 ? 0.0 : d0 / (d0 - d1);
}

// The point of triangle abc nearest to p (Ericson, Real-Time Collision Detection 5.1.5).
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

// ---- Predicates of the walk --------------------------------------------------
// Every predicate takes eps, the mesh's one tolerance (TetMesh::tolerance(),
// docs/decisions.md "Tolerance and its scale"), and the same quantities: an
// "along" value d . n, with d = p - q not normalised (how far p lies beyond
// the plane through q with outward unit normal n), or a signed distance.
// Strict means beyond eps; closed means within eps counts as on the plane.

// Eqs. (7) and (11): d points strictly into the wedge (2 planes) or cone (3
// planes) that the planes through q bound: the tet lies toward p.
template <std::size_t count>
constexpr bool points_strictly_into(const std::array<double, count>& along, double eps) {
  for (const double a : along) {
    if (!(a < -eps)) return false;
  }
  return true;
}

// Repair 2 (docs/method.md): d points strictly out of the closed wedge or cone: past one of
// its planes by more than eps. Only then may a walk leave the mesh there.
template <std::size_t count>
constexpr bool points_strictly_out_of(const std::array<double, count>& along, double eps) {
  for (const double a : along) {
    if (a > eps) return true;
  }
  return false;
}

// Whether two points (or a displacement d) are within eps of each other: "no
// motion" for a step (docs/method.md, repair 5: a change of q under the tolerance is no change).
inline bool within_tolerance(const Vec3& d, double eps) { return squared_norm(d) <= eps * eps; }

// One plane's half of the tests above: a signed distance or along value
// strictly beyond the plane (past it by more than eps), or on or beyond it
// (closed: within eps counts as on it).
constexpr bool strictly_beyond(double distance, double eps) { return distance > eps; }
constexpr bool on_or_beyond(double distance, double eps) { return distance >= -eps; }

// Eqs. (8) and (12), toward a wedge: the target projected onto face plane m,
// p' = p - n_m h with h = sd_m(p), points strictly into the half-space of
// another plane g through q: (p' - q) . n_g = (d . n_g) - h (n_m . n_g) < -eps,
// written without forming p'.
constexpr bool projected_strictly_into(double along_other, double height, double normals_dot,
                                       double eps) {
  return along_other - height * normals_dot < -eps;
}

// Eq. (10), beyond an edge's end: x, slid along the edge line with unit
// direction a from its start o0 toward its end o1, has reached or passed o0
// (going backwards) or o1. Exact (no eps): at an end the vertex takes over.
inline bool beyond_edge_start(const Vec3& x, const Vec3& o0, const Vec3& direction) {
  return dot(x - o0, direction) <= 0.0;
}
inline bool beyond_edge_end(const Vec3& x, const Vec3& o1, const Vec3& direction) {
  return dot(x - o1, direction) >= 0.0;
}

// Where a point lies against one side plane of a triangle (eq. 14 with
// repair 4, docs/method.md): inside, on the rim (within eps), or outside the triangle.
enum class RimSide : std::uint8_t { Inside, OnRim, Outside };
constexpr RimSide side_of_rim(double side_distance, double eps) {
  if (side_distance > eps) return RimSide::Outside;
  return side_distance >= -eps ? RimSide::OnRim : RimSide::Inside;
}

// FACE (b) ending on an edge: the slide's end q' lies on
// the plane of another face of the tet (|d1| <= eps: on the edge line) and
// the target p' does not lie strictly behind that plane as seen from q
// ((p' - q) . n >= -eps). Then the slide has reached the edge, and the edge's
// fan decides where the proxy goes; EDGE's (a-3) picks this face back only
// when (p' - q) . n < -eps, the exact complement, so the two never ping-pong.
constexpr bool slide_reaches_edge(double end_distance, double target_along, double eps) {
  return end_distance >= -eps && end_distance <= eps && target_along >= -eps;
}

// ---- Boxes of the OUTSIDE state ----------------------------------------------

// The box grown by pad on every side.
Aabb grown(const Aabb& box, double pad);

// The mesh's box (mesh_box with no pad) grown by its own diagonal on every
// side: every point of the mesh is farther than one diagonal from the outside
// of this box. From the mesh's box, so a caller that needs several of these
// boxes passes over the vertices once.
Aabb reach_box(const Aabb& tight_box);

// The mesh's box grown by a thousandth of its diagonal and a thousand
// tolerances: every point an OUTSIDE entry search can accept (a crossing of a
// boundary face within the tolerance of its triangle, however sharp its
// corners) lies inside it, so a segment beyond one of its faces enters nowhere.
Aabb entry_box(const Aabb& tight_box, double tolerance_mm);

// The part of segment a->b inside box: an OUTSIDE entry
// search on a->b computes the same entry on start->end, but with both ends
// near the mesh, so q + d s keeps its precision for any finite a and b (a
// jump from 1e18 mm loses every digit otherwise). An end inside the box is
// returned bit for bit; a clipped end lies exactly on the box's surface, so
// it is outside the mesh. hits is false when the segment misses the box.
struct ClippedSegment {
  bool hits = false;
  Vec3 start;
  Vec3 end;
};
ClippedSegment clip_far_segment_to_box(const Vec3& a, const Vec3& b, const Aabb& box);

// Whether the closed box holds x; inline, as OUTSIDE asks it every step and
// the blade for every point. Bitwise, not short-circuit: no branch per axis.
inline bool box_holds(const Aabb& box, const Vec3& x) {
  return static_cast<bool>((x.x >= box.lo.x) & (x.x <= box.hi.x) & (x.y >= box.lo.y) &
                           (x.y <= box.hi.y) & (x.z >= box.lo.z) & (x.z <= box.hi.z));
}

// The box of segment a->b: its ends' componentwise min and max (finite ends).
inline Aabb segment_box(const Vec3& a, const Vec3& b) {
  return {{std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)},
          {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}};
}

// The box of a moving segment, a0 -> b0 moved to a1 -> b1 (each end along a
// straight chord, so every point of the motion lies in its ends' hull),
// grown by pad on every side.
inline Aabb motion_box(const Vec3& a0, const Vec3& b0, const Vec3& a1, const Vec3& b1, double pad) {
  Aabb box = segment_box(a0, b0);
  box.grow(a1);
  box.grow(b1);
  const Vec3 margin{pad, pad, pad};
  return {box.lo - margin, box.hi + margin};
}

// Whether box `inner` (a segment's, segment_box) lies wholly beyond one face
// of the closed `box`: below its lo or above its hi on one axis. Then the
// segment meets nothing inside the box. Exact, no division; bitwise like box_holds.
inline bool box_beyond_face(const Aabb& inner, const Aabb& box) {
  return static_cast<bool>((inner.hi.x < box.lo.x) | (inner.lo.x > box.hi.x) |
                           (inner.hi.y < box.lo.y) | (inner.lo.y > box.hi.y) |
                           (inner.hi.z < box.lo.z) | (inner.lo.z > box.hi.z));
}

// Whether the closed `box` holds box `inner` (both ends of a segment, when
// inner is its segment_box).
inline bool box_holds_box(const Aabb& box, const Aabb& inner) {
  return static_cast<bool>((inner.lo.x >= box.lo.x) & (inner.hi.x <= box.hi.x) &
                           (inner.lo.y >= box.lo.y) & (inner.hi.y <= box.hi.y) &
                           (inner.lo.z >= box.lo.z) & (inner.hi.z <= box.hi.z));
}

// clip_far_segment_to_box, with the common case (both ends inside) inline.
inline ClippedSegment clip_segment_to_box(const Vec3& a, const Vec3& b, const Aabb& box) {
  if (box_holds(box, a) && box_holds(box, b)) return {true, a, b};
  return clip_far_segment_to_box(a, b, box);
}

// Two unit vectors across `direction`, with it a right-handed frame.
void frame_across(const Vec3& direction, Vec3& across1, Vec3& across2);

}  // namespace hapticut
