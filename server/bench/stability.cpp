#include "bench/stability.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <sstream>
#include <stdexcept>

#include "devices/virtual_hand.h"
#include "hapticut/blade.h"
#include "hapticut/reference_meshes.h"
#include "hapticut/space.h"
#include "safety.h"

namespace hapticut::servo {
namespace {

constexpr double kHandStep_s = 1e-4;  // The hand's physics runs at 10 kHz.
constexpr double kStartHeight_mm = 10.0;
constexpr double kPressDepth_mm = -15.0;  // Where the hand aims below the bone's surface (z = 0).
constexpr double kPressSpeed_mm_per_s = 60.0;

constexpr double kBladeHalfLength_mm = 20.0;

// A block of bone under z = 0: every tet rigid.
std::shared_ptr<const Space> bone_block(const StabilityCase& c) {
  const MeshData block = grid_mesh({-30.0, 0.0, 30.0}, {-30.0, 0.0, 30.0}, {-30.0, 0.0});
  EngineSettings settings;
  settings.stiffness_N_per_mm = point_stiffness_N_per_mm(c);
  settings.servo_rate_Hz = c.servo_rate_Hz;
  Material bone{"bone", MaterialModel::Rigid};
  return Space::create(
      TetMesh(block.vertices_mm, block.tets, std::vector<std::int32_t>(block.tets.size(), 0)),
      {bone}, settings);
}

// The hand aims down at a steady speed, then holds below the surface.
Vec3 hand_target(double t_s) {
  return {0.0, 0.0, std::max(kPressDepth_mm, kStartHeight_mm - kPressSpeed_mm_per_s * t_s)};
}

}  // namespace

double point_stiffness_N_per_mm(const StabilityCase& c) {
  if (c.points < 1) throw std::invalid_argument("a blade has at least 1 point");
  return c.coupling == BladeCoupling::Rigid ? c.stiffness_N_per_mm / c.points
                                            : c.stiffness_N_per_mm;
}

StabilityResult run_stability_case(const StabilityCase& c) {
  const auto space = bone_block(c);
  BladeSpec spec{
      "bench", {-kBladeHalfLength_mm, 0.0, 0.0}, {kBladeHalfLength_mm, 0.0, 0.0}, c.points};
  if (c.points == 1) spec.end_mm = spec.start_mm = {};
  spec.coupling = c.coupling;
  Blade blade(space, spec);
  const Vec3 start{0.0, 0.0, kStartHeight_mm};
  blade.reset({start, {}});
  VirtualHand hand;
  hand.reset(start);

  const int substeps_per_tick =
      std::max(1, static_cast<int>(std::lround(1.0 / (c.servo_rate_Hz * kHandStep_s))));
  const double tick_s = substeps_per_tick * kHandStep_s;
  const int delay_substeps = static_cast<int>(std::lround(c.link_delay_s / kHandStep_s));
  const int total_substeps = static_cast<int>(std::lround(c.duration_s / kHandStep_s));

  PassivitySettings passivity_settings;
  passivity_settings.enabled = c.passivity;
  passivity_settings.link_delay_ticks = c.link_delay_s / tick_s;
  HannafordRyuPassivity passivity(passivity_settings);

  std::vector<Vec3> history(static_cast<std::size_t>(total_substeps) + 1, start);
  StabilityResult result;
  Vec3 rendered_N;
  Vec3 last_seen = start;
  double energy_mJ = 0.0;
  double late_min_z = 1e300;
  double late_max_z = -1e300;
  for (int i = 0; i < total_substeps; ++i) {
    if (i % substeps_per_tick == 0) {
      // The servo sees the hand as it was a link delay ago.
      const Vec3 seen = history[static_cast<std::size_t>(std::max(0, i - delay_substeps))];
      const Vec3 force_N = blade.step({seen, {}}, tick_s).force_N;
      const Vec3 velocity = (seen - last_seen) / tick_s;
      last_seen = seen;
      rendered_N = passivity.observe(force_N, velocity, tick_s);
      result.peak_force_N = std::max(result.peak_force_N, norm(rendered_N));
    }
    const Vec3 before = hand.position_mm();
    hand.step(hand_target(i * kHandStep_s), rendered_N, kHandStep_s);
    // The force is held over the step: its work is f . dx exactly.
    energy_mJ += dot(rendered_N, hand.position_mm() - before);
    result.max_energy_to_hand_mJ = std::max(result.max_energy_to_hand_mJ, energy_mJ);
    history[static_cast<std::size_t>(i) + 1] = hand.position_mm();
    if (i >= total_substeps / 2) {
      late_min_z = std::min(late_min_z, hand.position_mm().z);
      late_max_z = std::max(late_max_z, hand.position_mm().z);
    }
  }
  result.final_energy_to_hand_mJ = energy_mJ;
  result.late_swing_mm = late_max_z - late_min_z;
  result.passivity_active_ticks = passivity.active_ticks();
  return result;
}

namespace {

StabilityRow make_row(const DeviceLimits& device, double rate_Hz, double delay_s, double k) {
  StabilityRow row;
  row.servo_rate_Hz = rate_Hz;
  row.link_delay_s = delay_s;
  row.stiffness_N_per_mm = k;
  row.limit_N_per_mm = stiffness_limit(device, rate_Hz);
  // Above the limit: the servo would not step with it (stiffness_in_force lowers it).
  row.above_limit = stiffness_in_force(k, row.limit_N_per_mm) < k;
  return row;
}

}  // namespace

std::vector<double> quarter_half_all(double limit_N_per_mm) {
  return {limit_N_per_mm / 4, limit_N_per_mm / 2, limit_N_per_mm};
}

std::vector<StabilityRow> servo_limit_grid(const DeviceLimits& device,
                                           const std::vector<double>& rates_Hz,
                                           const std::vector<double>& delays_s) {
  if (!(device.max_stiffness_N_per_mm > 0.0)) {
    throw std::invalid_argument("the device states no max_stiffness_N_per_mm");
  }
  std::vector<StabilityRow> rows;
  for (double rate : rates_Hz) {
    const double limit = stiffness_limit(device, rate);
    for (double delay : delays_s) {
      for (double k : quarter_half_all(limit)) rows.push_back(make_row(device, rate, delay, k));
    }
  }
  return rows;
}

std::vector<StabilityRow> absolute_grid(const DeviceLimits& device,
                                        const std::vector<double>& rates_Hz,
                                        const std::vector<double>& delays_s,
                                        const std::vector<double>& stiffnesses_N_per_mm) {
  std::vector<StabilityRow> rows;
  for (double rate : rates_Hz) {
    for (double delay : delays_s) {
      for (double k : stiffnesses_N_per_mm) rows.push_back(make_row(device, rate, delay, k));
    }
  }
  return rows;
}

StabilityCase stability_case(const StabilityRow& row, bool passivity, const StabilityBlade& blade) {
  StabilityCase c;
  c.points = blade.points;
  c.coupling = blade.coupling;
  c.servo_rate_Hz = row.servo_rate_Hz;
  c.link_delay_s = row.link_delay_s;
  c.stiffness_N_per_mm = row.stiffness_N_per_mm;
  c.passivity = passivity;
  return c;
}

void run_stability_rows(std::vector<StabilityRow>& rows, const StabilityBlade& blade) {
  for (StabilityRow& row : rows) {
    row.without = run_stability_case(stability_case(row, false, blade));
    row.with = run_stability_case(stability_case(row, true, blade));
  }
}

int rows_giving_energy(const std::vector<StabilityRow>& rows, bool passivity) {
  return static_cast<int>(std::count_if(rows.begin(), rows.end(), [&](const StabilityRow& row) {
    return (passivity ? row.with : row.without).max_energy_to_hand_mJ > 0.0;
  }));
}

std::string stability_table(const std::string& title, const std::vector<StabilityRow>& rows,
                            bool mark_limit) {
  std::ostringstream out;
  out << title << "\n\n";
  out << "| rate Hz | delay ms | k N/mm | without: energy mJ | swing mm | with: energy mJ | swing "
         "mm | damped ticks |"
      << (mark_limit ? " above the servo's limit at this rate |" : "") << "\n";
  out << "|--------:|---------:|-------:|-------------------:|---------:|----------------:|------"
         "---:|-------------:|"
      << (mark_limit ? ":-------------------------------------:|" : "") << "\n";
  for (const StabilityRow& row : rows) {
    char line[256];
    std::snprintf(line, sizeof line,
                  "| %7.0f | %8.1f | %6.3f | %18.4f | %8.3f | %15.4f | %8.3f | %12llu |",
                  row.servo_rate_Hz, row.link_delay_s * 1e3, row.stiffness_N_per_mm,
                  row.without.max_energy_to_hand_mJ, row.without.late_swing_mm,
                  row.with.max_energy_to_hand_mJ, row.with.late_swing_mm,
                  static_cast<unsigned long long>(row.with.passivity_active_ticks));
    out << line;
    if (mark_limit) {
      std::snprintf(line, sizeof line, " %37s |", row.above_limit ? "yes" : "no");
      out << line;
    }
    out << "\n";
  }
  const int cases = static_cast<int>(rows.size());
  out << "\nGives the hand energy: " << rows_giving_energy(rows, false) << " of " << cases
      << " cases without the controller, " << rows_giving_energy(rows, true) << " of " << cases
      << " with it.\n";
  if (mark_limit) {
    std::vector<StabilityRow> within;
    std::copy_if(rows.begin(), rows.end(), std::back_inserter(within),
                 [](const StabilityRow& row) { return !row.above_limit; });
    const int inside = static_cast<int>(within.size());
    out << "Within the servo's limit at their rate (" << inside << " of " << cases
        << " cases), gives the hand energy: " << rows_giving_energy(within, false) << " of "
        << inside << " without the controller, " << rows_giving_energy(within, true) << " of "
        << inside << " with it.\n";
  }
  return out.str();
}

}  // namespace hapticut::servo
