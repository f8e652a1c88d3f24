// A rigid blade over a rim: a box of bone whose side the blade crosses at 0 to
// 60 degrees, pressed 2 mm and slid along the side. The rim is straight and the
// top flat, so nothing along the slide changes: without friction there is no
// lateral force and no stick-slip; with friction, one release from static to
// dynamic and no repeated stick-slip.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "hapticut/blade.h"
#include "test_support.h"

namespace hapticut {
namespace {

constexpr double kDt = 0.001;
constexpr double kK = 0.1;  // N/mm, the paper's.
// The box: 80 mm along x, its side at y = 10, its top at z = 0.
constexpr double kSideY = 10.0;

TEST(RigidBladeRim, SlidAlongARimItNeitherSticksNorSlipsWithoutFrictionAndReleasesOnceWithIt) {
  using testing::axis;
  const MeshData mesh = grid_mesh(axis(-60, 60, 4), axis(-30, 30, 2), axis(-14, 6, 2));
  const auto in_box = [](const Vec3& c) {
    return std::abs(c.x) < 40.0 && std::abs(c.y) < kSideY && c.z < 0.0 && c.z > -10.0;
  };
  std::printf("blade 40 mm across the side of a bone box, pressed 2 mm, slid 10 mm along it:\n");
  std::printf("%-11s %5s %-7s %6s | %10s %10s %9s %6s %7s\n", "friction", "angle", "orient",
              "points", "|Fx| max N", "max dF N", "releases", "unres", "in bone");
  for (const double mu : {0.0, 0.4}) {
    const double mu_dynamic = 0.75 * mu;
    const auto space =
        testing::labelled_space(mesh, in_box,
                                {testing::free_material(), testing::drag_material(1.0),
                                 testing::rigid_material(mu, mu_dynamic)});
    for (const double angle_deg : {0.0, 30.0, 60.0}) {
      const double a = angle_deg * std::numbers::pi / 180.0;
      // Across the side: along y turned about z by the angle, its middle 2 mm
      // beyond the side, so more than half lies over the top.
      const Vec3 along{std::sin(a), std::cos(a), 0.0};
      for (BladeOrientation orientation : {BladeOrientation::Free, BladeOrientation::Locked}) {
        for (const int points : {50, 100}) {
          BladeSpec spec{"knife", along * -20.0, along * 20.0, points};
          spec.orientation = orientation;
          Blade blade(space, spec);
          const double middle_y = kSideY - 2.0;
          blade.reset({{-5.0, middle_y, 1.0}, {}});
          Vec3 force;
          for (int k = 1; k <= 300; ++k) {
            force = blade.step({{-5.0, middle_y, 1.0 - 0.01 * k}, {}}, kDt).force_N;
          }
          double most = 0.0;
          double largest_change = 0.0;
          int releases = 0;
          int unresolved = 0;
          int in_bone = 0;
          for (int k = 1; k <= 1000; ++k) {
            const Vec3 last = force;
            const BladeTick tick = blade.step({{-5.0 + 0.01 * k, middle_y, -2.0}, {}}, kDt);
            force = tick.force_N;
            unresolved += tick.unresolved ? 1 : 0;
            most = std::max(most, std::abs(force.x));
            largest_change = std::max(largest_change, norm(force - last));
            releases += std::abs(force.x) < std::abs(last.x) - 0.1 ? 1 : 0;
            for (int i = 0; i < points; ++i) {
              in_bone += testing::inside_rigid(*space, blade.ideal_point(i), 1e-6) ? 1 : 0;
            }
          }
          std::printf("%-5.2f %-5.2f %5.0f %-7s %6d | %10.4f %10.4f %9d %6d %7d\n", mu, mu_dynamic,
                      angle_deg, orientation == BladeOrientation::Free ? "free" : "locked", points,
                      most, largest_change, releases, unresolved, in_bone);
          EXPECT_EQ(in_bone, 0);
          // The device moves 0.01 mm a tick: the springs' sum changes by at
          // most n k 0.01 from that alone.
          const double explained_N = points * kK * 0.01;
          if (mu == 0.0) {
            EXPECT_LT(most, 1e-3) << angle_deg << " deg, " << points << " points";
            EXPECT_EQ(releases, 0) << angle_deg << " deg, " << points << " points";
            EXPECT_LE(largest_change, explained_N + 1e-6)
                << angle_deg << " deg, " << points << " points";
          } else {
            EXPECT_LE(releases, 1) << angle_deg << " deg, " << points << " points";
          }
        }
      }
    }
  }
}

}  // namespace
}  // namespace hapticut
