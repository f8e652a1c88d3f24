// The rigid blade's motion, not only its end pose, stays out of bone: a bone
// thinner than the points' spacing is held between two points, a blade of
// two points is held by a bone between them, and a one-tick turn cannot sweep
// the edge past a bone (swept_stretch.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "hapticut/blade.h"
#include "hapticut/edge_fit.h"
#include "test_support.h"

namespace hapticut {
namespace {

constexpr double kDt = 0.001;
constexpr double kK = 0.1;  // N/mm, the paper's.

using testing::axis;
using testing::inside_rigid;

template <class InBone>
std::shared_ptr<const Space> space_of(const MeshData& mesh, InBone in_bone) {
  return testing::labelled_space(mesh, in_bone);
}

// Samples of the ideal edge, 20 per gap between points, inside rigid material.
int samples_in_bone(const Blade& blade) {
  const Space& space = blade.space();
  int inside = 0;
  for (int i = 0; i + 1 < blade.point_count(); ++i) {
    for (int s = 0; s <= 20; ++s) {
      const Vec3 x =
          blade.ideal_point(i) + (blade.ideal_point(i + 1) - blade.ideal_point(i)) * (s / 20.0);
      inside += inside_rigid(space, x) ? 1 : 0;
    }
  }
  return inside;
}

TEST(RigidBladeSweep, ARodThinnerThanTheSpacingIsHeldBetweenTwoPoints) {
  std::printf(
      "rod across the blade between two points (spacing 2.04 mm), pressed at 10 mm/s "
      "to twice its height:\n%-9s %-7s %12s %12s %12s %8s\n",
      "width mm", "orient", "force N", "expected N", "lowest mm", "in bone");
  for (double width : {0.25, 0.5, 1.0, 2.0, 4.0}) {
    const double half = 0.5 * width;
    const MeshData mesh =
        grid_mesh(axis(-60, 60, 4, {-half, half}), axis(-8, 8, 4), axis(-16, 8, 4, {-width, 0.0}));
    const auto space = space_of(
        mesh, [&](const Vec3& c) { return std::abs(c.x) < half && c.z < 0.0 && c.z > -width; });
    for (BladeOrientation orientation : {BladeOrientation::Free, BladeOrientation::Locked}) {
      BladeSpec spec{"knife", {-50, 0, 0}, {50, 0, 0}, 50};
      spec.orientation = orientation;
      Blade blade(*space, spec);
      blade.reset({{0, 0, 1}, {}});
      const double depth = 2.0 * width;
      const int ticks = static_cast<int>(std::lround((1.0 + depth) / 0.01));
      BladeTick tick;
      double lowest = 1e9;
      int in_bone = 0;
      for (int k = 1; k <= ticks + 20; ++k) {
        tick = blade.step({{0, 0, std::max(-depth, 1.0 - 0.01 * k)}, {}}, kDt);
        for (int i = 0; i < blade.point_count(); ++i)
          lowest = std::min(lowest, blade.ideal_point(i).z);
        in_bone += samples_in_bone(blade);
      }
      const double expected = 50 * kK * depth;
      const char* name = orientation == BladeOrientation::Free ? "free" : "locked";
      std::printf("%-9.2f %-7s %12.4f %12.4f %12.6f %8d\n", width, name, tick.force_N.z, expected,
                  lowest, in_bone);
      EXPECT_EQ(in_bone, 0) << width << " " << name;
      EXPECT_NEAR(tick.force_N.z, expected, 0.02 * expected) << width << " " << name;
    }
  }
}

TEST(RigidBladeSweep, ATwoPointBladeIsHeldByABoneBetweenItsPoints) {
  const MeshData mesh = grid_mesh(axis(-60, 60, 4), axis(-8, 8, 4), axis(-16, 8, 4));
  const auto space =
      space_of(mesh, [](const Vec3& c) { return std::abs(c.x) < 4.0 && c.z < 0.0 && c.z > -8.0; });
  BladeSpec spec{"knife", {-50, 0, 0}, {50, 0, 0}, 2};
  Blade blade(*space, spec);
  blade.reset({{0, 0, 1}, {}});
  BladeTick tick;
  for (int k = 1; k <= 1400; ++k)
    tick = blade.step({{0, 0, std::max(-12.0, 1.0 - 0.01 * k)}, {}}, kDt);
  std::printf("two points over an 8 mm bone pressed 12 mm: ends at z %.6f and %.6f, force %.4f N\n",
              blade.ideal_point(0).z, blade.ideal_point(1).z, tick.force_N.z);
  EXPECT_EQ(samples_in_bone(blade), 0);
  // Balanced on the bone's top, free to tilt: the device holds it level.
  EXPECT_LT(std::abs(blade.ideal_point(0).z), 0.05);
  EXPECT_LT(std::abs(blade.ideal_point(1).z), 0.05);
  EXPECT_NEAR(tick.force_N.z, 2 * kK * 12.0, 0.02 * 2 * kK * 12.0);
}

TEST(RigidBladeSweep, AOneTickTurnCannotSweepTheEdgePastABone) {
  // A 30 mm blade turned about its start (at the origin) in the xy plane in one
  // tick; a bone `size` mm across lies at 45 degrees, 20 mm out. The blade's
  // motion from one pose to the next moves its middle straight and turns the
  // direction (interpolate_edge about 0.5): a turn of 60 or 90 degrees sweeps
  // the edge over the bone, so the edge stops short of it; a turn of 170
  // degrees moves the middle across beside the origin and the bone is not in
  // the way. Either way no sample of that motion lies in bone.
  for (double size : {4.0, 2.0, 1.0}) {
    const double c = 20.0 * std::sqrt(0.5);
    const double h = 0.5 * size;
    const MeshData mesh = grid_mesh(axis(-40, 40, 4, {c - h, c + h}),
                                    axis(-40, 40, 4, {c - h, c + h}), axis(-12, 12, 4, {-h, h}));
    const auto space = space_of(mesh, [&](const Vec3& x) {
      return std::abs(x.x - c) < h && std::abs(x.y - c) < h && std::abs(x.z) < h;
    });
    for (double turn_deg : {30.0, 60.0, 90.0, 170.0}) {
      BladeSpec spec{"knife", {0, 0, 0}, {30, 0, 0}, 16};
      Blade blade(*space, spec);
      blade.reset({{0, 0, 0}, {}});
      const EdgePose before{blade.ideal_point(0), {1, 0, 0}};
      const double half_turn = 0.5 * turn_deg * M_PI / 180.0;
      const BladeTick tick =
          blade.step({{0, 0, 0}, {std::cos(half_turn), 0, 0, std::sin(half_turn)}}, kDt);
      const Vec3 u = blade.ideal_pose().rotation.rotate({1, 0, 0});
      const double reached_deg = std::atan2(u.y, u.x) * 180.0 / M_PI;
      std::printf(
          "bone %.0f mm at 45 deg, one-tick turn of %.0f deg: the edge turned %.2f deg, "
          "%d contacts, %d rounds\n",
          size, turn_deg, reached_deg, tick.contacts, tick.rigid_rounds);
      EXPECT_EQ(samples_in_bone(blade), 0) << size << " " << turn_deg;
      if (turn_deg == 60.0 || turn_deg == 90.0) {
        EXPECT_LT(reached_deg, 45.0) << size << " " << turn_deg;
      }
      if (tick.rigid_rounds == 1 && !tick.unresolved) {
        // One verified move: every pose along it (to the pieces' bound) is clean.
        const EdgePose after{blade.ideal_point(0), u};
        for (int m = 1; m <= 64; ++m) {
          const EdgePose pose = interpolate_edge(before, after, m / 64.0, 0.5, 30.0);
          for (int s = 0; s <= 300; ++s) {
            const Vec3 x = pose.point(s / 300.0, 30.0);
            EXPECT_FALSE(inside_rigid(*space, x, 1e-4 * 30.0 + 1e-6))
                << size << " " << turn_deg << " motion " << m << " sample " << s;
          }
        }
      }
    }
  }
}

}  // namespace
}  // namespace hapticut
