// hapticut-stability: prints the stability table (docs/stability.md).
// `hapticut bench stability` runs it; options choose the grid.
#include <cstdio>
#include <cstring>
#include <exception>
#include <sstream>
#include <string>
#include <vector>

#include "devices/profile.h"
#include "devices/stability.h"

namespace {

std::vector<double> parse_list(const char* text, double unit) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    std::size_t used = 0;
    const double value = std::stod(item, &used);
    if (used != item.size() || !(value >= 0.0)) throw std::invalid_argument(item);
    values.push_back(value * unit);
  }
  if (values.empty()) throw std::invalid_argument(text);
  return values;
}

constexpr const char* kUsage =
    "usage: hapticut-stability [--rates HZ,...] [--delays MS,...] [--stiffness N_PER_MM,...]\n"
    "                          [--profile FILE.json]\n"
    "  A virtual hand presses on bone through the engine at each servo rate, link delay and\n"
    "  stiffness, without and with the passivity controller; prints the energy the loop gives\n"
    "  the hand. Defaults: rates 250,500,1000; delays 0,1,2,5 ms; stiffness 0.5,1,2 N/mm, or\n"
    "  a quarter, half and all of a profile's max_stiffness_N_per_mm with --profile.\n"
    "Exit codes: 0 printed, 2 bad option.\n";

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> rates{250.0, 500.0, 1000.0};
  std::vector<double> delays{0.0, 0.001, 0.002, 0.005};
  std::vector<double> stiffness{0.5, 1.0, 2.0};
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
      } else if (option == "--profile") {
        const double k = hapticut::servo::load_profile(value).limits.max_stiffness_N_per_mm;
        if (k <= 0.0) throw std::invalid_argument(std::string(value) + " states no max stiffness");
        stiffness = {k / 4, k / 2, k};
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
  std::fputs(hapticut::servo::stability_table(rates, delays, stiffness).c_str(), stdout);
  return 0;
}
