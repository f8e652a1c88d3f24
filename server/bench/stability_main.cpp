// hapticut-stability: prints the stability tables (docs/stability.md): the servo's grid
// (stiffness up to its limit at each rate) and a stress test beyond it.
// `hapticut bench stability` runs it; options choose the grids.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <sstream>
#include <string>
#include <vector>

#include "bench/stability.h"
#include "devices/device.h"
#include "devices/profile.h"

namespace {

std::vector<double> parse_list(const char* text, double unit) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    std::size_t used = 0;
    double value = -1.0;
    try {
      value = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (item.empty() || used != item.size() || !(value >= 0.0) || !std::isfinite(value)) {
      throw std::invalid_argument("'" + item + "' in '" + text +
                                  "' is not a number >= 0 (a list is comma-separated)");
    }
    values.push_back(value * unit);
  }
  if (values.empty()) throw std::invalid_argument("an empty list");
  return values;
}

constexpr const char* kUsage =
    "usage: hapticut-stability [--rates HZ,...] [--delays MS,...] [--stiffness N_PER_MM,...]\n"
    "                          [--profile FILE.json] [--points N]\n"
    "                          [--coupling rigid|independent]\n"
    "  A virtual hand presses on bone through the engine at each servo rate, link delay and\n"
    "  stiffness, without and with the passivity controller; prints the energy the loop gives\n"
    "  the hand. Defaults: rates 250,500,1000; delays 0,1,2,5 ms; the device is the test\n"
    "  force-device profile (2 N/mm at 1 kHz), or --profile's limits.\n"
    "  Two tables by default: (1) within the servo's limit, at each rate a quarter, half and\n"
    "  all of the stiffness the servo allows the device at that rate (max_stiffness_N_per_mm x\n"
    "  min(1, rate/1000)); (2) a stress test, a quarter, half and all of the device's 1 kHz\n"
    "  maximum at every rate, rows above the servo's limit at their rate marked.\n"
    "  --stiffness: only table (2), with these absolute stiffnesses.\n"
    "  --points, --coupling: the blade stepped in the loop (default 1 point), its edge flat\n"
    "  on the bone; the stiffness is what it renders there: a rigid blade's points have k / N\n"
    "  each (N k together), independent points k each.\n"
    "Exit codes: 0 printed, 2 bad option.\n";

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace hapticut::servo;
  std::vector<double> rates = kStabilityRates_Hz;
  std::vector<double> delays = kStabilityDelays_s;
  std::vector<double> stiffness;  // Empty: both tables.
  DeviceLimits device;
  device.max_stiffness_N_per_mm = kTestForceDeviceMaxStiffness_N_per_mm;
  std::string device_name = "the test force-device profile";
  StabilityBlade blade;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string option = argv[i];
      if (option == "--help" || option == "-h") {
        std::fputs(kUsage, stdout);
        return 0;
      }
      if (i + 1 >= argc) throw std::invalid_argument(option + " needs a value");
      const char* value = argv[++i];
      if (option == "--rates") {
        rates = parse_list(value, 1.0);
      } else if (option == "--delays") {
        delays = parse_list(value, 1e-3);
      } else if (option == "--stiffness") {
        stiffness = parse_list(value, 1.0);
      } else if (option == "--points") {
        const std::vector<double> points = parse_list(value, 1.0);
        if (points.size() != 1 || points[0] < 1.0 || points[0] > 1000.0 ||
            points[0] != std::floor(points[0])) {
          throw std::invalid_argument("--points takes one whole number, 1-1000");
        }
        blade.points = static_cast<int>(points[0]);
      } else if (option == "--coupling") {
        if (std::strcmp(value, "rigid") == 0) {
          blade.coupling = hapticut::BladeCoupling::Rigid;
        } else if (std::strcmp(value, "independent") == 0) {
          blade.coupling = hapticut::BladeCoupling::Independent;
        } else {
          throw std::invalid_argument("--coupling is rigid or independent");
        }
      } else if (option == "--profile") {
        device = load_profile(value).limits;
        if (!(device.max_stiffness_N_per_mm > 0.0)) {
          throw std::invalid_argument(std::string(value) + " states no max stiffness");
        }
        device_name = value;
      } else {
        throw std::invalid_argument("unknown option " + option);
      }
    }
    for (double rate : rates) {
      if (rate < 100.0 || rate > 10000.0) throw std::invalid_argument("rates must be 100-10000 Hz");
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "hapticut-stability: %s\n%s", error.what(), kUsage);
    return 2;
  }
  const std::string k_max = number(device.max_stiffness_N_per_mm) + " N/mm";
  std::fputs(
      "Energy the loop gives the hand (mJ, largest running sum; <= 0: passive) and the\n"
      "contact's swing in the last second (mm), without and with the passivity controller.\n"
      "Device: ",
      stdout);
  std::printf("%s, %s at 1 kHz.\n", device_name.c_str(), k_max.c_str());
  std::printf("Blade in the loop: %s, %d point%s.\n\n",
              hapticut::blade_coupling_name(blade.coupling), blade.points,
              blade.points == 1 ? "" : "s");
  const bool both_tables = stiffness.empty();  // No --stiffness: the servo's grid first.
  if (both_tables) {
    std::vector<StabilityRow> rows = servo_limit_grid(device, rates, delays);
    run_stability_rows(rows, blade);
    const std::string title =
        "Within the servo's limit: at each rate a quarter, half and all of the stiffness the\n"
        "servo allows there (stiffness_limit: " +
        k_max + " x min(1, rate / 1000 Hz)).";
    std::printf("%s\n", stability_table(title, rows, false).c_str());
    stiffness = quarter_half_all(stiffness_limit(device, kStiffnessLimitRate_Hz));
  }
  std::vector<StabilityRow> rows = absolute_grid(device, rates, delays, stiffness);
  run_stability_rows(rows, blade);
  const std::string title =
      (both_tables ? "Stress test, beyond the servo's limit: a quarter, half and all of " + k_max +
                         " at every rate."
                   : std::string("The stiffnesses asked (--stiffness) at every rate.")) +
      "\nThe servo lowers a scene stiffness above its limit at the rate and refuses a set\n"
      "above it; such rows are marked.";
  std::fputs(stability_table(title, rows, true).c_str(), stdout);
  return 0;
}
