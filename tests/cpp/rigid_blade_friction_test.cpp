// Friction at a rigid blade's contacts: pressed onto a round bone it stays
// where it landed (without friction it slides round to the side); pulled
// along a flat bone it sticks until the pull reaches the static coefficient
// times the push, then slides once and for all at the dynamic one; landed on
// one end it turns down onto the bone about that end (friction holds a
// support still, not a turn about it).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "hapticut/blade.h"
#include "hapticut/scene_io.h"
#include "test_support.h"

namespace hapticut {
namespace {

constexpr double kDt = 0.001;
constexpr double kK = 0.1;  // N/mm, the paper's.

using testing::axis;

template <class InBone>
std::shared_ptr<const Space> space_of(const MeshData& mesh, InBone in_bone, const Material& rigid) {
  return testing::labelled_space(mesh, in_bone,
                                 {testing::free_material(), testing::drag_material(1.0), rigid});
}

TEST(RigidBladeFriction, PressedPastARoundBonesCentreItStaysWhereItLanded) {
  // The example sphere of bone (320 faces); the blade level across it,
  // landing 13 degrees off its top, pressed to 3 mm under its centre.
  Scene scene = load_scene(std::string(HAPTICUT_EXAMPLES_DIR) + "/sphere320.hapticut.msgpack");
  double radius = 0.0;
  for (const Vec3& v : scene.vertices_mm) radius = std::max(radius, v.z);
  std::printf("%-22s %12s %12s %12s\n", "friction (static/dyn)", "landed y mm", "end y mm",
              "end z mm");
  for (const double mu : {0.0, 0.4}) {
    for (Material& m : scene.materials) {
      if (m.model == MaterialModel::Rigid) m = testing::rigid_material(mu, 0.75 * mu);
    }
    const auto space = Space::from_scene(scene);
    radius = 0.0;
    for (std::int32_t t = 0; t < space->mesh().tet_count(); ++t) {
      if (!space->tet_is_rigid(t)) continue;
      for (std::int32_t v : space->mesh().tet(t))
        radius = std::max(radius, space->mesh().vertex(v).z);
    }
    const double y = radius * std::sin(13.0 * M_PI / 180.0);
    for (BladeOrientation orientation : {BladeOrientation::Free, BladeOrientation::Locked}) {
      BladeSpec spec{"knife", {-20, 0, 0}, {20, 0, 0}, 50};
      spec.orientation = orientation;
      Blade blade(*space, spec);
      const double top = radius + 2.0;
      blade.reset({{0, y, top}, {}});
      double landed_y = 0.0;
      const int ticks = static_cast<int>((top + 3.0) / 0.01);
      for (int k = 1; k <= ticks + 20; ++k) {
        const BladeTick tick = blade.step({{0, y, std::max(-3.0, top - 0.01 * k)}, {}}, kDt);
        if (landed_y == 0.0 && tick.contacts > 0) landed_y = blade.ideal_point(25).y;
      }
      const Vec3 end = blade.ideal_point(25);
      std::printf("%-6.2f %-6.2f %-8s %12.4f %12.4f %12.4f\n", mu, 0.75 * mu,
                  orientation == BladeOrientation::Free ? "free" : "locked", landed_y, end.y,
                  end.z);
      if (mu > 0.0) {
        EXPECT_NEAR(end.y, landed_y, 0.1) << "orientation " << int(orientation);
        EXPECT_GT(end.z, 0.9 * radius);  // Still on the top.
      } else {
        EXPECT_GT(end.y, landed_y + 5.0) << "orientation " << int(orientation);  // Slid round.
      }
    }
  }
}

TEST(RigidBladeFriction, PulledAlongAFlatBoneItSticksThenSlidesOnce) {
  const MeshData mesh = grid_mesh(axis(-60, 60, 4), axis(-16, 16, 4), axis(-16, 8, 4));
  std::printf("%-14s %-7s %10s %10s %10s %9s\n", "friction", "orient", "max Fy N", "end Fy N",
              "max dF N", "releases");
  for (const double mu : {0.0, 0.4}) {
    const double mu_dynamic = 0.75 * mu;
    const auto space = space_of(
        mesh, [](const Vec3& c) { return c.z < 0.0; }, testing::rigid_material(mu, mu_dynamic));
    for (BladeOrientation orientation : {BladeOrientation::Free, BladeOrientation::Locked}) {
      BladeSpec spec{"knife", {-50, 0, 0}, {50, 0, 0}, 50};
      spec.orientation = orientation;
      Blade blade(*space, spec);
      blade.reset({{0, 0, 1}, {}});
      Vec3 force;
      for (int k = 1; k <= 330; ++k) {
        force = blade.step({{0, 0, std::max(-2.0, 1.0 - 0.01 * k)}, {}}, kDt).force_N;
      }
      const double push_N = 50 * kK * 2.0;
      ASSERT_NEAR(force.z, push_N, 1e-4);
      // Sideways at 10 mm/s for 3 mm.
      double most = 0.0;
      double largest_change = 0.0;
      int releases = 0;
      for (int k = 1; k <= 300; ++k) {
        const Vec3 last = force;
        force = blade.step({{0, 0.01 * k, -2.0}, {}}, kDt).force_N;
        most = std::max(most, std::abs(force.y));
        largest_change = std::max(largest_change, norm(force - last));
        releases += std::abs(force.y) < std::abs(last.y) - 0.1 ? 1 : 0;
      }
      std::printf("%-6.2f %-6.2f  %-7s %10.4f %10.4f %10.4f %9d\n", mu, mu_dynamic,
                  orientation == BladeOrientation::Free ? "free" : "locked", most, force.y,
                  largest_change, releases);
      // The hand pulls the blade: the force on it points back, -y.
      if (mu == 0.0) {
        EXPECT_LT(most, 1e-6);
        EXPECT_EQ(releases, 0);
      } else {
        EXPECT_LE(most, mu * push_N + 50 * kK * 0.01 + 1e-9);
        EXPECT_GE(most, mu * push_N - 50 * kK * 0.01);
        EXPECT_NEAR(-force.y, mu_dynamic * push_N, 0.05 * push_N);
        EXPECT_EQ(releases, 1);
      }
      EXPECT_NEAR(force.z, push_N, 1e-4);
    }
  }
}

TEST(RigidBladeFriction, LandedOnOneEndItTurnsDownOntoTheBoneAboutThatEnd) {
  // A flat bone under z = 0. The device comes down tilted 5 degrees (its
  // start lower) until that end rests on the bone, then levels 2 mm deep.
  const MeshData mesh = grid_mesh(axis(-60, 60, 4), axis(-16, 16, 4), axis(-16, 8, 4));
  const double tilt = -5.0 * M_PI / 180.0;
  const Quaternion tilted{std::cos(tilt / 2), 0.0, std::sin(tilt / 2), 0.0};
  std::printf("%-14s %-7s %14s %14s %12s\n", "friction", "orient", "highest z mm", "end x moved mm",
              "Fz N");
  for (const double mu : {0.0, 0.4}) {
    const auto space = space_of(
        mesh, [](const Vec3& c) { return c.z < 0.0; }, testing::rigid_material(mu, 0.75 * mu));
    BladeSpec spec{"knife", {-50, 0, 0}, {50, 0, 0}, 50};
    Blade blade(*space, spec);
    blade.reset({{0, 0, 6}, tilted});
    double landed_x = 0.0;
    for (int k = 1; k <= 400; ++k) {
      const BladeTick tick = blade.step({{0, 0, 6.0 - 0.01 * k}, tilted}, kDt);
      if (landed_x == 0.0 && tick.contacts > 0) landed_x = blade.ideal_point(0).x;
    }
    ASSERT_NE(landed_x, 0.0) << "the low end never reached the bone";
    // Levelled over 0.5 s, 2 mm under the bone's surface, then held.
    Vec3 force;
    for (int k = 1; k <= 700; ++k) {
      const double s = std::min(1.0, k / 500.0);
      const Quaternion turn{std::cos(tilt * (1 - s) / 2), 0.0, std::sin(tilt * (1 - s) / 2), 0.0};
      force = blade.step({{0, 0, 2.0 - 4.0 * s}, turn}, kDt).force_N;
    }
    double highest = -1e9;
    for (int i = 0; i < blade.point_count(); ++i) {
      highest = std::max(highest, blade.ideal_point(i).z);
      EXPECT_GT(blade.ideal_point(i).z, -1e-6) << "point " << i << " in the bone";
    }
    const double moved = blade.ideal_point(0).x - landed_x;
    std::printf("%-6.2f %-6.2f  %-7s %14.5f %14.5f %12.4f\n", mu, 0.75 * mu, "free", highest, moved,
                force.z);
    EXPECT_LT(highest, 0.01) << "friction " << mu << ": it still hangs on its end";
    EXPECT_NEAR(force.z, 50 * kK * 2.0, 0.1);
    // With friction the end it landed on stays where it landed: the blade turned about it.
    if (mu > 0.0) EXPECT_NEAR(moved, 0.0, 0.01);
  }
}

}  // namespace
}  // namespace hapticut
