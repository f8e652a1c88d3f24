#include "passivity.h"

#include <algorithm>
#include <cmath>

namespace hapticut::servo {
namespace {

// The lag compensation acts once the energy left after the forces in flight
// and the new one falls below the work the force would do at the hand's
// speed over this many loop latencies (delay + one tick).
constexpr double kMarginLatencies = 4.0;
// Its damping: the environment's stiffness times the loop's lag, from the
// middle of the velocity's interval to the end of the new force's hold,
// delay + 1.5 ticks, rounded up to delay + 2 for the velocity's own lag.
constexpr double kLagTicksBeyondDelay = 2.0;
// Below this squared displacement (mm^2) a tick says nothing about stiffness.
constexpr double kMinStiffnessDisplacement_mm2 = 1e-12;

}  // namespace

HannafordRyuPassivity::HannafordRyuPassivity(const PassivitySettings& settings)
    : settings_(settings) {
  const double delay = settings_.link_delay_ticks;
  settings_.link_delay_ticks =
      std::isfinite(delay) ? std::clamp(delay, 0.0, kMaxLinkDelayTicks) : 0.0;
}

void HannafordRyuPassivity::reset() {
  outputs_.fill(Vec3{});
  head_ = 0;
  filled_ = 0;
  observed_energy_mJ_ = 0.0;
  last_damping_ = 0.0;
  active_ticks_ = 0;
  last_velocity_ = Vec3{};
  has_velocity_ = false;
  last_asked_N_ = Vec3{};
  stiffness_N_per_mm_ = 0.0;
}

Vec3 HannafordRyuPassivity::observe(const Vec3& force_N, const Vec3& velocity_mm_per_s,
                                    double dt_s) {
  const int size = static_cast<int>(outputs_.size());
  // outputs_ ago k: the force rendered k + 1 ticks before this one.
  const auto ago = [&](int k) {
    return k < filled_ ? outputs_[(head_ - k + size) % size] : Vec3{};
  };
  const auto push = [&](const Vec3& output) {
    head_ = (head_ + 1) % size;
    outputs_[head_] = output;
    filled_ = std::min(filled_ + 1, size);
    return output;
  };
  last_damping_ = 0.0;
  const auto render = [&](const Vec3& output) {
    if (!(output == force_N)) ++active_ticks_;
    return push(output);
  };
  if (!is_finite(force_N) || !is_finite(velocity_mm_per_s) || !(dt_s > 0.0) ||
      !std::isfinite(dt_s)) {
    return push(Vec3{});
  }
  if (!settings_.enabled) return push(force_N);  // Nothing changed, nothing counted.

  // The interval just measured began delay + 1 ticks ago at the hand: it
  // was rendered with the force sent ceil(delay) ticks before the last one,
  // and for a fraction with the one after (delay need not be whole ticks).
  const double delay = settings_.link_delay_ticks;
  const int whole = static_cast<int>(std::ceil(delay));
  const double fraction_of_later = whole - delay;  // In [0, 1).
  const Vec3 observed_force = ago(whole) * (1.0 - fraction_of_later) +
                              (whole > 0 ? ago(whole - 1) * fraction_of_later : Vec3{});
  observed_energy_mJ_ -= dot(observed_force, velocity_mm_per_s) * dt_s;

  // Forces sent since, not yet seen at work, and the new one: their work
  // predicted at the velocity extrapolated to when each acts (force ago(k)
  // acts delay - k ticks after the interval just measured).
  const Vec3 acceleration = has_velocity_ ? (velocity_mm_per_s - last_velocity_) / dt_s : Vec3{};
  last_velocity_ = velocity_mm_per_s;
  has_velocity_ = true;
  const auto predicted = [&](double ticks_later) {
    return velocity_mm_per_s + acceleration * (dt_s * ticks_later);
  };
  // Pessimistic: the larger of the work at the extrapolated and at the measured velocity.
  const auto work_mJ = [&](const Vec3& force, double ticks_later) {
    return std::max({dot(force, predicted(ticks_later)), dot(force, velocity_mm_per_s),
                     dot(force, predicted(2.0 * ticks_later))}) *
           dt_s;
  };
  double in_flight_mJ = 0.0;
  for (int k = 0; k < whole; ++k) {
    const double unseen = k == whole - 1 ? 1.0 - fraction_of_later : 1.0;
    in_flight_mJ += unseen * work_mJ(ago(k), delay - k);
  }
  const Vec3 velocity_next = predicted(delay + 1);

  // The environment's stiffness along the motion, from the asked force's
  // change over the displacement just seen: the engine computed both forces
  // from the poses the servo saw, so this ratio has no link delay in it.
  const Vec3 seen_displacement = velocity_mm_per_s * dt_s;
  const double seen_squared = squared_norm(seen_displacement);
  if (filled_ > 0 && seen_squared > kMinStiffnessDisplacement_mm2) {
    const double stiffness = -dot(force_N - last_asked_N_, seen_displacement) / seen_squared;
    if (stiffness > 0.0) stiffness_N_per_mm_ = stiffness;
  }
  last_asked_N_ = force_N;

  // Lag compensation: a spring rendered from a pose delay + 1 ticks old
  // pushes a hand on its way out harder than the spring at the hand's true
  // position would, by stiffness x lag x speed; that surplus is the energy
  // the late loop gives. When the energy left runs low, take it off as a
  // damping along the velocity the hand is heading to (one tick on).
  Vec3 force = force_N;
  const Vec3 heading = predicted(1.0);
  const double heading_squared = squared_norm(heading);
  const double along = dot(force_N, heading);
  if (along > 0.0 && heading_squared * dt_s > 1e-12 && stiffness_N_per_mm_ > 0.0) {
    const double left_mJ = observed_energy_mJ_ - in_flight_mJ - work_mJ(force_N, delay + 1);
    const double margin_mJ =
        kMarginLatencies * norm(force_N) * std::sqrt(heading_squared) * (delay + 1.0) * dt_s;
    if (left_mJ < margin_mJ) {
      const double alpha = std::min({stiffness_N_per_mm_ * (delay + kLagTicksBeyondDelay) * dt_s,
                                     along / heading_squared, settings_.max_damping_N_s_per_mm});
      force = force_N - heading * alpha;
      last_damping_ = alpha;
    }
  }

  // The controller: what would remain if the new force did its work too.
  const double remaining_mJ = observed_energy_mJ_ - in_flight_mJ - work_mJ(force, delay + 1);
  const double speed_squared = squared_norm(velocity_next);
  if (remaining_mJ >= 0.0 || speed_squared * dt_s <= 1e-12) return render(force);

  // The damping never brakes beyond cancelling the force's own push along
  // the motion (f' . v >= 0 stays): behind a late link a stronger, delayed
  // damper is itself active. A deficit it cannot cover is carried.
  const double push_along_motion = std::max(0.0, dot(force, velocity_next)) / speed_squared;
  // The cap bounds both stages together.
  const double alpha = std::min({-remaining_mJ / (speed_squared * dt_s), push_along_motion,
                                 settings_.max_damping_N_s_per_mm - last_damping_});
  if (alpha <= 0.0) return render(force);
  last_damping_ += alpha;
  return render(force - velocity_next * alpha);
}

std::unique_ptr<PassivityController> make_passivity_controller(double link_delay_s,
                                                               double rate_Hz) {
  PassivitySettings settings;
  settings.link_delay_ticks =
      std::clamp(link_delay_s * rate_Hz, 0.0, HannafordRyuPassivity::kMaxLinkDelayTicks);
  return std::make_unique<HannafordRyuPassivity>(settings);
}

}  // namespace hapticut::servo
