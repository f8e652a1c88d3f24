// The rigid blade's small quadratic programme, in its least-distance form:
// the y of least length with rows[j] . y >= bounds[j] for every j. Solved
// exactly by Lawson and Hanson's reduction to non-negative least squares
// ("Solving Least Squares Problems", 1974, ch. 23: LDP through NNLS): finite,
// deterministic, fixed storage, no allocation; it copes with more
// constraints than unknowns and with constraints that repeat one another.
#pragma once

#include <array>
#include <span>

namespace hapticut {

inline constexpr int kLeastDistanceMaxUnknowns = 5;
inline constexpr int kLeastDistanceMaxConstraints = 64;

struct LeastDistanceRow {
  std::array<double, kLeastDistanceMaxUnknowns> a{};
};

enum class LeastDistanceStatus { Solved, Infeasible, IterationLimit };

// unknowns in 1..kLeastDistanceMaxUnknowns, rows.size() == bounds.size() <=
// kLeastDistanceMaxConstraints. y gets the answer when Solved (and the last
// iterate, which need not be feasible, on IterationLimit).
LeastDistanceStatus solve_least_distance(int unknowns, std::span<const LeastDistanceRow> rows,
                                         std::span<const double> bounds,
                                         std::array<double, kLeastDistanceMaxUnknowns>& y);

// The solver underneath: min |A x - f| over x >= 0 (Lawson and Hanson's NNLS),
// A given by its columns, each of kNonnegativeMaxRows entries of which the first
// `rows` are used, at most kLeastDistanceMaxConstraints of them; x (one entry
// per column) gets the answer. False when its iterations ran out (x then holds
// the last iterate, feasible). Columns that repeat others are fine.
inline constexpr int kNonnegativeMaxRows = kLeastDistanceMaxUnknowns + 1;
using NonnegativeColumn = std::array<double, kNonnegativeMaxRows>;
bool solve_nonnegative_least_squares(int rows, std::span<const NonnegativeColumn> columns,
                                     const NonnegativeColumn& f, std::span<double> x);

}  // namespace hapticut
