#include "devices/passivity.h"

#include <algorithm>
#include <cmath>

namespace hapticut::servo {

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
  if (!is_finite(force_N) || !is_finite(velocity_mm_per_s) || !(dt_s > 0.0) ||
      !std::isfinite(dt_s)) {
    return push(Vec3{});
  }
  if (!settings_.enabled) return push(force_N);

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

  // The controller: what would remain if the new force did its work too.
  const double remaining_mJ = observed_energy_mJ_ - in_flight_mJ - work_mJ(force_N, delay + 1);
  const double speed_squared = squared_norm(velocity_next);
  if (remaining_mJ >= 0.0 || speed_squared * dt_s <= 1e-12) return push(force_N);

  // The damping never brakes beyond cancelling the force's own push along
  // the motion (f' . v >= 0 stays): behind a late link a stronger, delayed
  // damper is itself active. A deficit it cannot cover is carried.
  const double push_along_motion = std::max(0.0, dot(force_N, velocity_next)) / speed_squared;
  const double alpha = std::min({-remaining_mJ / (speed_squared * dt_s), push_along_motion,
                                 settings_.max_damping_N_s_per_mm});
  if (alpha <= 0.0) return push(force_N);
  last_damping_ = alpha;
  ++active_ticks_;
  return push(force_N - velocity_next * alpha);
}

}  // namespace hapticut::servo
