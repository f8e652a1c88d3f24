// Switching a rigid blade's orientation while it rests on a bone: the edge
// turns from where it is to the new rule's direction over the ramp time, so
// the force changes a little each tick instead of jumping in one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "hapticut/blade.h"
#include "test_support.h"

namespace hapticut {
namespace {

constexpr double kDt = 0.001;

using testing::axis;

struct Switch {
  double largest_change_N = 0.0;  // Over the ticks after the switch.
  Vec3 end_force;
  double end_tilt_mm = 0.0;  // How far the edge's end stands above its start.
};

// A free 100 mm blade, its device tilted 5 degrees (the end lower), pressed
// 2 mm into a flat bone: the free edge lies flat on it. Then switched to
// `to` over ramp_s and held for a second.
Switch switch_on_a_bone(BladeOrientation from, BladeOrientation to, double ramp_s) {
  const MeshData mesh = grid_mesh(axis(-60, 60, 4), axis(-16, 16, 4), axis(-16, 8, 4));
  const auto space = testing::labelled_space(
      mesh, [](const Vec3& c) { return c.z < 0.0; },
      {testing::free_material(), testing::drag_material(1.0), testing::rigid_material()});
  const double tilt = 5.0 * M_PI / 180.0;
  const Quaternion tilted{std::cos(tilt / 2), 0.0, std::sin(tilt / 2), 0.0};
  BladeSpec spec{"knife", {-50, 0, 0}, {50, 0, 0}, 50};
  spec.orientation = from;
  Blade blade(*space, spec);
  blade.reset({{0, 0, 6}, tilted});
  Vec3 force;
  for (int k = 1; k <= 800; ++k) {
    force = blade.step({{0, 0, std::max(-2.0, 6.0 - 0.01 * k)}, tilted}, kDt).force_N;
  }
  Switch out;
  blade.set_orientation(to, ramp_s);
  for (int k = 1; k <= 1000; ++k) {
    const Vec3 last = force;
    force = blade.step({{0, 0, -2.0}, tilted}, kDt).force_N;
    out.largest_change_N = std::max(out.largest_change_N, norm(force - last));
  }
  out.end_force = force;
  out.end_tilt_mm = blade.ideal_point(blade.point_count() - 1).z - blade.ideal_point(0).z;
  return out;
}

TEST(RigidBladeOrientation, ASwitchTurnsInOverTheRampTime) {
  std::printf("%-15s %8s %16s %10s %12s\n", "switch", "ramp s", "largest dF N", "end Fz N",
              "end tilt mm");
  for (const auto& [from, to, name] :
       {std::tuple{BladeOrientation::Free, BladeOrientation::Locked, "free -> locked"},
        std::tuple{BladeOrientation::Locked, BladeOrientation::Free, "locked -> free"}}) {
    const Switch at_once = switch_on_a_bone(from, to, 0.0);
    const Switch ramped = switch_on_a_bone(from, to, 0.5);
    for (const auto& [ramp, r] : {std::pair{0.0, at_once}, std::pair{0.5, ramped}}) {
      std::printf("%-15s %8.2f %16.4f %10.4f %12.4f\n", name, ramp, r.largest_change_N,
                  r.end_force.z, r.end_tilt_mm);
    }
    // Both end where the new rule puts the blade.
    EXPECT_NEAR(ramped.end_force.z, at_once.end_force.z, 1e-3) << name;
    EXPECT_NEAR(ramped.end_tilt_mm, at_once.end_tilt_mm, 1e-3) << name;
    // Turned at once, the force jumps; over 0.5 s (500 ticks) it moves by
    // about a 500th of that each tick.
    EXPECT_GT(at_once.largest_change_N, 5.0) << name;
    EXPECT_LT(ramped.largest_change_N, at_once.largest_change_N / 100.0) << name;
  }
}

}  // namespace
}  // namespace hapticut
