#include "hapticut/edge_fit.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace hapticut {

namespace {

constexpr int kMaxUnknowns = kLeastDistanceMaxUnknowns;
using Vector = std::array<double, kMaxUnknowns>;
using Matrix = std::array<Vector, kMaxUnknowns>;

// Cholesky of the symmetric positive definite h (lower triangle), in place.
bool cholesky(Matrix& h, int n) {
  for (int p = 0; p < n; ++p) {
    for (int q = 0; q <= p; ++q) {
      double s = h[p][q];
      for (int k = 0; k < q; ++k) s -= h[p][k] * h[q][k];
      if (p == q) {
        if (!(s > 0.0)) return false;
        h[p][p] = std::sqrt(s);
      } else {
        h[p][q] = s / h[q][q];
      }
    }
  }
  return true;
}

// Solves L w = v (forward) for the Cholesky factor L.
Vector forward(const Matrix& l, const Vector& v, int n) {
  Vector w{};
  for (int p = 0; p < n; ++p) {
    double s = v[p];
    for (int k = 0; k < p; ++k) s -= l[p][k] * w[k];
    w[p] = s / l[p][p];
  }
  return w;
}

// Solves L^T w = v (backward).
Vector backward(const Matrix& l, const Vector& v, int n) {
  Vector w{};
  for (int p = n - 1; p >= 0; --p) {
    double s = v[p];
    for (int k = p + 1; k < n; ++k) s -= l[k][p] * w[k];
    w[p] = s / l[p][p];
  }
  return w;
}

}  // namespace

EdgePose fit_edge(std::span<const double> fractions, std::span<const Vec3> targets,
                  double length_mm, const Vec3& fallback, bool lock_direction) {
  const std::size_t n = fractions.size();
  double mean_f = 0.0;
  Vec3 mean_t;
  for (std::size_t i = 0; i < n; ++i) {
    mean_f += fractions[i];
    mean_t += targets[i];
  }
  mean_f /= double(n);
  mean_t = mean_t / double(n);
  // With the start eliminated (start = mean_t - mean_f length u), the error is
  // least for u along sum (f_i - mean_f)(t_i - mean_t).
  Vec3 direction = fallback;
  if (!lock_direction && length_mm > 0.0) {
    Vec3 spread;
    for (std::size_t i = 0; i < n; ++i) spread += (targets[i] - mean_t) * (fractions[i] - mean_f);
    const double size = norm(spread);
    if (size > 1e-12 * length_mm && std::isfinite(size)) direction = spread / size;
  }
  return {mean_t - direction * (mean_f * length_mm), direction};
}

EdgeFitStatus fit_edge_constrained(const EdgePose& base, std::span<const double> fractions,
                                   std::span<const Vec3> targets, double length_mm,
                                   bool lock_direction, std::span<const EdgeContact> contacts,
                                   double margin_mm, EdgePose& out) {
  const std::size_t n = fractions.size();
  const bool turns = !lock_direction && length_mm > 0.0 && n > 1;
  const int unknowns = turns ? 5 : 3;
  Vec3 across1;
  Vec3 across2;
  frame_across(base.direction, across1, across2);
  // Unknowns: the start's move (3) and the far end's move across the
  // direction, relative to the start's (2): sample f moves by
  // d_start + f (b1 across1 + b2 across2).
  double sum_f = 0.0;
  double sum_ff = 0.0;
  Vec3 sum_m;  // Sum of m_i = x_i(base) - t_i.
  Vec3 sum_fm;
  for (std::size_t i = 0; i < n; ++i) {
    const double f = fractions[i];
    const Vec3 m = base.point(f, length_mm) - targets[i];
    sum_f += f;
    sum_ff += f * f;
    sum_m += m;
    sum_fm += m * f;
  }
  Matrix h{};
  Vector g{};
  for (int k = 0; k < 3; ++k) {
    h[k][k] = double(n);
    g[k] = sum_m[k];
  }
  if (turns) {
    for (int k = 0; k < 3; ++k) {
      h[3][k] = h[k][3] = sum_f * across1[k];
      h[4][k] = h[k][4] = sum_f * across2[k];
    }
    h[3][3] = h[4][4] = sum_ff;
    g[3] = dot(across1, sum_fm);
    g[4] = dot(across2, sum_fm);
  }
  if (!cholesky(h, unknowns)) return EdgeFitStatus::Infeasible;
  // With z = L^T delta the objective is |z - z0|^2 / 2 + constant.
  Vector minus_g{};
  for (int k = 0; k < unknowns; ++k) minus_g[k] = -g[k];
  const Vector z0 = forward(h, minus_g, unknowns);
  std::array<LeastDistanceRow, kMaxEdgeContacts> rows;
  std::array<double, kMaxEdgeContacts> bounds{};
  const std::size_t count = std::min<std::size_t>(contacts.size(), kMaxEdgeContacts);
  for (std::size_t j = 0; j < count; ++j) {
    const EdgeContact& c = contacts[j];
    const Vec3& normal = c.plane.normal;
    Vector a{normal.x, normal.y, normal.z, 0.0, 0.0};
    if (turns) {
      a[3] = c.fraction * dot(across1, normal);
      a[4] = c.fraction * dot(across2, normal);
    }
    const Vector row = forward(h, a, unknowns);  // L^-1 a: the row in z.
    double row_z0 = 0.0;
    for (int k = 0; k < unknowns; ++k) {
      rows[j].a[k] = row[k];
      row_z0 += row[k] * z0[k];
    }
    bounds[j] = margin_mm - c.plane.signed_distance(base.point(c.fraction, length_mm)) - row_z0;
  }
  std::array<double, kMaxUnknowns> y{};
  const LeastDistanceStatus status =
      solve_least_distance(unknowns, std::span<const LeastDistanceRow>(rows.data(), count),
                           std::span<const double>(bounds.data(), count), y);
  if (status == LeastDistanceStatus::Infeasible) return EdgeFitStatus::Infeasible;
  Vector z{};
  for (int k = 0; k < unknowns; ++k) z[k] = z0[k] + y[k];
  const Vector delta = backward(h, z, unknowns);
  out.start_mm = base.start_mm + Vec3{delta[0], delta[1], delta[2]};
  out.direction = base.direction;
  if (turns) {
    const Vec3 far = base.direction * length_mm + across1 * delta[3] + across2 * delta[4];
    out.direction = far / norm(far);
  }
  return status == LeastDistanceStatus::Solved ? EdgeFitStatus::Solved
                                               : EdgeFitStatus::IterationLimit;
}

EdgePose fit_edge_about(const EdgePose& base, double pivot_fraction,
                        std::span<const double> fractions, std::span<const Vec3> targets,
                        double length_mm) {
  // With x_i = c + (f_i - f_c) length u and |u| = 1, the error is least for u
  // along sum (f_i - f_c)(t_i - c).
  const Vec3 pivot = base.point(pivot_fraction, length_mm);
  Vec3 spread;
  for (std::size_t i = 0; i < fractions.size(); ++i) {
    spread += (targets[i] - pivot) * (fractions[i] - pivot_fraction);
  }
  const double size = norm(spread);
  if (!(length_mm > 0.0) || !(size > 1e-12 * length_mm) || !std::isfinite(size)) return base;
  const Vec3 direction = spread / size;
  return {pivot - direction * (pivot_fraction * length_mm), direction};
}

EdgePose interpolate_edge(const EdgePose& a, const EdgePose& b, double t, double pivot_fraction,
                          double length_mm) {
  const Vec3 from = a.point(pivot_fraction, length_mm);
  const Vec3 pivot = from + (b.point(pivot_fraction, length_mm) - from) * t;
  const Vec3 mixed = a.direction + (b.direction - a.direction) * t;
  const double size = norm(mixed);
  const Vec3 direction = size > 1e-9 ? mixed / size : a.direction;
  return {pivot - direction * (pivot_fraction * length_mm), direction};
}

double interpolation_bow_mm(const Vec3& from, const Vec3& to, double fraction,
                            double pivot_fraction, double length_mm, const Vec3& normal) {
  // The motion moves the pivot's sample straight and turns the edge to u(t),
  // the normalised mix m(t) = (1 - t) d0 + t d1 of the two unit directions: a
  // sample lies off its chord by (s - p) L (1 - |m|) u, where
  // 1 - |m| <= 1 - |m|^2 = t (1 - t) |d1 - d0|^2 and |n . u| = |n . m| / |m|
  // <= (|n . d0| + |d1 - d0|) / |m|, |m| >= sqrt(1 - |d1 - d0|^2 / 4) (and
  // |n . u| <= 1). With bow = |s - p| L |d1 - d0|^2 |n . u|max, the distance at
  // t is at least (1 - t) dist0 + t dist1 - t (1 - t) bow >= t (dist1 - bow)
  // when dist0 >= 0: never negative when dist1 >= bow.
  const double change = squared_norm(to - from);
  const double least_mix = std::sqrt(std::max(1.0 - 0.25 * change, 0.0));
  const double along = std::abs(dot(normal, from)) + std::sqrt(change);
  const double across = along < least_mix ? along / least_mix : 1.0;
  return std::abs(fraction - pivot_fraction) * length_mm * change * across;
}

}  // namespace hapticut
