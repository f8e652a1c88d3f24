#include "hapticut/least_distance.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace hapticut {
namespace {

using Answer = std::array<double, kLeastDistanceMaxUnknowns>;

LeastDistanceRow row(double a0, double a1, double a2 = 0.0) {
  LeastDistanceRow r;
  r.a = {a0, a1, a2, 0.0, 0.0};
  return r;
}

TEST(LeastDistance, SimpleCases) {
  Answer y{};
  // Nothing binding: y = 0.
  std::vector<LeastDistanceRow> rows{row(1, 0)};
  std::vector<double> bounds{-1.0};
  EXPECT_EQ(solve_least_distance(2, rows, bounds, y), LeastDistanceStatus::Solved);
  EXPECT_EQ(y[0], 0.0);
  // y0 >= 1 and y1 >= 2, the first repeated and scaled (contacts that repeat one another).
  rows = {row(1, 0), row(0, 1), row(2, 0), row(1, 0), row(0.5, 0)};
  bounds = {1.0, 2.0, 2.0, 1.0, 0.5};
  EXPECT_EQ(solve_least_distance(2, rows, bounds, y), LeastDistanceStatus::Solved);
  EXPECT_NEAR(y[0], 1.0, 1e-12);
  EXPECT_NEAR(y[1], 2.0, 1e-12);
  // y0 + y1 >= 2: the nearest point is (1, 1).
  rows = {row(1, 1)};
  bounds = {2.0};
  EXPECT_EQ(solve_least_distance(2, rows, bounds, y), LeastDistanceStatus::Solved);
  EXPECT_NEAR(y[0], 1.0, 1e-12);
  EXPECT_NEAR(y[1], 1.0, 1e-12);
  // y0 >= 1 and -y0 >= 0 contradict each other.
  rows = {row(1, 0), row(-1, 0)};
  bounds = {1.0, 0.0};
  EXPECT_EQ(solve_least_distance(2, rows, bounds, y), LeastDistanceStatus::Infeasible);
}

// Random problems in 3 unknowns against every active set of up to 3 rows:
// the optimum is the shortest candidate that meets every row.
TEST(LeastDistance, AgreesWithEveryActiveSetOnRandomProblems) {
  std::mt19937 random(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int solved = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const int m = 1 + static_cast<int>(random() % 8);
    std::vector<LeastDistanceRow> rows(m);
    std::vector<double> bounds(m);
    for (int j = 0; j < m; ++j) {
      rows[j] = row(unit(random), unit(random), unit(random));
      bounds[j] = unit(random);
    }
    Answer y{};
    const LeastDistanceStatus status = solve_least_distance(3, rows, bounds, y);
    // Brute force over active sets of size 1..3 (and the empty one).
    double best =
        std::all_of(bounds.begin(), bounds.end(), [](double b) { return b <= 0; }) ? 0.0 : INFINITY;
    for (int mask = 1; mask < (1 << m); ++mask) {
      std::vector<int> active;
      for (int j = 0; j < m; ++j) {
        if ((mask >> j) & 1) active.push_back(j);
      }
      if (active.size() > 3) continue;
      // y = A^T w with (A A^T) w = b.
      const int k = static_cast<int>(active.size());
      double g[3][4] = {};
      for (int p = 0; p < k; ++p) {
        for (int q = 0; q < k; ++q) {
          double s = 0;
          for (int i = 0; i < 3; ++i) s += rows[active[p]].a[i] * rows[active[q]].a[i];
          g[p][q] = s;
        }
        g[p][3] = bounds[active[p]];
      }
      bool singular = false;
      for (int c = 0; c < k && !singular; ++c) {
        int pivot = c;
        for (int r = c + 1; r < k; ++r) {
          if (std::abs(g[r][c]) > std::abs(g[pivot][c])) pivot = r;
        }
        if (std::abs(g[pivot][c]) < 1e-14) {
          singular = true;
          break;
        }
        for (int i = 0; i < 4; ++i) std::swap(g[c][i], g[pivot][i]);
        for (int r = 0; r < k; ++r) {
          if (r == c) continue;
          const double f = g[r][c] / g[c][c];
          for (int i = 0; i < 4; ++i) g[r][i] -= f * g[c][i];
        }
      }
      if (singular) continue;
      double candidate[3] = {};
      for (int p = 0; p < k; ++p) {
        const double w = g[p][3] / g[p][p];
        for (int i = 0; i < 3; ++i) candidate[i] += rows[active[p]].a[i] * w;
      }
      bool feasible = true;
      for (int j = 0; j < m; ++j) {
        double s = 0;
        for (int i = 0; i < 3; ++i) s += rows[j].a[i] * candidate[i];
        feasible = feasible && s >= bounds[j] - 1e-9;
      }
      if (feasible) {
        best = std::min(best, std::sqrt(candidate[0] * candidate[0] + candidate[1] * candidate[1] +
                                        candidate[2] * candidate[2]));
      }
    }
    // A problem on the edge of having no solution has its answer far out
    // (rows nearly parallel); either verdict is then right to rounding.
    if (status == LeastDistanceStatus::Solved &&
        std::sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2]) > 50.0) {
      continue;
    }
    if (std::isinf(best)) {
      EXPECT_EQ(status, LeastDistanceStatus::Infeasible) << "trial " << trial;
      continue;
    }
    ASSERT_EQ(status, LeastDistanceStatus::Solved) << "trial " << trial;
    ++solved;
    for (int j = 0; j < m; ++j) {
      double s = 0;
      for (int i = 0; i < 3; ++i) s += rows[j].a[i] * y[i];
      EXPECT_GE(s, bounds[j] - 1e-9) << "trial " << trial << " row " << j;
    }
    EXPECT_NEAR(std::sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2]), best, 1e-7)
        << "trial " << trial;
  }
  EXPECT_GT(solved, 200);
}

// Contacts met twice through faces a rounding apart give rows that nearly
// repeat one another; the answer still meets every row (lifting along the
// first unknown always does, so none is infeasible).
TEST(LeastDistance, RowsThatNearlyRepeatOneAnotherAreStillMet) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<LeastDistanceRow> rows;
    std::vector<double> bounds;
    for (int i = 0; i < 2 + trial % 4; ++i) {
      LeastDistanceRow base;
      for (double& a : base.a) a = unit(random);
      base.a[0] = 0.5 + 0.5 * std::abs(base.a[0]);
      const double bound = 10.0 * unit(random);
      for (int copy = 0; copy < 2; ++copy) {
        LeastDistanceRow near = base;
        for (double& a : near.a) a += 1e-7 * unit(random);
        rows.push_back(near);
        bounds.push_back(bound + 1e-6 * unit(random));
      }
    }
    Answer y{};
    ASSERT_EQ(solve_least_distance(kLeastDistanceMaxUnknowns, rows, bounds, y),
              LeastDistanceStatus::Solved)
        << "trial " << trial;
    for (std::size_t j = 0; j < rows.size(); ++j) {
      // Met to rounding of the row's own terms.
      double s = 0.0;
      double size = 0.0;
      for (int i = 0; i < kLeastDistanceMaxUnknowns; ++i) {
        s += rows[j].a[i] * y[i];
        size += std::abs(rows[j].a[i] * y[i]);
      }
      EXPECT_GE(s, bounds[j] - 1e-9 * (1.0 + size + std::abs(bounds[j]))) << "trial " << trial;
    }
  }
}

}  // namespace
}  // namespace hapticut
