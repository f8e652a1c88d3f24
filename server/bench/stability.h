// The stability bench (`hapticut bench stability`, docs/stability.md): the
// closed loop of a virtual hand (devices/virtual_hand.h) pressing on a rigid block
// ("bone") through the real engine (a Blade, rigid or independent, lying flat
// on the block's top as the hand pushes it down), with a link delay
// and a servo rate, with and without the passivity controller. It measures
// the energy the loop gives the hand: the work of the rendered force on the
// hand's own motion, integrated at the hand's 10 kHz physics step.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "devices/device.h"
#include "hapticut/scene.h"
#include "passivity.h"

namespace hapticut::servo {

struct StabilityCase {
  double servo_rate_Hz = 1000.0;
  double link_delay_s =
      0.0;  // From the hand's pose to the servo (the force path adds one tick's hold).
  double stiffness_N_per_mm = 1.0;
  bool passivity = true;
  double duration_s = 2.0;
  // The blade stepped in the loop, its edge 40 mm long lying flat on the
  // block. stiffness_N_per_mm is what it renders pressed on the block: its
  // points' spring k is that over the points for a rigid blade (n k in
  // contact), that itself for independent points (hapticut.stiffness).
  int points = 1;
  BladeCoupling coupling = BladeCoupling::Rigid;
};

// The spring k of each point of the case's blade.
double point_stiffness_N_per_mm(const StabilityCase& c);

struct StabilityResult {
  // Work of the rendered force on the hand, mJ (N mm): the largest running
  // sum over the run (> 0: the loop has given the hand energy) and the sum at the end.
  double max_energy_to_hand_mJ = 0.0;
  double final_energy_to_hand_mJ = 0.0;
  double peak_force_N = 0.0;
  // Largest penetration swing (mm) in the last half of the run: a buzzing
  // contact swings, a settled one does not.
  double late_swing_mm = 0.0;
  std::uint64_t passivity_active_ticks = 0;
};

StabilityResult run_stability_case(const StabilityCase& c);

// The device the bench's grids are for unless a profile is given: the test
// force-device profile (server/devices/tests/data/example-force-device.json,
// not installed, hence stated here; a test holds the two equal).
inline constexpr double kTestForceDeviceMaxStiffness_N_per_mm = 2.0;

// The bench's default rates and link delays.
inline const std::vector<double> kStabilityRates_Hz{250.0, 500.0, 1000.0};
inline const std::vector<double> kStabilityDelays_s{0.0, 0.001, 0.002, 0.005};

// The blade every row of a table is run with.
struct StabilityBlade {
  int points = 1;
  BladeCoupling coupling = BladeCoupling::Rigid;
};

// One row of a table: a rate, a delay and a stiffness, run without and with
// the controller.
struct StabilityRow {
  double servo_rate_Hz = 1000.0;
  double link_delay_s = 0.0;
  double stiffness_N_per_mm = 1.0;
  // The servo's limit at this rate for the grid's device (stiffness_limit,
  // server/devices/device.h; 0: none known) and whether the stiffness is above it
  // (the servo would lower such a scene stiffness and refuse such a set).
  double limit_N_per_mm = 0.0;
  bool above_limit = false;
  StabilityResult without;  // Filled by run_stability_rows.
  StabilityResult with;
};

// A quarter, half and all of a stiffness limit: the stiffnesses of a grid.
std::vector<double> quarter_half_all(double limit_N_per_mm);

// The grid the servo can render: at each rate a quarter, half and all of
// stiffness_limit(device, rate), each at every delay. The device must state a
// limit (max_stiffness_N_per_mm > 0), else std::invalid_argument.
std::vector<StabilityRow> servo_limit_grid(const DeviceLimits& device,
                                           const std::vector<double>& rates_Hz,
                                           const std::vector<double>& delays_s);

// Every stiffness (absolute, N/mm) at every rate and delay, each row marked
// against the device's limit at its rate.
std::vector<StabilityRow> absolute_grid(const DeviceLimits& device,
                                        const std::vector<double>& rates_Hz,
                                        const std::vector<double>& delays_s,
                                        const std::vector<double>& stiffnesses_N_per_mm);

// The case of a row, without or with the controller.
StabilityCase stability_case(const StabilityRow& row, bool passivity,
                             const StabilityBlade& blade = {});

// Runs every row without and with the controller.
void run_stability_rows(std::vector<StabilityRow>& rows, const StabilityBlade& blade = {});

// Rows with energy > 0 (the loop gave the hand energy), without or with the controller.
int rows_giving_energy(const std::vector<StabilityRow>& rows, bool passivity);

// The table of run rows, under `title`; mark_limit adds the column "above
// the servo's limit at this rate" and a summary of the rows within it.
std::string stability_table(const std::string& title, const std::vector<StabilityRow>& rows,
                            bool mark_limit);

}  // namespace hapticut::servo
