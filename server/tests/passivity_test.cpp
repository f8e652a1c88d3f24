#include "passivity.h"

#include <gtest/gtest.h>

namespace hapticut::servo {
namespace {

TEST(Passivity, PassesForceWhileTheEnvironmentAbsorbsEnergy) {
  HannafordRyuPassivity controller;
  // A wall pushing back against a hand moving into it (f . v < 0): absorbing.
  for (int i = 0; i < 10; ++i) {
    const Vec3 out = controller.observe({0, 0, 1.0}, {0, 0, -10.0}, 1e-3);
    EXPECT_EQ(out, (Vec3{0, 0, 1.0}));
  }
  EXPECT_GT(controller.observed_energy_mJ(), 0.0);
  EXPECT_EQ(controller.active_ticks(), 0U);
}

TEST(Passivity, DampsWhenTheObservedEnergyWouldTurnNegative) {
  HannafordRyuPassivity controller;
  // A force along the motion gives the hand energy from the first tick.
  const Vec3 out = controller.observe({0, 0, 2.0}, {0, 0, 10.0}, 1e-3);
  EXPECT_LT(out.z, 2.0);
  EXPECT_EQ(controller.active_ticks(), 1U);
  EXPECT_GT(controller.last_damping_N_s_per_mm(), 0.0);
  // The next tick observes the rendered force's work: what the damping left
  // is no energy given (up to the damping cap).
  controller.observe({0, 0, 2.0}, {0, 0, 10.0}, 1e-3);
  EXPECT_GE(controller.observed_energy_mJ(), -1e-12);
}

TEST(Passivity, DisabledControllerPassesEverything) {
  PassivitySettings settings;
  settings.enabled = false;
  HannafordRyuPassivity controller(settings);
  EXPECT_EQ(controller.observe({0, 0, 2.0}, {0, 0, 10.0}, 1e-3), (Vec3{0, 0, 2.0}));
}

// A spring seen two ticks late, the hand leaving it: the controller measures
// the spring's stiffness from the asked forces and takes the lag's surplus
// off, never rendering more than asked or pulling the hand in.
TEST(Passivity, LateSpringReleasingTheHandIsCompensated) {
  PassivitySettings settings;
  settings.link_delay_ticks = 2.0;
  HannafordRyuPassivity controller(settings);
  const double k = 1.5;  // N/mm
  const double dt = 1e-3;
  double z = 0.0;     // Penetration the servo sees, mm.
  double speed = 40;  // mm/s, into the wall.
  bool compensated = false;
  for (int i = 0; i < 40; ++i) {
    if (i == 20) speed = -40;  // The hand turns and leaves.
    const double previous = z;
    z = std::max(0.0, z + speed * dt);
    const Vec3 asked{0, 0, k * z};
    const Vec3 velocity{0, 0, -(z - previous) / dt};  // Up is out of the wall.
    const Vec3 out = controller.observe(asked, velocity, dt);
    EXPECT_LE(norm(out), norm(asked) + 1e-12);
    EXPECT_GE(out.z, -1e-12);  // Never pulls the hand in.
    if (i > 20 && i < 30 && out.z < asked.z - 1e-9) compensated = true;
    if (i < 20) EXPECT_EQ(out, asked);  // Entering: absorbing, untouched.
  }
  EXPECT_NEAR(controller.stiffness_N_per_mm(), k, 1e-9);
  EXPECT_TRUE(compensated);
  EXPECT_GT(controller.active_ticks(), 0U);
}

TEST(Passivity, DampingStaysUnderTheCap) {
  PassivitySettings settings;
  settings.link_delay_ticks = 5.0;
  settings.max_damping_N_s_per_mm = 0.01;
  HannafordRyuPassivity controller(settings);
  // A stiff force pushing along a slow motion: the cap bounds what is taken off.
  for (int i = 0; i < 20; ++i) {
    const Vec3 asked{0, 0, 10.0 + 2.0 * i};
    const Vec3 velocity{0, 0, 5.0};
    const Vec3 out = controller.observe(asked, velocity, 1e-3);
    EXPECT_LE(controller.last_damping_N_s_per_mm(), 0.01 + 1e-12);
    EXPECT_LE(norm(out), norm(asked) + 1e-12);
  }
}

TEST(Passivity, NonFiniteInputRendersNothing) {
  HannafordRyuPassivity controller;
  EXPECT_EQ(controller.observe({0, 0, NAN}, {0, 0, 1.0}, 1e-3), Vec3{});
  EXPECT_EQ(controller.observe({0, 0, 1.0}, {0, 0, INFINITY}, 1e-3), Vec3{});
  EXPECT_EQ(controller.observe({0, 0, 1.0}, {0, 0, 1.0}, 0.0), Vec3{});
}

}  // namespace
}  // namespace hapticut::servo
