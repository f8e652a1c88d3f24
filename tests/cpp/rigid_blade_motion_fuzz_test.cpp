// The rigid blade's motion fuzz: random device poses with one-tick turns up to
// 180 degrees and drops, around thin rods, creases of 30 to 150 degrees and a
// notch. The edge, sampled along the motion between one tick's ideal pose and
// the next (the interpolation the swept test verifies), never lies in bone;
// nothing is NaN; the rounds stay within their bound. The largest one-tick
// force step is printed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "hapticut/blade.h"
#include "hapticut/edge_fit.h"
#include "test_support.h"

namespace hapticut {
namespace {

constexpr double kDt = 0.001;

using testing::axis;
using testing::inside_rigid;

std::shared_ptr<const Space> space_of(const MeshData& mesh,
                                      const std::function<bool(const Vec3&)>& in_bone) {
  return testing::labelled_space(mesh, in_bone);
}

struct Scenario {
  std::string name;
  std::shared_ptr<const Space> space;
};

std::vector<Scenario> scenarios() {
  std::vector<Scenario> out;
  for (double width : {0.25, 0.5, 1.0, 2.0}) {
    const double h = 0.5 * width;
    // A rod along y, square in section, its top at z = 0.
    const MeshData mesh =
        grid_mesh(axis(-24, 24, 4, {-h, h}), axis(-12, 12, 4), axis(-12, 12, 4, {-width, 0.0}));
    out.push_back({"rod " + std::to_string(width).substr(0, 4) + " mm",
                   space_of(mesh, [h, width](const Vec3& c) {
                     return std::abs(c.x) < h && c.z < 0.0 && c.z > -width;
                   })});
  }
  for (double angle_deg : {30.0, 90.0, 150.0}) {
    // A V-groove along x: vertices lifted by c |y|, c = 1 / tan(angle / 2).
    const double c = 1.0 / std::tan(0.5 * angle_deg * M_PI / 180.0);
    out.push_back({"crease " + std::to_string(int(angle_deg)) + " deg",
                   testing::v_groove(axis(-24, 24, 4), axis(-12, 12, 2), axis(-12, 12, 2), c)});
  }
  // An L-shaped notch of two bones: a floor and a wall.
  const MeshData notch = grid_mesh(axis(-24, 24, 4), axis(-12, 12, 2), axis(-12, 12, 2));
  out.push_back({"notch", space_of(notch, [](const Vec3& c) { return c.z < -4.0 || c.y > 4.0; })});
  return out;
}

Quaternion turn_about_z(double angle) {
  return {std::cos(0.5 * angle), 0, 0, std::sin(0.5 * angle)};
}

TEST(RigidBladeMotionFuzz, TheSweptEdgeNeverEntersBone) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (const Scenario& scenario : scenarios()) {
    for (BladeOrientation orientation : {BladeOrientation::Free, BladeOrientation::Locked}) {
      BladeSpec spec{"knife", {-8, 0, 0}, {8, 0, 0}, 9};  // 2 mm spacing.
      spec.orientation = orientation;
      Blade blade(*scenario.space, spec);
      Vec3 position{0, 0, 6};
      Quaternion rotation;
      blade.reset({position, rotation});
      int through = 0;
      int worst_rounds = 0;
      int unresolved = 0;
      double worst_excess_N = 0.0;
      EdgePose last{blade.ideal_point(0), (blade.ideal_point(8) - blade.ideal_point(0)) / 16.0};
      Vec3 last_force;
      for (int tick_index = 0; tick_index < 1500; ++tick_index) {
        const std::uint32_t roll = random() % 100;
        if (roll < 4) {  // A one-tick turn of up to 180 degrees about z.
          rotation = multiply(turn_about_z(M_PI * unit(random)), rotation).normalized();
        } else if (roll < 7) {  // A drop.
          position.z -= 3.0 * std::abs(unit(random));
        } else {
          position += Vec3{unit(random), unit(random), unit(random)} * 0.3;
          const Quaternion wobble{1.0, 0.02 * unit(random), 0.02 * unit(random),
                                  0.02 * unit(random)};
          rotation = multiply(wobble, rotation).normalized();
        }
        position = {std::clamp(position.x, -10.0, 10.0), std::clamp(position.y, -6.0, 6.0),
                    std::clamp(position.z, -8.0, 8.0)};
        const BladeTick tick = blade.step({position, rotation}, kDt);
        if (tick.rejected) continue;
        ASSERT_TRUE(is_finite(tick.force_N) && is_finite(tick.torque_N_mm)) << scenario.name;
        ASSERT_LE(tick.rigid_rounds, Blade::kMaxRigidRounds);
        worst_rounds = std::max(worst_rounds, tick.rigid_rounds);
        unresolved += tick.unresolved ? 1 : 0;
        const EdgePose now{blade.ideal_point(0),
                           (blade.ideal_point(8) - blade.ideal_point(0)) / 16.0};
        // Along the motion: 8 poses between the last ideal pose and this one
        // (about the sample the move carried straight), where the tick made it
        // in one verified move (one round, resolved);
        // a tick of several rounds moves along their chain, and its end pose
        // is checked. The motion is verified in pieces whose chords leave the
        // interpolation by at most 1e-4 of the length: that much depth is
        // allowed between them.
        const bool one_move = tick.rigid_rounds == 1 && !tick.unresolved;
        for (int m = one_move ? 1 : 8; m <= 8 && through == 0; ++m) {
          const EdgePose pose =
              interpolate_edge(last, now, m / 8.0, blade.rigid_motion_pivot(), 16.0);
          for (int s = 0; s <= 160; ++s) {
            if (inside_rigid(*scenario.space, pose.point(s / 160.0, 16.0), 1e-4 * 16.0 + 1e-6)) {
              ++through;
              ADD_FAILURE() << scenario.name << " tick " << tick_index << " motion " << m
                            << "/8 sample " << s;
              break;
            }
          }
        }
        worst_excess_N = std::max(worst_excess_N, norm(tick.force_N - last_force));
        last_force = tick.force_N;
        last = now;
        if (through != 0) break;
      }
      std::printf(
          "motion fuzz %-14s %-6s: most rounds %d, unresolved %d of 1500, largest force step %.3f "
          "N\n",
          scenario.name.c_str(), orientation == BladeOrientation::Free ? "free" : "locked",
          worst_rounds, unresolved, worst_excess_N);
      EXPECT_EQ(through, 0) << scenario.name;
    }
  }
}

}  // namespace
}  // namespace hapticut
