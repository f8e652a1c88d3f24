// The stability bench's closed loop (stability.h) with and without the
// passivity controller.
#include "bench/stability.h"

#include <gtest/gtest.h>

namespace hapticut::servo {
namespace {

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

// Corners where the observer alone, acting only once the observed energy
// turned negative, let the hand take energy (up to half a millijoule): each
// gives energy and buzzes without the controller and gives none with it.
TEST(Stability, LateCornersGiveNoEnergyWithTheController) {
  struct Corner {
    double rate_Hz;
    double delay_s;
    double stiffness_N_per_mm;
  };
  for (const Corner corner :
       {Corner{250.0, 0.001, 1.0}, Corner{250.0, 0.001, 2.0}, Corner{250.0, 0.002, 2.0},
        Corner{250.0, 0.005, 0.5}, Corner{250.0, 0.005, 1.0}, Corner{500.0, 0.001, 2.0},
        Corner{500.0, 0.005, 2.0}, Corner{1000.0, 0.005, 2.0}}) {
    SCOPED_TRACE(testing::Message() << corner.rate_Hz << " Hz, " << corner.delay_s * 1e3 << " ms, "
                                    << corner.stiffness_N_per_mm << " N/mm");
    StabilityCase c;
    c.servo_rate_Hz = corner.rate_Hz;
    c.link_delay_s = corner.delay_s;
    c.stiffness_N_per_mm = corner.stiffness_N_per_mm;
    c.passivity = false;
    const StabilityResult without = run_stability_case(c);
    c.passivity = true;
    const StabilityResult with = run_stability_case(c);
    EXPECT_GT(without.max_energy_to_hand_mJ, 1.0);
    EXPECT_LE(with.max_energy_to_hand_mJ, 0.0);
    EXPECT_LT(with.late_swing_mm, 2.0);  // Settled, where it swung centimetres.
  }
}

// The slowest, latest corner (250 Hz, 5 ms, 2 N/mm): the hand turns within
// the 11 ms the servo cannot see; the sum stays far below the hand's kinetic
// energy at the press speed (0.36 mJ; the observer alone let it reach 1.9 mJ).
TEST(Stability, SlowLateCornerStaysBoundedWithTheController) {
  StabilityCase c;
  c.servo_rate_Hz = 250.0;
  c.link_delay_s = 0.005;
  c.stiffness_N_per_mm = 2.0;
  c.passivity = false;
  const StabilityResult without = run_stability_case(c);
  c.passivity = true;
  const StabilityResult with = run_stability_case(c);
  EXPECT_LT(with.max_energy_to_hand_mJ, 0.5);
  EXPECT_LT(with.late_swing_mm, 0.01 * without.late_swing_mm);
  EXPECT_LT(with.late_swing_mm, 1.0);
}

// Where the loop is passive by itself the controller leaves the force alone.
TEST(Stability, ControllerLeavesLocalSoftLoopsAlone) {
  for (const double rate_Hz : {250.0, 500.0, 1000.0}) {
    for (const double k : {0.5, 1.0}) {
      StabilityCase c;
      c.servo_rate_Hz = rate_Hz;
      c.stiffness_N_per_mm = k;
      const StabilityResult with = run_stability_case(c);
      EXPECT_EQ(with.passivity_active_ticks, 0U) << rate_Hz << " Hz, " << k << " N/mm";
      EXPECT_GT(with.peak_force_N, 1.0);
    }
  }
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

// The loop steps a real blade. A rigid blade of 50 points at its rendered
// stiffness (each point k / 50) is one body on the bone: the loop behaves as
// for one point at that stiffness. Independent points at that k each render
// 50 k pressed flat on the bone: without the controller that loop buzzes.
TEST(Stability, TheBladeInTheLoopRendersItsPointsTogether) {
  StabilityCase one;
  one.servo_rate_Hz = 1000.0;
  one.link_delay_s = 0.002;
  one.stiffness_N_per_mm = 0.5;
  one.passivity = false;
  StabilityCase rigid = one;
  rigid.points = 50;
  EXPECT_DOUBLE_EQ(point_stiffness_N_per_mm(rigid), 0.01);
  const StabilityResult alone = run_stability_case(one);
  const StabilityResult blade = run_stability_case(rigid);
  EXPECT_NEAR(blade.peak_force_N, alone.peak_force_N, 1e-6 * alone.peak_force_N);
  EXPECT_NEAR(blade.late_swing_mm, alone.late_swing_mm, 1e-6);
  EXPECT_LE(blade.max_energy_to_hand_mJ, 1e-9);
  StabilityCase independent = rigid;
  independent.coupling = BladeCoupling::Independent;
  EXPECT_DOUBLE_EQ(point_stiffness_N_per_mm(independent), 0.5);
  const StabilityResult points = run_stability_case(independent);
  EXPECT_GT(points.max_energy_to_hand_mJ, 1.0);
  EXPECT_GT(points.peak_force_N, 10.0 * alone.peak_force_N);
}

}  // namespace
}  // namespace hapticut::servo
