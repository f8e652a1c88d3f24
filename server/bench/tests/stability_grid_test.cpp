// The stability bench's grids (stability.h): the main grid follows the
// servo's stiffness limit per rate (stiffness_limit, server/devices/device.h), and
// with the controller none of its rows gives the hand energy.
#include <gtest/gtest.h>

#include <stdexcept>

#include "bench/stability.h"
#include "devices/device.h"
#include "test_profiles.h"

namespace hapticut::servo {
namespace {

DeviceLimits test_force_device() { return testing::force_device_profile().limits; }

TEST(StabilityGrid, DefaultDeviceIsTheTestForceDeviceProfile) {
  EXPECT_EQ(test_force_device().max_stiffness_N_per_mm, kTestForceDeviceMaxStiffness_N_per_mm);
}

TEST(StabilityGrid, MainGridAt250HzIsAQuarterOfThatAt1kHz) {
  const DeviceLimits device = test_force_device();
  const std::vector<StabilityRow> slow = servo_limit_grid(device, {250.0}, {0.0});
  const std::vector<StabilityRow> fast = servo_limit_grid(device, {1000.0}, {0.0});
  ASSERT_EQ(slow.size(), 3U);
  ASSERT_EQ(fast.size(), 3U);
  for (std::size_t i = 0; i < slow.size(); ++i) {
    EXPECT_DOUBLE_EQ(slow[i].stiffness_N_per_mm, fast[i].stiffness_N_per_mm / 4);
    EXPECT_FALSE(slow[i].above_limit);
    EXPECT_FALSE(fast[i].above_limit);
  }
  // A quarter, half and all of the servo's limit at the rate.
  EXPECT_DOUBLE_EQ(slow[0].stiffness_N_per_mm, stiffness_limit(device, 250.0) / 4);
  EXPECT_DOUBLE_EQ(slow[1].stiffness_N_per_mm, stiffness_limit(device, 250.0) / 2);
  EXPECT_DOUBLE_EQ(slow[2].stiffness_N_per_mm, stiffness_limit(device, 250.0));
  EXPECT_DOUBLE_EQ(fast[2].stiffness_N_per_mm, device.max_stiffness_N_per_mm);
  EXPECT_DOUBLE_EQ(slow[2].limit_N_per_mm, stiffness_limit(device, 250.0));
}

TEST(StabilityGrid, MainGridCoversEveryDefaultRateAndDelay) {
  const std::vector<StabilityRow> rows =
      servo_limit_grid(test_force_device(), kStabilityRates_Hz, kStabilityDelays_s);
  EXPECT_EQ(rows.size(), kStabilityRates_Hz.size() * kStabilityDelays_s.size() * 3);
  for (const StabilityRow& row : rows) {
    EXPECT_FALSE(row.above_limit);
    EXPECT_LE(row.stiffness_N_per_mm, row.limit_N_per_mm);
    EXPECT_GT(row.stiffness_N_per_mm, 0.0);
  }
}

TEST(StabilityGrid, MainGridNeedsADeviceLimit) {
  EXPECT_THROW(servo_limit_grid(DeviceLimits{}, {1000.0}, {0.0}), std::invalid_argument);
}

TEST(StabilityGrid, AbsoluteGridMarksTheRowsAboveTheServosLimit) {
  const std::vector<StabilityRow> rows =
      absolute_grid(test_force_device(), {250.0, 500.0, 1000.0}, {0.0}, {0.5, 1.0, 2.0});
  ASSERT_EQ(rows.size(), 9U);
  for (const StabilityRow& row : rows) {
    // 2 N/mm at 1 kHz: 0.5 N/mm at 250 Hz, 1 N/mm at 500 Hz; at the limit is within it.
    const bool above = (row.servo_rate_Hz == 250.0 && row.stiffness_N_per_mm > 0.5) ||
                       (row.servo_rate_Hz == 500.0 && row.stiffness_N_per_mm > 1.0);
    EXPECT_EQ(row.above_limit, above)
        << row.servo_rate_Hz << " Hz, " << row.stiffness_N_per_mm << " N/mm";
  }
  // No limit known: nothing is above it.
  for (const StabilityRow& row : absolute_grid(DeviceLimits{}, {250.0}, {0.0}, {2.0})) {
    EXPECT_FALSE(row.above_limit);
  }
}

// The claim on what the servo can render: at every default rate and
// delay, at a quarter, half and all of the servo's limit, the loop with the
// controller gives the hand no energy.
TEST(StabilityGrid, EveryMainGridRowGivesNoEnergyWithTheController) {
  for (const StabilityRow& row :
       servo_limit_grid(test_force_device(), kStabilityRates_Hz, kStabilityDelays_s)) {
    const StabilityResult with = run_stability_case(stability_case(row, true));
    EXPECT_LE(with.max_energy_to_hand_mJ, 0.0)
        << row.servo_rate_Hz << " Hz, " << row.link_delay_s * 1e3 << " ms, "
        << row.stiffness_N_per_mm << " N/mm";
    EXPECT_LT(with.late_swing_mm, 2.0);
  }
}

}  // namespace
}  // namespace hapticut::servo
