// The rigid edge's fit (edge_fit.h) on its own: the edge nearest the targets
// in closed form, the same with contact planes, turned about one sample, and
// the motion between two poses.
#include "hapticut/edge_fit.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "test_support.h"

namespace hapticut {
namespace {

constexpr double kLength = 40.0;

std::vector<Vec3> targets_on(const EdgePose& edge, const std::vector<double>& f) {
  std::vector<Vec3> t;
  for (double s : f) t.push_back(edge.point(s, kLength));
  return t;
}

void expect_near(const Vec3& a, const Vec3& b, double tolerance) {
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
}

TEST(EdgeFit, TargetsOnAnEdgeGiveThatEdgeAndALockKeepsTheDirection) {
  const std::vector<double> f = testing::evenly_spaced(9);
  const Vec3 direction = Vec3{1.0, 2.0, -0.5} / norm(Vec3{1.0, 2.0, -0.5});
  const EdgePose truth{{3.0, -1.0, 7.0}, direction};
  const std::vector<Vec3> t = targets_on(truth, f);
  const EdgePose free = fit_edge(f, t, kLength, Vec3{1, 0, 0}, false);
  expect_near(free.start_mm, truth.start_mm, 1e-9);
  expect_near(free.direction, truth.direction, 1e-12);
  // Locked along x: the start that puts the samples' mean on the targets' mean.
  const EdgePose locked = fit_edge(f, t, kLength, Vec3{1, 0, 0}, true);
  expect_near(locked.direction, Vec3{1, 0, 0}, 0.0);
  expect_near(locked.point(0.5, kLength), truth.point(0.5, kLength), 1e-9);
  // Targets all in one place give no direction: the fallback's.
  const std::vector<Vec3> heap(f.size(), Vec3{1, 1, 1});
  expect_near(fit_edge(f, heap, kLength, Vec3{0, 1, 0}, false).direction, Vec3{0, 1, 0}, 0.0);
}

TEST(EdgeFit, AContactPlaneKeepsItsSampleOnItsFreeSideByTheMargin) {
  // Targets under the plane z = 0 along the whole edge, tilted: the fit
  // with contacts at both ends lays the edge on the plane, a margin above.
  const std::vector<double> f = testing::evenly_spaced(11);
  std::vector<Vec3> t;
  for (double s : f) t.push_back({s * kLength, 0.0, -1.0 - 2.0 * s});
  const EdgePose base{{0.0, 0.0, 1.0}, {1.0, 0.0, 0.0}};
  const Plane floor{{0.0, 0.0, 1.0}, 0.0};
  const std::array<EdgeContact, 2> contacts{EdgeContact{0.0, floor}, EdgeContact{1.0, floor}};
  const double margin = 1e-6;
  for (const bool lock : {false, true}) {
    EdgePose out;
    // Linearised about its base: a few passes settle the turn.
    EdgePose at = base;
    for (int pass = 0; pass < 4; ++pass) {
      ASSERT_EQ(fit_edge_constrained(at, f, t, kLength, lock, contacts, margin, out),
                EdgeFitStatus::Solved);
      at = out;
    }
    for (const EdgeContact& c : contacts) {
      EXPECT_GE(floor.signed_distance(out.point(c.fraction, kLength)), margin * 0.5) << lock;
      EXPECT_NEAR(floor.signed_distance(out.point(c.fraction, kLength)), margin, 1e-4) << lock;
    }
    EXPECT_NEAR(norm(out.direction), 1.0, 1e-12);
    if (lock) expect_near(out.direction, base.direction, 0.0);
  }
  // Two contacts that cannot both hold (a sample above one plane and below
  // another): infeasible.
  const std::array<EdgeContact, 2> clash{EdgeContact{0.5, floor},
                                         EdgeContact{0.5, Plane{{0.0, 0.0, -1.0}, 1.0}}};
  EdgePose out;
  EXPECT_EQ(fit_edge_constrained(base, f, t, kLength, true, clash, margin, out),
            EdgeFitStatus::Infeasible);
}

TEST(EdgeFit, TurnedAboutASampleThatSampleStaysAndTheRestFollowTheTargets) {
  const std::vector<double> f = testing::evenly_spaced(7);
  const EdgePose base{{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}};
  // Targets on an edge through base's sample at 0.25, tilted up by 10 degrees.
  const double a = 10.0 * M_PI / 180.0;
  const Vec3 pivot = base.point(0.25, kLength);
  std::vector<Vec3> t;
  for (double s : f)
    t.push_back(pivot + Vec3{std::cos(a), 0.0, std::sin(a)} * ((s - 0.25) * kLength));
  const EdgePose turned = fit_edge_about(base, 0.25, f, t, kLength);
  expect_near(turned.point(0.25, kLength), pivot, 1e-9);
  expect_near(turned.direction, Vec3{std::cos(a), 0.0, std::sin(a)}, 1e-12);
}

TEST(EdgeFit, AMotionMovesItsPivotSampleOnAStraightLine) {
  const EdgePose from{{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}};
  const EdgePose to{{5.0, 2.0, -1.0}, Vec3{0.0, 1.0, 1.0} / std::sqrt(2.0)};
  const double pivot = 0.3;
  const EdgePose start = interpolate_edge(from, to, 0.0, pivot, kLength);
  const EdgePose end = interpolate_edge(from, to, 1.0, pivot, kLength);
  expect_near(start.start_mm, from.start_mm, 1e-12);
  expect_near(end.start_mm, to.start_mm, 1e-12);
  expect_near(end.direction, to.direction, 1e-12);
  const Vec3 a = from.point(pivot, kLength);
  const Vec3 b = to.point(pivot, kLength);
  for (const double s : {0.1, 0.5, 0.9}) {
    const EdgePose mid = interpolate_edge(from, to, s, pivot, kLength);
    expect_near(mid.point(pivot, kLength), a + (b - a) * s, 1e-9);
    EXPECT_NEAR(norm(mid.direction), 1.0, 1e-12);
  }
}

// The bow bound: from a start on a plane to an end that far beyond it, the
// sample stays on the plane's free side at every step of the motion; an end
// only just beyond the plane does not, so the bound is what keeps it there.
TEST(EdgeFit, ASampleBeyondItsBowStaysOffThePlaneAllAlongTheMotion) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto direction = [&] {
    Vec3 d{unit(random), unit(random), unit(random)};
    while (!(norm(d) > 0.1)) d = {unit(random), unit(random), unit(random)};
    return d / norm(d);
  };
  int dipped_without_bow = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3 d0 = direction();
    // Turns from a thousandth of a radian to most of a half turn.
    const double turn = std::pow(10.0, -3.0 + 3.4 * (0.5 + 0.5 * unit(random)));
    Vec3 across = cross(d0, direction());
    across = across / norm(across);
    const Vec3 d1 = d0 * std::cos(turn) + across * std::sin(turn);
    const double pivot = 0.5 + 0.5 * unit(random);
    const double fraction = 0.5 + 0.5 * unit(random);
    const Vec3 normal = direction();
    const EdgePose from{Vec3{unit(random), unit(random), unit(random)} * 10.0, d0};
    const EdgePose to_base{from.start_mm + Vec3{unit(random), unit(random), unit(random)}, d1};
    const double bow = interpolation_bow_mm(d0, d1, fraction, pivot, kLength, normal);
    // The plane through the start's sample; the end moved along the normal so
    // that its sample lies `end_distance` beyond the plane.
    const Plane plane{normal, dot(normal, from.point(fraction, kLength))};
    for (const double extra : {0.0, bow}) {
      const double shift = extra - plane.signed_distance(to_base.point(fraction, kLength));
      const EdgePose to{to_base.start_mm + normal * shift, d1};
      double least = 0.0;
      for (int k = 1; k < 200; ++k) {
        const EdgePose mid = interpolate_edge(from, to, k / 200.0, pivot, kLength);
        least = std::min(least, plane.signed_distance(mid.point(fraction, kLength)));
      }
      if (extra == 0.0) {
        dipped_without_bow += least < -1e-9 ? 1 : 0;
      } else {
        EXPECT_GE(least, -1e-9 * (1.0 + bow)) << "trial " << trial << " bow " << bow;
      }
    }
  }
  EXPECT_GT(dipped_without_bow, 100);
}

}  // namespace
}  // namespace hapticut
