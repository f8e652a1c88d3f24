// The rigid blade along a concave crease of bone: it slides along the groove
// and up its side with the force its pose explains, whatever the number of
// points, free or locked (the contact set keeps two samples per plane).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "hapticut/blade.h"
#include "test_support.h"

namespace hapticut {
namespace {

constexpr double kDt = 0.001;
constexpr double kK = 0.1;  // N/mm, the paper's.

using testing::axis;

// A 90 degree V-groove of bone running along x: a Kuhn grid of 4 x 2 x 2 mm
// cells with every vertex lifted by |y|, bone below the lifted z = 0 (the
// groove's bottom line is the x axis).
std::shared_ptr<const Space> v_groove() {
  return testing::v_groove(axis(-80, 80, 4), axis(-16, 16, 2), axis(-16, 16, 2), 1.0);
}

struct Slide {
  Vec3 end_force;
  double largest_lateral_N = 0.0;  // |F_x| along the groove, |F_y| going up its side.
  double largest_change_N = 0.0;   // |F(k) - F(k - 1)|.
  int unresolved = 0;
  int most_contacts = 0;
  int most_rounds = 0;
};

// Steps the blade to each device position in turn, recording the force's changes.
void slide(Blade& blade, const std::vector<Vec3>& path, Vec3& last_force, Slide& out,
           bool along_x) {
  for (const Vec3& p : path) {
    const BladeTick tick = blade.step({p, {}}, kDt);
    out.largest_change_N = std::max(out.largest_change_N, norm(tick.force_N - last_force));
    out.largest_lateral_N =
        std::max(out.largest_lateral_N, std::abs(along_x ? tick.force_N.x : tick.force_N.y));
    out.unresolved += tick.unresolved ? 1 : 0;
    out.most_contacts = std::max(out.most_contacts, tick.contacts);
    out.most_rounds = std::max(out.most_rounds, tick.rigid_rounds);
    last_force = tick.force_N;
    out.end_force = tick.force_N;
  }
}

TEST(RigidBladeCrease, SlidesAlongAVGrooveAndUpItsSideWithTheForceItsPoseExplains) {
  const auto space = v_groove();
  std::printf("V-groove, pressed 1 mm, 20 mm along at 10 mm/s, then 3 mm sideways:\n");
  std::printf("%-7s %6s | %-22s %8s %8s %6s %5s | %8s %8s\n", "orient", "points",
              "force at the end (N)", "|Fx| max", "max dF", "unres", "cont", "side dF", "side unr");
  for (BladeOrientation orientation : {BladeOrientation::Free, BladeOrientation::Locked}) {
    for (int points : {50, 100}) {
      BladeSpec spec{"knife", {-50, 0, 0}, {50, 0, 0}, points};
      spec.orientation = orientation;
      Blade blade(*space, spec);
      blade.reset({{0, 0, 3}, {}});
      Vec3 force;
      for (int k = 1; k <= 60; ++k)
        force = blade.step({{0, 0, 3 - 0.1 * std::min(k, 40)}, {}}, kDt).force_N;
      const double pressed_N = points * kK * 1.0;
      EXPECT_NEAR(force.z, pressed_N, 1e-3 * pressed_N);
      std::vector<Vec3> along;
      for (int k = 1; k <= 2000; ++k) along.push_back({0.01 * k, 0, -1});
      Slide groove;
      slide(blade, along, force, groove, true);
      std::vector<Vec3> side;
      for (int k = 1; k <= 300; ++k) side.push_back({20, 0.01 * k, -1});
      Slide up;
      slide(blade, side, force, up, false);
      const char* name = orientation == BladeOrientation::Free ? "free" : "locked";
      std::printf("%-7s %6d | (%6.3f, %6.3f, %6.3f) %8.4f %8.4f %6d %5d | %8.4f %8d\n", name,
                  points, groove.end_force.x, groove.end_force.y, groove.end_force.z,
                  groove.largest_lateral_N, groove.largest_change_N, groove.unresolved,
                  groove.most_contacts, up.largest_change_N, up.unresolved);
      // Along the groove: only the press, no drag, and every tick resolved.
      EXPECT_LT(groove.largest_lateral_N, 1e-3 * pressed_N) << name << " " << points;
      EXPECT_NEAR(groove.end_force.z, pressed_N, 1e-3 * pressed_N) << name << " " << points;
      EXPECT_EQ(groove.unresolved, 0) << name << " " << points;
      EXPECT_LE(groove.most_contacts, 4 + 2) << name << " " << points;
      // Each tick moves the device 0.01 mm: n k 0.01 N of force at most,
      // whatever the groove does to the pose (a slope of 45 degrees).
      const double per_tick_N = points * kK * 0.01;
      EXPECT_LT(groove.largest_change_N, 2.0 * per_tick_N) << name << " " << points;
      EXPECT_LT(up.largest_change_N, 2.0 * per_tick_N) << name << " " << points;
      EXPECT_EQ(up.unresolved, 0) << name << " " << points;
      // The device 3 mm sideways and 1 mm down: on the 45 degree side z = y the
      // nearest place is (1, 1).
      EXPECT_NEAR(blade.ideal_point(points / 2).y, 1.0, 1e-3) << name << " " << points;
      EXPECT_NEAR(blade.ideal_point(points / 2).z, 1.0, 1e-3) << name << " " << points;
    }
  }
}

TEST(RigidBladeCrease, TheIdealQuaternionStaysInTheHemisphereOfTheLastOne) {
  const auto space = v_groove();
  for (BladeCoupling coupling : {BladeCoupling::Rigid, BladeCoupling::Independent}) {
    BladeSpec spec{"knife", {-50, 0, 0}, {50, 0, 0}, 50};
    spec.coupling = coupling;
    Blade blade(*space, spec);
    const double half = 0.5 * 0.3;
    const Quaternion turned{std::cos(half), 0, 0, std::sin(half)};
    blade.reset({{0, 0, 5}, turned});
    Quaternion last = blade.ideal_pose().rotation;
    for (int k = 1; k <= 20; ++k) {
      const double sign = k % 2 == 0 ? 1.0 : -1.0;
      blade.step({{0, 0, 5}, {sign * turned.w, 0, 0, sign * turned.z}}, kDt);
      const Quaternion& q = blade.ideal_pose().rotation;
      EXPECT_GT(q.w * last.w + q.x * last.x + q.y * last.y + q.z * last.z, 0.0) << "tick " << k;
      last = q;
    }
  }
}

}  // namespace
}  // namespace hapticut
