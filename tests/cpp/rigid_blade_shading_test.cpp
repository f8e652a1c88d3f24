// Force shading of a rigid blade (docs/decisions.md, "The rigid blade"): on a
// faceted sphere the shaded force follows the sphere, where the plain force
// follows the facets; with shading off the force is the springs' sum; on a
// flat bone shading changes nothing.
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

double degrees_between(const Vec3& a, const Vec3& b) {
  return std::acos(std::clamp(dot(a, b) / (norm(a) * norm(b)), -1.0, 1.0)) * 180.0 / M_PI;
}

RuntimeSettings shading(const Space& space, bool on) {
  RuntimeSettings settings = space.runtime_settings();
  settings.force_shading = on;
  return settings;
}

// An example sphere of bone (radius 30 mm about the origin) in air.
std::shared_ptr<const Space> example_sphere(const std::string& name) {
  return Space::from_scene(
      load_scene(std::string(HAPTICUT_EXAMPLES_DIR) + "/" + name + ".hapticut.msgpack"));
}

// A blade along x: one point at the origin of the tool frame, or 50 on a
// 40 mm edge centred on it.
BladeSpec knife(int points) {
  return points == 1 ? BladeSpec{"point", {0, 0, 0}, {0, 0, 0}, 1}
                     : BladeSpec{"knife", {-20, 0, 0}, {20, 0, 0}, points};
}

// The blade pressed along -d onto the sphere, from 3 mm outside to 2 mm
// inside (d across the edge, so the edge lies along the sphere's tangent),
// then held: the angle between the force and the sphere's normal d there.
double pressed_error_deg(const std::shared_ptr<const Space>& space, int points, const Vec3& d,
                         bool shaded) {
  constexpr double kRadius = 30.0;
  Blade blade(space, knife(points));
  const RuntimeSettings settings = shading(*space, shaded);
  blade.reset({d * (kRadius + 3.0), {}});
  constexpr int kPress = 250;
  Vec3 force;
  for (int k = 1; k <= kPress + 50; ++k) {
    const double height = kRadius + 3.0 - 5.0 * std::min(k, kPress) / kPress;
    force = blade.step({d * height, {}}, kDt, settings).force_N;
  }
  EXPECT_GT(norm(force), 0.0);
  return degrees_between(force, d);
}

TEST(RigidBladeShading, OnAFacetedSphereTheForceFollowsTheSphere) {
  std::printf("%-10s %6s %14s %14s\n", "sphere", "points", "plain deg", "shaded deg");
  for (const char* name : {"sphere80", "sphere320"}) {
    const auto space = example_sphere(name);
    for (const int points : {1, 50}) {
      double plain_sum = 0.0;
      double shaded_sum = 0.0;
      double shaded_most = 0.0;
      int presses = 0;
      // Directions across the edge (x): off every symmetry of the icosphere.
      for (const double degrees : {7.0, 23.0, 41.0, 58.0, 77.0, 131.0}) {
        const double a = degrees * M_PI / 180.0;
        const Vec3 d{0.0, std::sin(a), std::cos(a)};
        plain_sum += pressed_error_deg(space, points, d, false);
        const double shaded = pressed_error_deg(space, points, d, true);
        shaded_sum += shaded;
        shaded_most = std::max(shaded_most, shaded);
        ++presses;
      }
      const double plain_mean = plain_sum / presses;
      const double shaded_mean = shaded_sum / presses;
      std::printf("%-10s %6d %14.4f %14.4f (most %.4f)\n", name, points, plain_mean, shaded_mean,
                  shaded_most);
      EXPECT_GT(plain_mean, 1.0) << name << " " << points;  // The facets are felt.
      EXPECT_LT(shaded_mean, 0.1 * plain_mean) << name << " " << points;
      EXPECT_LT(shaded_most, 0.5) << name << " " << points;
    }
  }
}

TEST(RigidBladeShading, OffTheForceIsTheSpringsSum) {
  const auto space = example_sphere("sphere80");
  const Vec3 d = Vec3{0.0, std::sin(0.4), std::cos(0.4)};
  for (const int points : {1, 50}) {
    Blade plain(space, knife(points));
    Blade shaded(space, knife(points));
    plain.reset({d * 33.0, {}});
    shaded.reset({d * 33.0, {}});
    bool differed = false;
    for (int k = 1; k <= 300; ++k) {
      const Pose pose{d * (33.0 - 0.02 * std::min(k, 250)) + Vec3{0.01 * k, 0.0, 0.0}, {}};
      const BladeTick tick = plain.step(pose, kDt, shading(*space, false));
      Vec3 sum;
      for (int i = 0; i < points; ++i) sum += plain.point_force(i);
      ASSERT_EQ(tick.force_N, sum) << "tick " << k;
      const BladeTick other = shaded.step(pose, kDt, shading(*space, true));
      // The same pose either way: shading changes the force, not the blade.
      ASSERT_EQ(plain.ideal_point(0), shaded.ideal_point(0)) << "tick " << k;
      differed = differed || !(other.force_N == tick.force_N);
    }
    EXPECT_TRUE(differed) << points;  // Shading on does change it on the facets.
  }
}

TEST(RigidBladeShading, OnAFlatBoneShadingChangesNothing) {
  // Bone below z = 0 in 4 mm cells: a plane's shaded normal is its own.
  const auto space = testing::labelled_space(
      grid_mesh(testing::axis(-24, 24, 4), testing::axis(-24, 24, 4), testing::axis(-12, 12, 4)),
      [](const Vec3& c) { return c.z < 0.0; });
  for (const int points : {1, 50}) {
    BladeSpec spec = points == 1 ? knife(1) : BladeSpec{"knife", {-10, 0, 0}, {10, 0, 0}, 50};
    Blade plain(space, spec);
    Blade shaded(space, spec);
    // Tilted about y, so one end lands first, then pressed and slid along y.
    const Quaternion tilt{std::cos(0.025), 0.0, std::sin(0.025), 0.0};
    plain.reset({{0, 0, 2}, tilt});
    shaded.reset({{0, 0, 2}, tilt});
    double largest = 0.0;
    for (int k = 1; k <= 400; ++k) {
      const Pose pose{{0, 0.01 * std::max(0, k - 300), 2.0 - 0.02 * std::min(k, 200)}, tilt};
      const BladeTick a = plain.step(pose, kDt, shading(*space, false));
      const BladeTick b = shaded.step(pose, kDt, shading(*space, true));
      largest = std::max(largest, norm(a.force_N - b.force_N) / std::max(1.0, norm(a.force_N)));
      ASSERT_LE(norm(a.torque_N_mm - b.torque_N_mm), 1e-9 * std::max(1.0, norm(a.torque_N_mm)))
          << "tick " << k;
    }
    EXPECT_LE(largest, 1e-9) << points;
  }
}

// A V-groove of bone along x, its flanks rising by `slope` x |y| (a Kuhn grid
// of 4 x 2 x 2 mm cells, every vertex lifted; bone below the lifted z = 0).
std::shared_ptr<const Space> v_groove(double slope) {
  return testing::v_groove(testing::axis(-40, 40, 4), testing::axis(-16, 16, 2),
                           testing::axis(-16, 16, 2), slope);
}

TEST(RigidBladeShading, InAGrooveTheForceStaysAlongItsMiddle) {
  // Pressed into a groove along it, the edge rests on both flanks: sharper
  // than the crease angle (90 degrees) each keeps its push; gentler (30
  // degrees), the flanks are one smooth surface touching the edge along both
  // sides. Either way the force stays up the groove's middle, its size kept.
  for (const double slope : {1.0, std::tan(15.0 * M_PI / 180.0)}) {
    const auto space = v_groove(slope);
    const BladeSpec spec{"knife", {-20, 0, 0}, {20, 0, 0}, 50};
    Blade plain(space, spec);
    Blade shaded(space, spec);
    plain.reset({{0, 0, 2}, {}});
    shaded.reset({{0, 0, 2}, {}});
    BladeTick a;
    BladeTick b;
    for (int k = 1; k <= 300; ++k) {
      const Pose pose{{0, 0, 2.0 - 0.02 * std::min(k, 150)}, {}};
      a = plain.step(pose, kDt, shading(*space, false));
      b = shaded.step(pose, kDt, shading(*space, true));
    }
    std::printf("slope %.3f: plain %.6f %.6f %.6f, shaded %.6f %.6f %.6f\n", slope, a.force_N.x,
                a.force_N.y, a.force_N.z, b.force_N.x, b.force_N.y, b.force_N.z);
    EXPECT_GT(a.force_N.z, 1.0) << slope;
    EXPECT_LT(degrees_between(b.force_N, {0, 0, 1}), 0.01) << slope;
    EXPECT_NEAR(norm(b.force_N), norm(a.force_N), 1e-9 * norm(a.force_N)) << slope;
  }
}

}  // namespace
}  // namespace hapticut
