// RigidEdge's friction at rigid contacts (docs/decisions.md, "Friction at
// rigid contacts"): the friction cone of the god-object literature on the
// edge's pose; friction holds the support, not a turn about it.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "hapticut/rigid_edge.h"

namespace hapticut {

namespace {

// Contacts this far from the pose (a fraction of the edge's length, beyond
// the tolerance) support it: friction holds them, a turn about them is free.
constexpr double kSupportTouch = 1e-3;
// Supports tried per end of the contacts when turning about them.
constexpr int kSupportSearches = 3;

}  // namespace

double RigidEdge::spring_energy() const {
  double energy = 0.0;
  for (std::size_t i = 0; i < fractions_.size(); ++i) {
    energy += squared_norm(ideal_edge_.point(fractions_[i], length_mm_) - targets_[i]);
  }
  return energy;
}

double RigidEdge::touching_distance() const {
  // The nearest contact, with a margin: the fit leaves contacts a margin
  // away, the walks' advance a little more, and a sample may rest between two
  // of the contacts' samples.
  double nearest = std::numeric_limits<double>::infinity();
  for (const EdgeContactSet::HeldPlane& held : contacts_.planes()) {
    for (const double fraction : {held.least_fraction, held.greatest_fraction}) {
      nearest =
          std::min(nearest, held.plane.signed_distance(ideal_edge_.point(fraction, length_mm_)));
    }
  }
  return nearest + 8.0 * space_->tolerance() + kSupportTouch * length_mm_;
}

void RigidEdge::roll_on_support(bool locked) {
  if (locked || fractions_.size() < 2 || !(length_mm_ > 0.0)) {
    return;
  }
  // The support: the contacts touching the pose.
  const double touching = touching_distance();
  double least = std::numeric_limits<double>::infinity();
  double greatest = -least;
  for (const EdgeContact& c : contacts_.constraints()) {
    if (c.plane.signed_distance(ideal_edge_.point(c.fraction, length_mm_)) <= touching) {
      least = std::min(least, c.fraction);
      greatest = std::max(greatest, c.fraction);
    }
  }
  if (!(least <= greatest)) return;
  // Turned about either end of the support, the one the springs' torque
  // favours first; a turn into the material about the wrong end is refused by
  // the walks.
  const EdgePose start = ideal_edge_;
  const double start_energy = spring_energy();
  const auto energy_about = [&](double pivot) {
    ideal_edge_ = fit_edge_about(start, pivot, fractions_, targets_, length_mm_);
    const double energy = spring_energy();
    ideal_edge_ = start;
    return energy;
  };
  std::array<double, 2> pivots{least, greatest};
  const int candidates = greatest > least ? 2 : 1;
  if (candidates == 2 && energy_about(greatest) < energy_about(least)) {
    std::swap(pivots[0], pivots[1]);
  }
  const auto turned = [&] { return squared_norm(ideal_edge_.direction - start.direction) > 0.0; };
  const double motion_pivot = motion_pivot_;
  for (int c = 0; c < candidates && !turned(); ++c) {
    double pivot = pivots[c];
    // The contacts found are samples; where the edge rests between them the
    // turn meets the material at once, and that meeting is the support.
    for (int attempt = 0; attempt < kSupportSearches; ++attempt) {
      const EdgePose rolled = fit_edge_about(start, pivot, fractions_, targets_, length_mm_);
      ideal_edge_ = rolled;
      const bool lower = spring_energy() < start_energy;
      ideal_edge_ = start;
      if (!lower) break;
      motion_pivot_ = pivot;
      double advance = 1.0;
      if (probe_motion(rolled, advance, false)) {
        accept_trial(rolled);
        break;
      }
      const double met = earliest_hit_fraction_;
      advance_verified(rolled, advance);
      if (turned() || met == pivot) break;
      pivot = met;
    }
  }
  motion_pivot_ = motion_pivot;
}

void RigidEdge::apply_friction(bool locked) {
  const std::size_t n = fractions_.size();
  const bool sliding = sliding_;
  sliding_ = false;
  if (contacts_.plane_count() == 0 || !(contact_static_friction_ > 0.0)) return;
  // The springs' pull (over k) at the frictionless pose, where the contacts'
  // reaction balances it: its direction is their normal.
  Vec3 at_end;
  for (std::size_t i = 0; i < n; ++i) at_end += ideal_points_[i] - targets_[i];
  const double push_end = norm(at_end);
  if (!(push_end > space_->tolerance())) return;
  const Vec3 normal = at_end / push_end;
  const EdgePose frictionless = ideal_edge_;
  std::copy(ideal_points_.begin(), ideal_points_.end(), held_points_.begin());
  std::copy(ideal_tets_.begin(), ideal_tets_.end(), held_tets_.begin());
  const auto keep_frictionless = [&] {
    ideal_edge_ = frictionless;
    std::copy(held_points_.begin(), held_points_.end(), ideal_points_.begin());
    std::copy(held_tets_.begin(), held_tets_.end(), ideal_tets_.begin());
  };
  // The stuck pose: the tick's first, turned about its support as far as the
  // springs turn it (friction holds the support, not a turn about it).
  restart_tick();
  roll_on_support(locked);
  const EdgePose stuck = ideal_edge_;
  Vec3 at_stuck;
  for (std::size_t i = 0; i < n; ++i) at_stuck += ideal_points_[i] - targets_[i];
  // There the pull splits into a push along the normal and a pull across it.
  const double push = dot(at_stuck, normal);
  if (!(push > 0.0)) {  // Pulled off the contacts: no friction.
    keep_frictionless();
    return;
  }
  const double pull = norm(at_stuck - normal * push);
  const double mu_static = contact_static_friction_;
  const double mu_dynamic = std::min(contact_dynamic_friction_, mu_static);
  if (pull <= (sliding ? mu_dynamic : mu_static) * push) return;  // Stuck: inside the cone.
  sliding_ = true;
  // Along the way to the frictionless pose the pull along the contacts falls
  // as (1 - s) pull and the push moves linearly to push_end: the fraction s
  // where pull = mu_d push.
  const double denominator = pull + mu_dynamic * (push_end - push);
  const double s = denominator > 0.0 ? (pull - mu_dynamic * push) / denominator : 1.0;
  if (!(s < 1.0)) {
    keep_frictionless();
    return;
  }
  const EdgePose part =
      interpolate_edge(stuck, frictionless, std::max(s, 0.0), motion_pivot_, length_mm_);
  double ignored = 1.0;
  if (probe_motion(part, ignored, false)) {
    accept_trial(part);
    return;
  }
  // The slide's pose is not verified from the stuck one: the frictionless one is.
  keep_frictionless();
}

}  // namespace hapticut
