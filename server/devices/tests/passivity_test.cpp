#include "devices/passivity.h"

#include <gtest/gtest.h>

#include "devices/stability.h"

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

TEST(Passivity, NonFiniteInputRendersNothing) {
  HannafordRyuPassivity controller;
  EXPECT_EQ(controller.observe({0, 0, NAN}, {0, 0, 1.0}, 1e-3), Vec3{});
  EXPECT_EQ(controller.observe({0, 0, 1.0}, {0, 0, INFINITY}, 1e-3), Vec3{});
  EXPECT_EQ(controller.observe({0, 0, 1.0}, {0, 0, 1.0}, 0.0), Vec3{});
}

// The bench's claim where the observer sees the link well: a 1 kHz servo
// behind a 2 ms link on stiff bone buzzes without the controller and gives
// the hand no energy with it.
TEST(Stability, LateStiffLoopGivesEnergyWithoutTheControllerAndNoneWithIt) {
  StabilityCase c;
  c.servo_rate_Hz = 1000.0;
  c.link_delay_s = 0.002;
  c.stiffness_N_per_mm = 2.0;
  c.passivity = false;
  const StabilityResult without = run_stability_case(c);
  c.passivity = true;
  const StabilityResult with = run_stability_case(c);
  EXPECT_GT(without.max_energy_to_hand_mJ, 1.0);
  EXPECT_GT(without.late_swing_mm, 5.0);  // Buzzing.
  EXPECT_LE(with.max_energy_to_hand_mJ, 1e-9);
  EXPECT_GT(with.passivity_active_ticks, 0U);
  EXPECT_LT(with.late_swing_mm, 1.0);
}

// The slow, late corner (250 Hz, 5 ms): the controller cannot see the hand
// soon enough to keep the sum at zero, but it keeps the contact from buzzing.
TEST(Stability, SlowLateCornerStaysBoundedWithTheController) {
  StabilityCase c;
  c.servo_rate_Hz = 250.0;
  c.link_delay_s = 0.005;
  c.stiffness_N_per_mm = 2.0;
  c.passivity = false;
  const StabilityResult without = run_stability_case(c);
  c.passivity = true;
  const StabilityResult with = run_stability_case(c);
  EXPECT_LT(with.max_energy_to_hand_mJ, 1e-3 * without.max_energy_to_hand_mJ);
  EXPECT_LT(with.late_swing_mm, 0.01 * without.late_swing_mm);
}

TEST(Stability, FastLocalSoftLoopIsPassiveEitherWay) {
  StabilityCase c;
  c.servo_rate_Hz = 1000.0;
  c.stiffness_N_per_mm = 0.5;
  c.passivity = false;
  const StabilityResult without = run_stability_case(c);
  EXPECT_GT(without.peak_force_N, 1.0);  // It did touch the bone.
  EXPECT_LE(without.final_energy_to_hand_mJ, 0.0);
}

}  // namespace
}  // namespace hapticut::servo
