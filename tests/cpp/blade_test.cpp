#include "hapticut/blade.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "test_support.h"

namespace hapticut {
namespace {

TEST(Blade, PointsFollowThePose) {
  const auto space_owner = testing::make_space(cube_mesh(100.0), 0);
  const Space& space = *space_owner;
  Blade blade(space, {"b", {0, 0, 0}, {10, 0, 0}, 11});
  // A quarter turn about z: the blade now points along +y.
  const double h = std::sqrt(0.5);
  blade.reset({{50, 50, 50}, {h, 0, 0, h}});
  EXPECT_NEAR(blade.world_points()[10].x, 50.0, 1e-12);
  EXPECT_NEAR(blade.world_points()[10].y, 60.0, 1e-12);
  EXPECT_EQ(blade.point_count(), 11);
}

TEST(Blade, ForceIsTheSumAndTorqueIsAboutTheToolOrigin) {
  // Bone below z = 0 inside a free box: the blade pressed 2 mm down feels
  // k * 2 mm per point, pushing up; tilted, the torque follows the lever arms.
  // Independent points rest on the floor exactly; a rigid blade's pose is kept
  // 4 tolerances on the free side of its contacts (docs/decisions.md, "The
  // rigid blade"), which each point's spring adds.
  const auto space_owner = testing::bone_floor();
  const Space& space = *space_owner;
  for (const BladeCoupling coupling : {BladeCoupling::Independent, BladeCoupling::Rigid}) {
    Blade blade(space, {"b", {0, 0, 0}, {10, 0, 0}, 5, coupling});
    const double margin_N = coupling == BladeCoupling::Rigid ? 0.1 * 4.0 * space.tolerance() : 0.0;
    blade.reset({{-5, 0, 5}, {}});
    BladeTick tick{};
    for (int i = 0; i <= 20; ++i) tick = blade.step({{-5, 0, 5 - 0.35 * i}, {}}, 0.001);
    EXPECT_NEAR(tick.force_N.z, 5 * 0.1 * 2.0, 5 * margin_N + 1e-9);
    EXPECT_NEAR(tick.force_N.x, 0.0, 1e-9);
    // Points at x = 0, 2.5, ..., 10 from the origin, each pushed up by 0.2 N: torque about y.
    EXPECT_NEAR(tick.torque_N_mm.y, -(0 + 2.5 + 5 + 7.5 + 10) * 0.2, 25 * margin_N + 1e-9);
    EXPECT_EQ(tick.capped_points, 0);
    for (const Proxy& p : blade.proxies()) EXPECT_EQ(p.check_invariants(), "");
  }
}

// The points are placed as a + s_i b and the torque summed as
// (a - origin) x F + b x sum(s_i f_i) (docs/decisions.md): both agree with the
// per-point definitions, origin + R t_i and sum((p_i - origin) x f_i), to
// rounding, over tilted strokes into bone with a blade off the tool origin.
TEST(Blade, PlacementAndTorqueAgreeWithThePerPointDefinitions) {
  const auto space = testing::bone_floor();
  Blade blade(space, {"b", {3, -2, 1}, {-9, 4, 6}, 37});
  const Quaternion tilt = Quaternion{0.9, 0.2, -0.3, 0.1}.normalized();
  blade.reset({{0, 0, 8}, tilt});
  double largest_torque = 0.0;
  for (int i = 0; i < 60; ++i) {
    const Quaternion r = Quaternion{0.9, 0.2 + 0.004 * i, -0.3, 0.1 - 0.003 * i}.normalized();
    const Pose pose{{0.1 * i, -0.05 * i, 8.0 - 0.2 * i}, r};
    const BladeTick tick = blade.step(pose, 0.001);
    ASSERT_FALSE(tick.rejected) << "tick " << i;
    Vec3 torque;
    for (int k = 0; k < blade.point_count(); ++k) {
      const Vec3 expected = pose.position_mm + r.rotate(blade.tool_points()[k]);
      ASSERT_LT(norm(blade.world_points()[k] - expected), 1e-12) << "tick " << i << " point " << k;
      torque += cross(blade.world_points()[k] - pose.position_mm, blade.proxies()[k].force_N());
    }
    EXPECT_LT(norm(tick.torque_N_mm - torque), 1e-9 * (1.0 + norm(torque))) << "tick " << i;
    largest_torque = std::max(largest_torque, norm(torque));
  }
  EXPECT_GT(largest_torque, 1.0);  // The blade was pressed into the bone.
  // The workspace check on the two ends: a pose with one end just beyond the
  // workspace is refused, the same pose just inside it taken.
  Blade along_x(space, {"x", {0, 0, 0}, {10, 0, 0}, 7});
  const Aabb workspace = space->workspace();
  EXPECT_EQ(along_x.check_pose({{workspace.hi.x - 10.0 - 1e-6, 0, 5}, {}}), PoseCheck::Fine);
  EXPECT_EQ(along_x.check_pose({{workspace.hi.x - 10.0 + 1e-6, 0, 5}, {}}),
            PoseCheck::OutOfWorkspace);
  EXPECT_EQ(along_x.check_pose({{workspace.lo.x + 1e-6, 0, 5}, {}}), PoseCheck::Fine);
  EXPECT_EQ(along_x.check_pose({{workspace.lo.x - 1e-6, 0, 5}, {}}), PoseCheck::OutOfWorkspace);
}

TEST(Blade, NonFinitePoseIsRejected) {
  const auto space_owner = testing::make_space(cube_mesh(100.0), 0);
  const Space& space = *space_owner;
  Blade blade(space, {"b", {0, 0, 0}, {10, 0, 0}, 3});
  blade.reset({{50, 50, 50}, {}});
  const BladeTick tick =
      blade.step({{std::numeric_limits<double>::quiet_NaN(), 50, 50}, {}}, 0.001);
  EXPECT_TRUE(tick.rejected);
  EXPECT_EQ(tick.force_N, Vec3(0, 0, 0));
}

// check_pose: the check step and reset run, answered without placing anything.
TEST(Blade, CheckPoseSaysWhyAPoseIsRefusedWithoutPlacingIt) {
  const auto space_owner = testing::make_space(cube_mesh(100.0), 0);
  const Space& space = *space_owner;
  Blade blade(space, {"b", {0, 0, 0}, {10, 0, 0}, 3});
  const Vec3 centre = (space.workspace().lo + space.workspace().hi) * 0.5;
  blade.reset({centre, {}});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  // The origin 5 mm inside the workspace's +x face: the tip (10 mm along x) is outside,
  // and back inside once a half turn about z points the blade along -x.
  const Vec3 near_face{space.workspace().hi.x - 5.0, centre.y, centre.z};
  struct Case {
    Pose pose;
    PoseCheck expected;
  };
  const Case cases[] = {
      {{centre, {}}, PoseCheck::Fine},
      {{centre, {0.0, 0.0, 0.0, 2.0}}, PoseCheck::Fine},  // Normalised on use.
      {{near_face, {0.0, 0.0, 0.0, 1.0}}, PoseCheck::Fine},
      {{{nan, centre.y, centre.z}, {}}, PoseCheck::NotFinite},
      {{{centre.x, inf, centre.z}, {}}, PoseCheck::NotFinite},
      {{centre, {1.0, nan, 0.0, 0.0}}, PoseCheck::NotFinite},
      {{centre, {0.0, 0.0, 0.0, 0.0}}, PoseCheck::ZeroRotation},
      {{centre, {1e-7, 0.0, 0.0, 0.0}}, PoseCheck::ZeroRotation},
      {{centre, {1e200, 0.0, 0.0, 0.0}}, PoseCheck::ZeroRotation},  // Norm overflows.
      {{near_face, {}}, PoseCheck::OutOfWorkspace},
      {{space.workspace().hi + Vec3{1, 1, 1}, {}}, PoseCheck::OutOfWorkspace},
  };
  for (const Case& c : cases) {
    const std::vector<Vec3> world_before = blade.world_points();
    const BladeCounters counters_before = blade.counters();
    EXPECT_EQ(blade.check_pose(c.pose), c.expected);
    // Nothing placed, nothing counted.
    EXPECT_EQ(blade.world_points(), world_before);
    EXPECT_EQ(blade.counters().ticks, counters_before.ticks);
    // And step takes exactly the poses check_pose passes, counting a refusal outside the
    // workspace as such.
    const BladeTick tick = blade.step(c.pose, 0.001);
    EXPECT_EQ(tick.rejected, c.expected != PoseCheck::Fine);
    EXPECT_EQ(blade.counters().out_of_workspace_ticks - counters_before.out_of_workspace_ticks,
              c.expected == PoseCheck::OutOfWorkspace ? 1U : 0U);
    if (c.expected == PoseCheck::Fine) {
      blade.reset(c.pose);
    } else {
      EXPECT_THROW(blade.reset(c.pose), std::invalid_argument);
    }
    blade.reset({centre, {}});
  }
}

}  // namespace
}  // namespace hapticut
