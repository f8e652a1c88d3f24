// The stability bench (`hapticut bench stability`, docs/stability.md): the
// closed loop of a virtual hand (virtual_hand.h) pressing on a rigid block
// ("bone") through the real engine (a Proxy on a Space), with a link delay
// and a servo rate, with and without the passivity controller. It measures
// the energy the loop gives the hand: the work of the rendered force on the
// hand's own motion, integrated at the hand's 10 kHz physics step.
#pragma once

#include <string>
#include <vector>

#include "devices/passivity.h"

namespace hapticut::servo {

struct StabilityCase {
  double servo_rate_Hz = 1000.0;
  double link_delay_s =
      0.0;  // From the hand's pose to the servo (the force path adds one tick's hold).
  double stiffness_N_per_mm = 1.0;
  bool passivity = true;
  double duration_s = 2.0;
};

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

// The table for the given rates, delays and stiffnesses, each with and without the controller.
std::string stability_table(const std::vector<double>& rates_Hz,
                            const std::vector<double>& delays_s,
                            const std::vector<double>& stiffnesses_N_per_mm);

}  // namespace hapticut::servo
