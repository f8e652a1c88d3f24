// The rigid blade's pose, as its edge: the first point and the unit
// direction to the last (the roll about the edge moves no point, so it is not
// part of this; the blade takes it from the device). Point i is
// start + f_i length direction, f_i in [0, 1].
//
// fit_edge: the edge nearest the targets in the springs' metric,
// sum |x_i - t_i|^2, in closed form. fit_edge_constrained: the same near a
// base edge, linearised, with contact planes each sample of the edge must
// stay on the free side of (docs/decisions.md, "The rigid blade", its solver).
// Both are deterministic and never allocate.
#pragma once

#include <span>

#include "hapticut/geometry.h"
#include "hapticut/least_distance.h"

namespace hapticut {

struct EdgePose {
  Vec3 start_mm;
  Vec3 direction{1.0, 0.0, 0.0};  // Unit.
  Vec3 point(double fraction, double length_mm) const {
    return start_mm + direction * (fraction * length_mm);
  }
};

// A plane a sample of the edge (at `fraction`) must not cross: its free side
// is signed_distance >= 0.
struct EdgeContact {
  double fraction = 0.0;
  Plane plane;
};

inline constexpr int kMaxEdgeContacts = kLeastDistanceMaxConstraints;

// The edge nearest the targets; the direction is `fallback` when the
// targets give none (one point, a zero length, targets all in one place) or
// when `lock_direction`.
EdgePose fit_edge(std::span<const double> fractions, std::span<const Vec3> targets,
                  double length_mm, const Vec3& fallback, bool lock_direction);

enum class EdgeFitStatus { Solved, Infeasible, IterationLimit };

// The edge nearest the targets (least squares, linearised about `base`:
// start moved by a vector, the far end by a vector across base.direction)
// with every contact's sample at least margin_mm on its free side, or
// Infeasible. With lock_direction, only the start moves and the direction
// stays base's (then the problem is linear and one solve is exact).
EdgeFitStatus fit_edge_constrained(const EdgePose& base, std::span<const double> fractions,
                                   std::span<const Vec3> targets, double length_mm,
                                   bool lock_direction, std::span<const EdgeContact> contacts,
                                   double margin_mm, EdgePose& out);

// The edge nearest the targets among those through base's sample at
// `pivot_fraction` (that sample held still, the edge turned about it), in
// closed form: base itself when the targets give no direction.
EdgePose fit_edge_about(const EdgePose& base, double pivot_fraction,
                        std::span<const double> fractions, std::span<const Vec3> targets,
                        double length_mm);

// The edge a fraction t of the way from a to b: the sample at
// `pivot_fraction` of the edge moves on a straight line, the direction
// normalised linear. About a contact's sample, that sample stays on its
// plane's free side all the way (a chord between two points on one side).
EdgePose interpolate_edge(const EdgePose& a, const EdgePose& b, double t, double pivot_fraction,
                          double length_mm);

// How far a sample at `fraction` may lie off its chord, along a plane's unit
// `normal`, on interpolate_edge's motion from a pose of direction `from` to
// one of direction `to` about `pivot_fraction`: a sample on the plane's free
// side at the start and at least this far on it at the end stays on the free
// side all the way.
double interpolation_bow_mm(const Vec3& from, const Vec3& to, double fraction,
                            double pivot_fraction, double length_mm, const Vec3& normal);

}  // namespace hapticut
