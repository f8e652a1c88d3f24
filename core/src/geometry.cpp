#include "hapticut/geometry.h"

#include <algorithm>
#include <array>

namespace hapticut {

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a;
  const Vec3 ac = c - a;
  const Vec3 ap = p - a;
  const double d1 = dot(ab, ap);
  const double d2 = dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return a;
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp);
  const double d4 = dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - c;
  const double d5 = dot(ab, cp);
  const double d6 = dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  }
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

Aabb grown(const Aabb& box, double pad) {
  Aabb out = box;
  out.lo -= Vec3{pad, pad, pad};
  out.hi += Vec3{pad, pad, pad};
  return out;
}

Aabb reach_box(const Aabb& tight_box) {
  return grown(tight_box, norm(tight_box.hi - tight_box.lo));
}

Aabb entry_box(const Aabb& tight_box, double tolerance_mm) {
  return grown(tight_box, 1e-3 * norm(tight_box.hi - tight_box.lo) + 1e3 * tolerance_mm);
}

namespace {

// Where the segment o + h u, u in [0, 2], enters and leaves a box: the
// parameters, and the axis and face coordinate of the crossing (axis -1:
// the rounded parameters cross no face there, an end within rounding of it).
struct SlabCrossings {
  double u_enter = 0.0;
  double u_exit = 2.0;
  int enter_axis = -1;
  int exit_axis = -1;
  double enter_face = 0.0;
  double exit_face = 0.0;
  bool misses = false;
};

SlabCrossings cross_slabs(const Vec3& o, const Vec3& h, const Aabb& box) {
  const std::array<double, 3> origin{o.x, o.y, o.z};
  const std::array<double, 3> step{h.x, h.y, h.z};
  const std::array<double, 3> lo{box.lo.x, box.lo.y, box.lo.z};
  const std::array<double, 3> hi{box.hi.x, box.hi.y, box.hi.z};
  SlabCrossings c;
  for (int i = 0; i < 3; ++i) {
    if (step[i] == 0.0) {
      c.misses = c.misses || origin[i] < lo[i] || origin[i] > hi[i];
      continue;
    }
    const double near_face = step[i] > 0.0 ? lo[i] : hi[i];
    const double far_face = step[i] > 0.0 ? hi[i] : lo[i];
    const double u_near = (near_face - origin[i]) / step[i];
    const double u_far = (far_face - origin[i]) / step[i];
    if (u_near > c.u_enter) {
      c.u_enter = u_near;
      c.enter_axis = i;
      c.enter_face = near_face;
    }
    if (u_far < c.u_exit) {
      c.u_exit = u_far;
      c.exit_axis = i;
      c.exit_face = far_face;
    }
  }
  c.misses = c.misses || c.u_enter > c.u_exit;
  return c;
}

// The point o + h u, with the coordinate of the face it crosses set exactly
// to that face and the others kept inside the box: rounding cannot move it
// into the box's interior or off its surface.
Vec3 point_on_box_surface(const Vec3& o, const Vec3& h, double u, int axis, double face,
                          const Aabb& box) {
  std::array<double, 3> x{o.x + h.x * u, o.y + h.y * u, o.z + h.z * u};
  const std::array<double, 3> lo{box.lo.x, box.lo.y, box.lo.z};
  const std::array<double, 3> hi{box.hi.x, box.hi.y, box.hi.z};
  for (int i = 0; i < 3; ++i) x[i] = i == axis ? face : std::clamp(x[i], lo[i], hi[i]);
  return {x[0], x[1], x[2]};
}

}  // namespace

ClippedSegment clip_far_segment_to_box(const Vec3& a, const Vec3& b, const Aabb& box) {
  const bool a_inside = box_holds(box, a);
  const bool b_inside = box_holds(box, b);
  if (a_inside && b_inside) return {true, a, b};
  // Half the direction, so b - a cannot overflow: a + h u, u in [0, 2]. Each
  // clipped end is computed from the original end nearer to it (u <= 1), so
  // a far end's digits never enter it: from_b runs the same segment backward.
  const Vec3 h = b * 0.5 - a * 0.5;
  const SlabCrossings from_a = cross_slabs(a, h, box);
  const SlabCrossings from_b = cross_slabs(b, -h, box);
  // Either verdict of a miss is a graze of the surface within rounding, one
  // box margin away from the mesh: no entry there either way.
  if (from_a.misses || from_b.misses) return {};
  ClippedSegment clipped{true, a, b};
  if (!a_inside) {
    clipped.start =
        from_a.u_enter <= 1.0
            ? point_on_box_surface(a, h, from_a.u_enter, from_a.enter_axis, from_a.enter_face, box)
            : point_on_box_surface(b, -h, from_b.u_exit, from_b.exit_axis, from_b.exit_face, box);
  }
  if (!b_inside) {
    clipped.end =
        from_a.u_exit <= 1.0
            ? point_on_box_surface(a, h, from_a.u_exit, from_a.exit_axis, from_a.exit_face, box)
            : point_on_box_surface(b, -h, from_b.u_enter, from_b.enter_axis, from_b.enter_face,
                                   box);
  }
  return clipped;
}

void frame_across(const Vec3& direction, Vec3& across1, Vec3& across2) {
  // The world axis least along the direction gives a well-conditioned cross product.
  const double ax = std::abs(direction.x);
  const double ay = std::abs(direction.y);
  const double az = std::abs(direction.z);
  const Vec3 axis =
      ax <= ay && ax <= az ? Vec3{1, 0, 0} : (ay <= az ? Vec3{0, 1, 0} : Vec3{0, 0, 1});
  across1 = cross(direction, axis);
  across1 = across1 / norm(across1);
  across2 = cross(direction, across1);
}

}  // namespace hapticut
