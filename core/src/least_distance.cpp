#include "hapticut/least_distance.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hapticut {

namespace {

constexpr int kRows = kNonnegativeMaxRows;
constexpr int kColumns = kLeastDistanceMaxConstraints;

// min |A x - f| over x >= 0 (Lawson and Hanson's NNLS), A of `rows` x
// `columns`, stored by column. Returns false when its iterations run out.
struct Nnls {
  int rows = 0;
  int columns = 0;
  std::array<NonnegativeColumn, kColumns> column{};
  std::array<double, kRows> f{};
  std::array<double, kColumns> x{};

  // Least squares on the passive columns (normal equations, Cholesky: at most
  // kRows columns, kept independent by the caller). False when they are not.
  bool solve_passive(const std::array<int, kColumns>& passive, int count,
                     std::array<double, kColumns>& z) const {
    std::array<std::array<double, kRows>, kRows> g{};
    std::array<double, kRows> rhs{};
    for (int p = 0; p < count; ++p) {
      const auto& cp = column[passive[p]];
      for (int q = 0; q <= p; ++q) {
        const auto& cq = column[passive[q]];
        double s = 0.0;
        for (int r = 0; r < rows; ++r) s += cp[r] * cq[r];
        g[p][q] = s;
      }
      double s = 0.0;
      for (int r = 0; r < rows; ++r) s += cp[r] * f[r];
      rhs[p] = s;
    }
    // Cholesky in place (lower triangle).
    for (int p = 0; p < count; ++p) {
      for (int q = 0; q <= p; ++q) {
        double s = g[p][q];
        for (int k = 0; k < q; ++k) s -= g[p][k] * g[q][k];
        if (p == q) {
          if (!(s > 1e-13 * (1.0 + std::abs(g[p][p])))) return false;
          g[p][p] = std::sqrt(s);
        } else {
          g[p][q] = s / g[q][q];
        }
      }
    }
    std::array<double, kRows> w{};
    for (int p = 0; p < count; ++p) {
      double s = rhs[p];
      for (int k = 0; k < p; ++k) s -= g[p][k] * w[k];
      w[p] = s / g[p][p];
    }
    for (int p = count - 1; p >= 0; --p) {
      double s = w[p];
      for (int k = p + 1; k < count; ++k) s -= g[k][p] * w[k];
      w[p] = s / g[p][p];
    }
    for (int p = 0; p < count; ++p) z[passive[p]] = w[p];
    return true;
  }

  // The gradient's negative, A^T (f - A x).
  void dual(std::array<double, kColumns>& w) const {
    std::array<double, kRows> residual = f;
    for (int j = 0; j < columns; ++j) {
      if (x[j] == 0.0) continue;
      for (int r = 0; r < rows; ++r) residual[r] -= column[j][r] * x[j];
    }
    for (int j = 0; j < columns; ++j) {
      double s = 0.0;
      for (int r = 0; r < rows; ++r) s += column[j][r] * residual[r];
      w[j] = s;
    }
  }

  bool solve() {
    std::array<bool, kColumns> in_passive{};
    std::array<bool, kColumns> barred{};  // Would make the passive columns dependent.
    std::array<int, kColumns> passive{};
    std::array<double, kColumns> w{};
    std::array<double, kColumns> z{};
    int count = 0;
    constexpr double kDualTolerance = 1e-12;
    for (int outer = 0; outer < 3 * kColumns; ++outer) {
      dual(w);
      int best = -1;
      for (int j = 0; j < columns; ++j) {
        if (in_passive[j] || barred[j] || !(w[j] > kDualTolerance)) continue;
        if (best < 0 || w[j] > w[best]) best = j;
      }
      if (best < 0) return true;
      if (count == rows) {
        barred[best] = true;
        continue;
      }
      passive[count++] = best;
      in_passive[best] = true;
      bool first = true;
      for (int inner = 0; inner < 3 * kColumns; ++inner) {
        z.fill(0.0);
        if (!solve_passive(passive, count, z) || (first && !(z[best] > 0.0))) {
          // The new column adds nothing the others lack (or, by rounding, would
          // enter at zero): leave it out until the others change.
          in_passive[best] = false;
          --count;
          barred[best] = true;
          break;
        }
        first = false;
        bool all_positive = true;
        for (int p = 0; p < count; ++p) all_positive = all_positive && z[passive[p]] > 0.0;
        if (all_positive) {
          for (int p = 0; p < count; ++p) x[passive[p]] = z[passive[p]];
          barred.fill(false);
          break;
        }
        double alpha = 1.0;
        for (int p = 0; p < count; ++p) {
          const int j = passive[p];
          if (z[j] <= 0.0) alpha = std::min(alpha, x[j] / (x[j] - z[j]));
        }
        for (int p = 0; p < count; ++p) {
          const int j = passive[p];
          x[j] += alpha * (z[j] - x[j]);
        }
        int kept = 0;
        for (int p = 0; p < count; ++p) {
          const int j = passive[p];
          if (x[j] > 1e-15) {
            passive[kept++] = j;
          } else {
            x[j] = 0.0;
            in_passive[j] = false;
          }
        }
        count = kept;
      }
    }
    return false;
  }
};

}  // namespace

bool solve_nonnegative_least_squares(int rows, std::span<const NonnegativeColumn> columns,
                                     const NonnegativeColumn& f, std::span<double> x) {
  Nnls nnls;
  nnls.rows = rows;
  nnls.columns = static_cast<int>(columns.size());
  std::copy(columns.begin(), columns.end(), nnls.column.begin());
  nnls.f = f;
  const bool finished = nnls.solve();
  std::copy_n(nnls.x.begin(), columns.size(), x.begin());
  return finished;
}

namespace {

// One pass of Lawson and Hanson's LDP: y gets the NNLS residual's answer, or
// Infeasible when the residual is zero (no y meets every row).
LeastDistanceStatus least_distance_pass(int unknowns, std::span<const LeastDistanceRow> rows,
                                        std::span<const double> bounds,
                                        std::array<double, kLeastDistanceMaxUnknowns>& y) {
  y.fill(0.0);
  bool any_binding = false;
  for (double b : bounds) any_binding = any_binding || b > 0.0;
  if (!any_binding) return LeastDistanceStatus::Solved;  // y = 0 meets every row.
  // Lawson and Hanson: with E = [G^T; h^T] and f = (0, ..., 0, 1), the NNLS
  // residual r = E u - f gives y = -r[0..n) / r[n], or none when r = 0.
  Nnls nnls;
  nnls.rows = unknowns + 1;
  nnls.columns = static_cast<int>(rows.size());
  for (int j = 0; j < nnls.columns; ++j) {
    for (int i = 0; i < unknowns; ++i) nnls.column[j][i] = rows[j].a[i];
    nnls.column[j][unknowns] = bounds[j];
  }
  nnls.f[unknowns] = 1.0;
  const bool finished = nnls.solve();
  std::array<double, kRows> r{};
  for (int i = 0; i <= unknowns; ++i) r[i] = -nnls.f[i];
  for (int j = 0; j < nnls.columns; ++j) {
    for (int i = 0; i <= unknowns; ++i) r[i] += nnls.column[j][i] * nnls.x[j];
  }
  double length = 0.0;
  for (int i = 0; i <= unknowns; ++i) length += r[i] * r[i];
  if (!(std::sqrt(length) > 1e-12) || !(std::abs(r[unknowns]) > 1e-300)) {
    return LeastDistanceStatus::Infeasible;
  }
  for (int i = 0; i < unknowns; ++i) y[i] = -r[i] / r[unknowns];
  return finished ? LeastDistanceStatus::Solved : LeastDistanceStatus::IterationLimit;
}

// How far y misses the rows, each against its own scale: the least of
// (rows[j] . y - bounds[j]) / (1 + sum |rows[j]_i y_i| + |bounds[j]|), and the
// shortfalls bounds[j] - rows[j] . y in `shortfall`.
double least_slack(int unknowns, std::span<const LeastDistanceRow> rows,
                   std::span<const double> bounds,
                   const std::array<double, kLeastDistanceMaxUnknowns>& y,
                   std::span<double> shortfall) {
  double least = std::numeric_limits<double>::infinity();
  for (std::size_t j = 0; j < rows.size(); ++j) {
    double s = 0.0;
    double size = 0.0;
    for (int i = 0; i < unknowns; ++i) {
      s += rows[j].a[i] * y[i];
      size += std::abs(rows[j].a[i] * y[i]);
    }
    shortfall[j] = bounds[j] - s;
    least = std::min(least, (s - bounds[j]) / (1.0 + size + std::abs(bounds[j])));
  }
  return least;
}

}  // namespace

LeastDistanceStatus solve_least_distance(int unknowns, std::span<const LeastDistanceRow> rows,
                                         std::span<const double> bounds,
                                         std::array<double, kLeastDistanceMaxUnknowns>& y) {
  LeastDistanceStatus status = least_distance_pass(unknowns, rows, bounds, y);
  if (status == LeastDistanceStatus::Infeasible) return status;
  // NNLS solves its passive columns through their normal equations, which
  // square the condition of rows that nearly repeat one another (coplanar
  // faces a rounding apart): the answer can miss a row by far more than
  // rounding. Iterative refinement: the least correction that meets what the
  // answer missed, solved the same way, is small, so its own error is small
  // against the first one's. An answer that still misses a row is none
  // (rounding can leave a residual short of zero on a problem with none).
  constexpr double kMiss = -1e-9;
  constexpr int kRefinements = 2;
  std::array<double, kLeastDistanceMaxConstraints> shortfall{};
  const std::span<double> shortfalls(shortfall.data(), rows.size());
  for (int refinement = 0;; ++refinement) {
    if (least_slack(unknowns, rows, bounds, y, shortfalls) >= kMiss) return status;
    if (refinement == kRefinements) return LeastDistanceStatus::Infeasible;
    std::array<double, kLeastDistanceMaxUnknowns> correction{};
    const LeastDistanceStatus pass = least_distance_pass(unknowns, rows, shortfalls, correction);
    if (pass == LeastDistanceStatus::Infeasible) return pass;
    if (pass == LeastDistanceStatus::IterationLimit) status = pass;
    for (int i = 0; i < unknowns; ++i) y[i] += correction[i];
  }
}

}  // namespace hapticut
