// The rigid coupling of a Blade (docs/decisions.md, "The rigid blade"): the
// whole edge stops at bone, resisting materials set the springs' targets,
// the orientation is free or locked, and no sample of the ideal edge ever
// lies inside rigid material.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <vector>

#include "hapticut/blade.h"
#include "test_support.h"

namespace hapticut {
namespace {

constexpr double kDt = 0.001;
constexpr double kK = 0.1;  // N/mm, the paper's.

using testing::axis;

// A 4 mm Kuhn grid from -60 to 60 in x, -16 to 16 in y, -24 to 16 in z, each
// tet's material chosen from its centroid (0 air, 1 flesh with D = 1 mm, 2 bone).
std::shared_ptr<const Space> grid_space(const std::function<int(const Vec3&)>& material,
                                        double jitter = 0.0) {
  const MeshData mesh = grid_mesh(axis(-60, 60, 4), axis(-16, 16, 4), axis(-24, 16, 4), jitter, 3);
  std::vector<std::int32_t> labels(mesh.tets.size());
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    Vec3 c;
    for (std::int32_t v : mesh.tets[t]) c += mesh.vertices_mm[v] * 0.25;
    labels[t] = material(c);
  }
  return testing::make_space(mesh, labels);
}

bool in_box(const Vec3& c, const Vec3& lo, const Vec3& hi) {
  return c.x > lo.x && c.x < hi.x && c.y > lo.y && c.y < hi.y && c.z > lo.z && c.z < hi.z;
}

// The 8 x 8 x 8 mm bone under the middle of the blade, its top at z = 0.
int middle_bone(const Vec3& c) { return in_box(c, {-4, -4, -8}, {4, 4, 0}) ? 2 : 0; }

using testing::inside_rigid;

// Samples of the ideal edge at `per_gap` per gap between points (the points
// included) that lie inside rigid material.
int samples_inside_rigid(const Blade& blade, int per_gap) {
  const int n = blade.point_count();
  int inside = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3 a = blade.ideal_point(i);
    const int samples = i + 1 < n ? per_gap : 1;
    for (int s = 0; s < samples; ++s) {
      const Vec3 x = s == 0 ? a : a + (blade.ideal_point(i + 1) - a) * (double(s) / per_gap);
      inside += inside_rigid(blade.space(), x) ? 1 : 0;
    }
  }
  return inside;
}

BladeSpec blade_spec(BladeCoupling coupling,
                     BladeOrientation orientation = BladeOrientation::Free) {
  BladeSpec spec{"knife", {-50, 0, 0}, {50, 0, 0}, 50};
  spec.coupling = coupling;
  spec.orientation = orientation;
  return spec;
}

// Presses the blade (level, along x at y) from z_from to z_to at 100 mm/s
// (0.1 mm a tick), then holds it there for 20 ticks.
BladeTick press(Blade& blade, double y, double z_from, double z_to) {
  blade.reset({{0, y, z_from}, {}});
  BladeTick tick;
  const int ticks = static_cast<int>(std::lround((z_from - z_to) / 0.1));
  for (int k = 1; k <= ticks + 20; ++k) {
    const double z = std::max(z_to, z_from - 0.1 * k);
    tick = blade.step({{0, y, z}, {}}, kDt);
  }
  return tick;
}

int points_below(const Blade& blade, double z) {
  int below = 0;
  for (int i = 0; i < blade.point_count(); ++i) below += blade.ideal_point(i).z < z - 1e-6 ? 1 : 0;
  return below;
}

TEST(RigidBlade, TheWholeEdgeStopsAtABoneUnderItsMiddle) {
  const auto space = grid_space(middle_bone);
  Blade rigid(space, blade_spec(BladeCoupling::Rigid));
  const BladeTick held = press(rigid, 0.0, 2.0, -10.0);
  Blade independent(space, blade_spec(BladeCoupling::Independent));
  const BladeTick loose = press(independent, 0.0, 2.0, -10.0);
  std::printf(
      "bone under the middle, pressed 10 mm: rigid %d of 50 points below the top, "
      "%d edge samples in bone, force %.3f N, %d rounds; independent %d below, %.3f N\n",
      points_below(rigid, 0.0), samples_inside_rigid(rigid, 10), held.force_N.z, held.rigid_rounds,
      points_below(independent, 0.0), loose.force_N.z);
  EXPECT_EQ(points_below(rigid, 0.0), 0);
  EXPECT_EQ(samples_inside_rigid(rigid, 10), 0);
  EXPECT_GE(held.force_N.z, 0.95 * 50 * kK * 10.0);
  EXPECT_LE(held.force_N.z, 50 * kK * 10.0 + 1e-3);
  EXPECT_FALSE(held.unresolved);
  EXPECT_LE(held.rigid_rounds, Blade::kMaxRigidRounds);
  // The paper's independent points: only those over the bone are held.
  EXPECT_GE(points_below(independent, 0.0), 40);
  EXPECT_LT(loose.force_N.z, 10.0);
}

TEST(RigidBlade, ABladeOfDefaultSpecIsRigidWithItsOwnOrientation) {
  const BladeSpec spec{"knife", {-50, 0, 0}, {50, 0, 0}, 50};
  EXPECT_EQ(spec.coupling, BladeCoupling::Rigid);
  EXPECT_EQ(spec.orientation, BladeOrientation::Free);
  const auto space = grid_space(middle_bone);
  Blade blade(space, spec);
  EXPECT_EQ(blade.coupling(), BladeCoupling::Rigid);
  const BladeTick held = press(blade, 0.0, 2.0, -10.0);
  EXPECT_EQ(points_below(blade, 0.0), 0);
  EXPECT_GE(held.force_N.z, 0.95 * 50 * kK * 10.0);
}

TEST(RigidBlade, ABoneUnderOneEndTiltsAFreeBladeAndNotALockedOne) {
  // The bone under the last 6 mm of the edge.
  const auto space = grid_space([](const Vec3& c) {
    return in_box(c, {44, -4, -8}, {52, 4, 0}) ? 2 : 0;
  });
  Blade free_blade(space, blade_spec(BladeCoupling::Rigid, BladeOrientation::Free));
  const BladeTick tilted = press(free_blade, 0.0, 2.0, -6.0);
  const Vec3 u = free_blade.ideal_pose().rotation.rotate({1, 0, 0});
  std::printf(
      "bone under one end: free blade direction (%.4f, %.4f, %.4f), force %.3f N, "
      "torque y %.3f N mm\n",
      u.x, u.y, u.z, tilted.force_N.z, tilted.torque_N_mm.y);
  EXPECT_EQ(samples_inside_rigid(free_blade, 10), 0);
  EXPECT_GT(u.z, 0.05);  // The far end rests on the bone, the near end hangs lower.
  EXPECT_LT(free_blade.ideal_point(0).z, -6.0 + 1e-6);
  EXPECT_GE(free_blade.ideal_point(49).z, -1e-6);
  // The torque about the tool origin is the sum of the point torques.
  Vec3 torque;
  Vec3 force;
  for (int i = 0; i < free_blade.point_count(); ++i) {
    const Vec3 f = free_blade.point_force(i);
    const Vec3 p = free_blade.world_points()[i];
    EXPECT_LT(norm(f - (free_blade.ideal_point(i) - p) * kK), 1e-12);
    torque += cross(p - Vec3{0, 0, -6}, f);
    force += f;
  }
  EXPECT_LT(norm(tilted.torque_N_mm - torque), 1e-9 * (1 + norm(torque)));
  EXPECT_LT(norm(tilted.force_N - force), 1e-12 * (1 + norm(force)));
  EXPECT_GT(std::abs(tilted.torque_N_mm.y), 1.0);

  Blade locked(space, blade_spec(BladeCoupling::Rigid, BladeOrientation::Locked));
  const BladeTick level = press(locked, 0.0, 2.0, -6.0);
  const Vec3 v = locked.ideal_pose().rotation.rotate({1, 0, 0});
  EXPECT_LT(norm(v - Vec3{1, 0, 0}), 1e-12);
  EXPECT_EQ(samples_inside_rigid(locked, 10), 0);
  EXPECT_EQ(points_below(locked, 0.0), 0);
  EXPECT_GE(level.force_N.z, 0.95 * 50 * kK * 6.0);
}

TEST(RigidBlade, SlidesAlongABoneAndPassesItsSide) {
  const auto space = grid_space(middle_bone);
  Blade blade(space, blade_spec(BladeCoupling::Rigid));
  press(blade, -3.0, 2.0, -3.0);
  // Across the bone's top (y from -3 to 3) at 0.05 mm a tick: on the top all along.
  for (int k = 1; k <= 120; ++k) {
    const BladeTick tick = blade.step({{0, -3.0 + 0.05 * k, -3.0}, {}}, kDt);
    ASSERT_EQ(points_below(blade, 0.0), 0) << "tick " << k;
    ASSERT_NEAR(blade.ideal_point(25).z, 0.0, 1e-4) << "tick " << k;
    ASSERT_NEAR(tick.force_N.z, 50 * kK * 3.0, 1e-3) << "tick " << k;
    ASSERT_NEAR(blade.ideal_point(25).y, -3.0 + 0.05 * k, 1e-9) << "tick " << k;
  }
  // On past the side (y = 4): the blade drops to the device.
  BladeTick tick;
  for (int k = 1; k <= 100; ++k) tick = blade.step({{0, 3.0 + 0.05 * k, -3.0}, {}}, kDt);
  EXPECT_EQ(samples_inside_rigid(blade, 10), 0);
  EXPECT_NEAR(blade.ideal_point(25).z, -3.0, 1e-9);
  EXPECT_NEAR(norm(tick.force_N), 0.0, 1e-9);
}

TEST(RigidBlade, InFleshOverABoneTheWholeEdgeStopsAtTheBone) {
  // Flesh up to z = 8 everywhere, the bone under the middle.
  const auto space = grid_space([](const Vec3& c) {
    if (in_box(c, {-4, -4, -8}, {4, 4, 0})) return 2;
    return c.z < 8 ? 1 : 0;
  });
  Blade rigid(space, blade_spec(BladeCoupling::Rigid));
  const BladeTick held = press(rigid, 0.0, 12.0, -5.0);
  Blade independent(space, blade_spec(BladeCoupling::Independent));
  press(independent, 0.0, 12.0, -5.0);
  std::printf(
      "in flesh over the bone: rigid %d points below the top, force %.3f N; "
      "independent %d below\n",
      points_below(rigid, 0.0), held.force_N.z, points_below(independent, 0.0));
  EXPECT_EQ(points_below(rigid, 0.0), 0);
  EXPECT_EQ(samples_inside_rigid(rigid, 10), 0);
  EXPECT_GE(held.force_N.z, 0.95 * 50 * kK * 5.0);
  EXPECT_GE(points_below(independent, 0.0), 40);
}

TEST(RigidBlade, InFleshTheBladeLagsByDAndHalfInFleshItTiltsAndLagsBetween) {
  // Wholly in flesh (no bone): moving down, every point lags 1 mm.
  const auto flesh = grid_space([](const Vec3&) { return 1; });
  Blade whole(flesh, blade_spec(BladeCoupling::Rigid));
  press(whole, 0.0, 10.0, -5.0);
  for (int k = 1; k <= 30; ++k) whole.step({{0, 0, -5.0 - 0.1 * k}, {}}, kDt);
  for (int i = 0; i < whole.point_count(); ++i) {
    EXPECT_NEAR(whole.ideal_point(i).z - whole.world_points()[i].z, 1.0, 1e-9) << "point " << i;
  }
  // Flesh for x < 0, air for x > 0.
  const auto half = grid_space([](const Vec3& c) { return c.x < 0 ? 1 : 0; });
  Blade blade(half, blade_spec(BladeCoupling::Rigid));
  press(blade, 0.0, 10.0, -5.0);
  for (int k = 1; k <= 30; ++k) blade.step({{0, 0, -5.0 - 0.1 * k}, {}}, kDt);
  const double lag_start = blade.ideal_point(0).z - blade.world_points()[0].z;
  const double lag_end = blade.ideal_point(49).z - blade.world_points()[49].z;
  const double lag_middle = 0.5 * (blade.ideal_point(24).z - blade.world_points()[24].z +
                                   blade.ideal_point(25).z - blade.world_points()[25].z);
  const Vec3 u = blade.ideal_pose().rotation.rotate({1, 0, 0});
  std::printf(
      "half in flesh: lag at the flesh end %.4f mm, the middle %.4f mm, the air end "
      "%.4f mm, direction z %.5f\n",
      lag_start, lag_middle, lag_end, u.z);
  // The least-squares line through targets lagging 1 mm on one half and 0 on
  // the other: lagging half of D in the middle, more at the flesh end.
  EXPECT_GT(lag_middle, 0.3);
  EXPECT_LT(lag_middle, 0.7);
  EXPECT_GT(lag_start, lag_end + 0.5);
  EXPECT_LT(u.z, -0.002);  // Tilted: the flesh end (x < 0) higher.
}

// Random device poses, small steps and large jumps, turns included, around
// bones of several shapes on straight and jittered grids: no sample of the
// ideal edge inside bone, nothing NaN, rounds within their bound.
TEST(RigidBlade, FuzzNeverInsideBone) {
  struct Case {
    const char* name;
    std::function<int(const Vec3&)> material;
    double jitter;
  };
  const std::vector<Case> cases = {
      {"cube", middle_bone, 0.0},
      {"bar across",
       [](const Vec3& c) {
         return in_box(c, {-2, -20, -6}, {6, 20, 2}) ? 2 : 0;
       },
       0.2},
      {"slope", [](const Vec3& c) { return c.z < 0.25 * c.x - 6 ? 2 : 0; }, 0.25},
      {"two bones in flesh",
       [](const Vec3& c) {
         if (in_box(c, {-30, -8, -12}, {-18, 8, -2}) || in_box(c, {20, -4, -10}, {24, 4, 4})) {
           return 2;
         }
         return c.z < 6 ? 1 : 0;
       },
       0.15},
  };
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (const Case& c : cases) {
    const auto space = grid_space(c.material, c.jitter);
    for (BladeOrientation orientation : {BladeOrientation::Free, BladeOrientation::Locked}) {
      BladeSpec spec{"knife", {-15, 0, 0}, {15, 0, 0}, 16};
      spec.coupling = BladeCoupling::Rigid;
      spec.orientation = orientation;
      Blade blade(space, spec);
      Vec3 position{0, 0, 12};
      Quaternion rotation;
      blade.reset({position, rotation});
      int worst_rounds = 0;
      int unresolved = 0;
      int inside = 0;
      for (int k = 0; k < 3000; ++k) {
        const std::uint32_t roll = random() % 100;
        if (roll < 3) {  // A jump anywhere, any orientation.
          position = {20 * unit(random), 8 * unit(random), -4 + 12 * unit(random)};
          rotation = Quaternion{unit(random), unit(random), unit(random), unit(random)};
        } else {
          position += Vec3{unit(random), unit(random), unit(random)} * 0.6;
          position = {std::clamp(position.x, -28.0, 28.0), std::clamp(position.y, -10.0, 10.0),
                      std::clamp(position.z, -18.0, 12.0)};
          const Quaternion turn{1.0, 0.02 * unit(random), 0.02 * unit(random), 0.02 * unit(random)};
          rotation = multiply(turn, rotation).normalized();
        }
        if (!rotation.valid()) rotation = {};
        rotation = rotation.normalized();
        const BladeTick tick = blade.step({position, rotation}, kDt);
        if (tick.rejected) continue;
        ASSERT_TRUE(is_finite(tick.force_N) && is_finite(tick.torque_N_mm)) << c.name << " " << k;
        const Pose& ideal = blade.ideal_pose();
        ASSERT_TRUE(is_finite(ideal.position_mm) && std::isfinite(ideal.rotation.w))
            << c.name << " " << k;
        ASSERT_LE(tick.rigid_rounds, Blade::kMaxRigidRounds);
        worst_rounds = std::max(worst_rounds, tick.rigid_rounds);
        unresolved += tick.unresolved ? 1 : 0;
        const int bad = samples_inside_rigid(blade, 10);
        inside += bad;
        EXPECT_EQ(bad, 0) << c.name << " tick " << k;
        if (bad != 0) break;
      }
      std::printf("fuzz %-18s %s: most rounds %d, unresolved ticks %d of 3000, unseated %llu\n",
                  c.name, orientation == BladeOrientation::Free ? "free  " : "locked", worst_rounds,
                  unresolved, static_cast<unsigned long long>(blade.counters().unseated_ticks));
      EXPECT_EQ(inside, 0);
    }
  }
}

}  // namespace
}  // namespace hapticut
