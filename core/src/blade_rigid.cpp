// The rigid coupling of a Blade (docs/decisions.md, "The rigid blade"): one
// ideal pose for the whole edge, a six degree-of-freedom god-object (Ortega,
// Redon and Coquillart 2007) with the tet walk as its collision detector.
//
// One tick:
//  1. The point proxies, placed on the last ideal pose, tick toward their
//     device points as in the paper: where a resisting material (drag,
//     viscous, membrane) holds one back, its q is the spring's target t_i;
//     elsewhere t_i is the device point. A membrane a point reached without
//     breaking it is a wall for that point's walks, as bone is.
//  2. The edge nearest the targets (fit_edge) is the first trial.
//  3. The motion from the ideal pose to the trial is verified: in pieces
//     (swept_pieces), every point walks its chord (probe_segment) and every
//     stretch between neighbours sweeps its patch against the rigid surface's
//     edges (swept_stretch.h); then the stretches are walked at the trial.
//     All free: the trial becomes the ideal pose. Else the planes met join
//     the contact set (two samples per plane, edge_contact_set.h), the pose
//     advances as far as the earliest contact (a verified pose, or none), and
//     the fit with the contacts (fit_edge_constrained) from there is the next
//     trial.
//  4. After kMaxRigidRounds rounds the tick ends on the last verified pose.
//  5. Friction (apply_friction) keeps the tick's first pose inside the cone
//     or shortens the slide.
// Force and torque are the sums of the point springs with q_i = x_i(ideal
// pose), shaded when the settings ask (shade_rigid_force, blade_shading.cpp).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "hapticut/blade.h"
#include "hapticut/segment_probe.h"

namespace hapticut {

namespace {

// A pose's advance below this fraction is no advance.
constexpr double kLeastAdvance = 1e-9;
// The swept test cuts a turn into pieces whose chords every sample's arc
// leaves by at most this fraction of the blade's length.
constexpr double kSweptDeviation = 1e-4;
// Linearised fits per round at most (free orientation).
constexpr int kFitPasses = 4;
// Contacts this far from the pose (a fraction of the blade's length, beyond
// the tolerance) support it: friction holds them, a turn about them is free.
constexpr double kSupportTouch = 1e-3;
// Rigid surface edges per stretch, at most, that the swept test's broad
// phase gathers for a piece of the motion.
constexpr std::size_t kBroadPhasePerStretch = 4;
// Supports tried per end of the contacts when turning about them.
constexpr int kSupportSearches = 3;

// The contact for a stretch a -> b of the edge that enters rigid material
// through plane `in` (at fraction s_in) and leaves it through plane `out` (at
// s_out), both with normals out of the material. Near their common line the
// material lies on the rigid side of both, so of every plane through that
// line whose normal combines theirs with weights >= 0: the one parallel to the
// edge's direction keeps the whole edge off it when the edge stays on its free
// side. Its sample is the stretch's deepest one, where both planes are equally
// far. False when no such combination exists (the edge along the line).
bool wedge_contact(const Plane& in, const Plane& out, const Vec3& direction, const Vec3& a,
                   const Vec3& b, double s_in, double s_out, EdgeContact& contact) {
  double w_in = dot(out.normal, direction);
  double w_out = -dot(in.normal, direction);
  if (w_in < 0.0 && w_out < 0.0) {
    w_in = -w_in;
    w_out = -w_out;
  }
  if (w_in < 0.0 || w_out < 0.0) return false;
  const Vec3 normal = in.normal * w_in + out.normal * w_out;
  const double size = norm(normal);
  if (!(size > 1e-9)) {
    // Parallel planes (entered and left through one plane): that plane.
    contact.plane = in;
  } else {
    contact.plane = {normal / size, (in.offset * w_in + out.offset * w_out) / size};
  }
  const double in_a = in.signed_distance(a);
  const double out_a = out.signed_distance(a);
  const double slope = (in.signed_distance(b) - in_a) - (out.signed_distance(b) - out_a);
  double s = 0.5 * (s_in + s_out);
  if (std::abs(slope) > 1e-12) s = (out_a - in_a) / slope;
  contact.fraction = std::clamp(s, std::min(s_in, s_out), std::max(s_in, s_out));
  return true;
}

}  // namespace

ProbeWalls Blade::membrane_walls(const ProxyPlace& place, const Vec3& device_point,
                                 std::int32_t& start_tet) const {
  const Space& space = *space_;
  const auto is_membrane = [&space](std::int32_t t) {
    return t != kNoTet && space.tet_model(t) == MaterialModel::Membrane;
  };
  const bool constrained = place.state == ProxyState::Face || place.state == ProxyState::Edge ||
                           place.state == ProxyState::Vertex;
  if (constrained) {
    // The point's tick ended on a wall outside every membrane: none let it in.
    return !is_membrane(place.tet) && !is_membrane(start_tet) ? ProbeWalls::RigidAndMembrane
                                                              : ProbeWalls::Rigid;
  }
  // Held still in a membrane tet from a point on its outer face (the point had
  // reached the membrane, not broken it): the walk starts in the tet outside.
  const double eps = space.tolerance();
  if (place.state != ProxyState::Tet || place.tet != start_tet || !is_membrane(start_tet) ||
      !(squared_norm(place.q - device_point) > eps * eps)) {
    return ProbeWalls::Rigid;
  }
  const TetMesh& mesh = space.mesh();
  for (int f = 0; f < 4; ++f) {
    const std::int32_t u = mesh.neighbour(start_tet, f);
    if (is_membrane(u) || (u != kNoTet && space.tet_is_rigid(u))) continue;
    if (std::abs(mesh.face_plane(start_tet, f).signed_distance(place.q)) <= eps) {
      start_tet = u;
      return ProbeWalls::RigidAndMembrane;
    }
  }
  return ProbeWalls::Rigid;
}

EdgePose Blade::device_edge() const {
  return {
      device_pose_.position_mm + world_lever_,
      length_mm_ > 0.0 ? world_span_ / length_mm_ : device_pose_.rotation.rotate(tool_direction_)};
}

void Blade::add_contact(double fraction, const Plane& plane, std::int32_t wall_tet,
                        const ContactFeature& feature) {
  if (wall_tet != kNoTet) {
    const Material& material = space_->material_of_tet(wall_tet);
    contact_static_friction_ = std::max(contact_static_friction_, material.static_friction);
    contact_dynamic_friction_ = std::max(contact_dynamic_friction_, material.dynamic_friction);
  }
  // Planes a tolerance apart are one: coplanar faces of a tet mesh differ by
  // rounding. A plane the full set cannot keep: the walks still refuse every
  // pose that enters the material; the fit only lacks it.
  contacts_.add(fraction, plane, space_->tolerance(), feature);
}

bool Blade::probe_motion(const EdgePose& edge, double& advance, bool add_contacts) {
  const Space& space = *space_;
  const std::size_t n = proxies_.size();
  advance = 1.0;
  // The motion: a turn is cut into pieces (swept_pieces) between poses on the
  // interpolation from the ideal edge; in each piece every point walks its
  // chord and every stretch between neighbours sweeps its patch. A point's
  // walk in one piece starts where its last one ended (trial_*).
  const double turn = std::acos(std::clamp(dot(ideal_edge_.direction, edge.direction), -1.0, 1.0));
  const int pieces = swept_pieces(turn, length_mm_, kSweptDeviation * length_mm_);
  for (int k = 0; k < pieces; ++k) {
    const double from = double(k) / pieces;
    const double to = double(k + 1) / pieces;
    const EdgePose first =
        k == 0 ? ideal_edge_ : interpolate_edge(ideal_edge_, edge, from, motion_pivot_, length_mm_);
    const EdgePose last =
        k + 1 == pieces ? edge : interpolate_edge(ideal_edge_, edge, to, motion_pivot_, length_mm_);
    bool free = true;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3 a = k == 0 ? ideal_points_[i] : trial_points_[i];
      const std::int32_t a_tet = k == 0 ? ideal_tets_[i] : trial_tets_[i];
      trial_points_[i] = last.point(fractions_[i], length_mm_);
      const SegmentProbe probe = probe_segment(space, a_tet, a, trial_points_[i], walls_[i]);
      if (probe.hit) {
        free = false;
        const double at = from + (to - from) * probe.fraction;
        if (at < advance) {
          advance = at;
          earliest_hit_fraction_ = fractions_[i];
        }
        if (add_contacts && !probe.exhausted) {
          ContactFeature met;
          if (probe.owner_tet != kNoTet) {
            met = {ContactFeature::Kind::Face, probe.owner_tet, probe.owner_face};
          }
          add_contact(fractions_[i], probe.contact, probe.wall_tet, met);
        }
      } else {
        trial_tets_[i] = probe.end_tet;
      }
    }
    if (!free) return false;
    if (!sweep_stretches(first, last, from, to, advance, add_contacts)) return false;
  }
  bool free = true;
  // Between neighbours: a stretch that passes through rigid material is
  // walked from both ends, giving the plane it enters by and the plane it
  // leaves by; the contact is the plane through their common line that runs
  // along the edge (wedge_contact), at the stretch's deepest sample.
  const Vec3 direction = edge.direction;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    // A membrane is a wall between two points it holds; where one of them has
    // broken it, the edge cuts on from there.
    const ProbeWalls walls =
        walls_[i] == ProbeWalls::RigidAndMembrane && walls_[i + 1] == ProbeWalls::RigidAndMembrane
            ? ProbeWalls::RigidAndMembrane
            : ProbeWalls::Rigid;
    const SegmentProbe ahead =
        probe_segment(space, trial_tets_[i], trial_points_[i], trial_points_[i + 1], walls);
    if (!ahead.hit) continue;
    free = false;
    if (!add_contacts) return false;
    const SegmentProbe back =
        probe_segment(space, trial_tets_[i + 1], trial_points_[i + 1], trial_points_[i], walls);
    if (ahead.exhausted || !back.hit || back.exhausted) continue;
    const double gap = fractions_[i + 1] - fractions_[i];
    EdgeContact contact;
    if (wedge_contact(ahead.contact, back.contact, direction, trial_points_[i],
                      trial_points_[i + 1], ahead.fraction, 1.0 - back.fraction, contact)) {
      contact.fraction = fractions_[i] + contact.fraction * gap;
      add_contact(contact.fraction, contact.plane, ahead.wall_tet, {});
    }
  }
  if (!free) advance = 0.0;  // The points got there; the edge between them did not.
  return free;
}

void Blade::take_swept_hit(const SweptHit& hit, double f0, double f1, double& advance,
                           bool add_contacts) {
  const double fraction = f0 + hit.along * (f1 - f0);
  if (hit.motion < advance) {
    advance = hit.motion;
    earliest_hit_fraction_ = fraction;
  }
  if (add_contacts) {
    add_contact(fraction, hit.contact, hit.wall_tet,
                {ContactFeature::Kind::Edge, hit.mesh_edge, 0});
  }
}

bool Blade::sweep_stretches_each(const EdgePose& first, const EdgePose& last, double from,
                                 double to, double& advance, bool add_contacts) {
  const std::size_t n = proxies_.size();
  const double tolerance = space_->tolerance();
  bool free = true;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const double f0 = fractions_[i];
    const double f1 = fractions_[i + 1];
    const SweptHit hit =
        sweep_stretch(*rigid_edges_, first.point(f0, length_mm_), first.point(f1, length_mm_),
                      last.point(f0, length_mm_), last.point(f1, length_mm_), from, to, tolerance);
    if (!hit.hit) continue;
    free = false;
    take_swept_hit(hit, f0, f1, advance, add_contacts);
  }
  return free;
}

bool Blade::sweep_stretches(const EdgePose& first, const EdgePose& last, double from, double to,
                            double& advance, bool add_contacts) {
  if (!rigid_edges_ || rigid_edges_->size() == 0) return true;
  const std::size_t n = proxies_.size();
  const double tolerance = space_->tolerance();
  // The broad phase, once for the whole edge: the rigid surface's edges near
  // its motion, each with the span along the first pose's edge where it can
  // meet a stretch. A sample's move is a mix of the ends' moves, so it moves
  // along the edge by at most the larger of them.
  const Vec3 a0 = first.start_mm;
  const Vec3 b0 = first.point(1.0, length_mm_);
  const Vec3 a1 = last.start_mm;
  const Vec3 b1 = last.point(1.0, length_mm_);
  const Aabb box = motion_box(a0, b0, a1, b1, tolerance);
  const double reach = std::max(norm(a1 - a0), norm(b1 - b0)) + tolerance;
  // Where the surface's edges are small beside the motion (a fine mesh, a long
  // step) the stretches' own queries find fewer: past a few per stretch the
  // broad phase gives way to them.
  const std::size_t most = kBroadPhasePerStretch * (n - 1);
  swept_candidates_.clear();
  const bool broad = rigid_edges_->tree().for_each_overlapping_while(box, [&](std::int32_t k) {
    if (swept_candidates_.size() == most) return false;
    const auto& segment = rigid_edges_->segment(k);
    const double t0 = dot(segment[0] - a0, first.direction);
    const double t1 = dot(segment[1] - a0, first.direction);
    swept_candidates_.push_back({k, std::min(t0, t1) - reach, std::max(t0, t1) + reach});
    return true;
  });
  if (!broad) return sweep_stretches_each(first, last, from, to, advance, add_contacts);
  if (swept_candidates_.empty()) return true;
  // Along the edge in order: a candidate joins when the stretches reach its
  // span and leaves once they have passed it.
  std::sort(swept_candidates_.begin(), swept_candidates_.end(),
            [](const SweptCandidate& a, const SweptCandidate& b) {
              return a.least_mm < b.least_mm || (a.least_mm == b.least_mm && a.edge < b.edge);
            });
  std::size_t next = 0;
  active_candidates_.clear();
  bool free = true;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const double f0 = fractions_[i];
    const double f1 = fractions_[i + 1];
    while (next < swept_candidates_.size() && swept_candidates_[next].least_mm <= f1 * length_mm_) {
      active_candidates_.push_back(swept_candidates_[next++]);
    }
    std::erase_if(active_candidates_,
                  [&](const SweptCandidate& c) { return c.greatest_mm < f0 * length_mm_; });
    if (active_candidates_.empty()) continue;
    stretch_candidates_.clear();
    for (const SweptCandidate& c : active_candidates_) stretch_candidates_.push_back(c.edge);
    const SweptHit hit =
        sweep_stretch_among(*rigid_edges_, stretch_candidates_, first.point(f0, length_mm_),
                            first.point(f1, length_mm_), last.point(f0, length_mm_),
                            last.point(f1, length_mm_), from, to, tolerance);
    if (!hit.hit) continue;
    free = false;
    take_swept_hit(hit, f0, f1, advance, add_contacts);
  }
  return free;
}

void Blade::accept_trial(const EdgePose& edge) {
  ideal_edge_ = edge;
  ideal_points_.swap(trial_points_);
  ideal_tets_.swap(trial_tets_);
}

void Blade::advance_verified(const EdgePose& trial, double advance) {
  double fraction = advance;
  for (int h = 0; h <= kMaxAdvanceHalvings && fraction > kLeastAdvance; ++h, fraction *= 0.5) {
    const EdgePose part = interpolate_edge(ideal_edge_, trial, fraction, motion_pivot_, length_mm_);
    double ignored = 1.0;
    if (probe_motion(part, ignored, false)) {
      accept_trial(part);
      return;
    }
  }
}

double Blade::spring_energy() const {
  double energy = 0.0;
  for (std::size_t i = 0; i < proxies_.size(); ++i) {
    energy += squared_norm(ideal_edge_.point(fractions_[i], length_mm_) - targets_[i]);
  }
  return energy;
}

double Blade::touching_distance() const {
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

void Blade::roll_on_support(bool locked) {
  if (locked || proxies_.size() < 2 || !(length_mm_ > 0.0)) {
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

void Blade::apply_friction(const EdgePose& start, bool locked) {
  const std::size_t n = proxies_.size();
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
  ideal_edge_ = start;
  std::copy(start_points_.begin(), start_points_.end(), ideal_points_.begin());
  std::copy(start_tets_.begin(), start_tets_.end(), ideal_tets_.begin());
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

bool Blade::seat_at(const EdgePose& edge) {
  const Space& space = *space_;
  const std::size_t n = proxies_.size();
  for (std::size_t i = 0; i < n; ++i) {
    trial_points_[i] = edge.point(fractions_[i], length_mm_);
    bool inside_rigid = false;
    trial_tets_[i] = locate_for_probe(space, trial_points_[i], inside_rigid);
    if (inside_rigid) return false;
  }
  for (std::size_t i = 0; i + 1 < n; ++i) {
    if (probe_segment(space, trial_tets_[i], trial_points_[i], trial_points_[i + 1]).hit) {
      return false;
    }
  }
  accept_trial(edge);
  return true;
}

// The tool pose of the ideal edge: the device's rotation turned (the least
// turn) from the device's edge direction onto the ideal one, so the roll
// about the edge is the device's; the origin where that rotation puts the
// edge's start on the ideal one.
void Blade::update_ideal_pose(const Pose& device) {
  const Vec3 device_direction = device.rotation.rotate(tool_direction_);
  const Quaternion turn = rotation_between(device_direction, ideal_edge_.direction);
  const Quaternion rotation =
      same_hemisphere(multiply(turn, device.rotation).normalized(), ideal_pose_.rotation);
  ideal_pose_ = {ideal_edge_.start_mm - rotation.rotate(tool_start_), rotation};
}

// Each proxy at its point of the ideal pose, in the tet that holds it (a TET
// state owned by a non-rigid tet, or OUTSIDE), with the point's force: the
// next tick's walks start there.
void Blade::place_proxies_on_ideal(const RuntimeSettings& settings) {
  const std::size_t n = proxies_.size();
  for (std::size_t i = 0; i < n; ++i) {
    Proxy& proxy = proxies_[i];
    const std::int32_t t = ideal_tets_[i];
    proxy.place_ = {t == kNoTet ? ProxyState::Outside : ProxyState::Tet, t, 0, ideal_points_[i]};
    point_forces_[i] = proxy.spring_force(world_points_[i], settings, nullptr);
    proxy.force_N_ = point_forces_[i];
  }
}

bool Blade::solve_pose(bool lock, const Vec3& lock_direction, int& rounds) {
  const std::span<const double> fractions(fractions_);
  const std::span<const Vec3> targets(targets_);
  EdgePose trial = fit_edge(fractions, targets, length_mm_, lock_direction, lock);
  contacts_.clear();
  motion_pivot_ = 0.5;
  contact_static_friction_ = 0.0;
  contact_dynamic_friction_ = 0.0;
  // The fit keeps contacts this far on their free side: a rounding error of
  // the pose then never reads as a step into the plane.
  const double margin = 4.0 * space_->tolerance();
  rounds = 0;
  while (rounds < kMaxRigidRounds) {
    ++rounds;
    const int known = contacts_.changes();
    double advance = 1.0;
    if (probe_motion(trial, advance, true)) {
      accept_trial(trial);
      return true;
    }
    // As far as every walk got, verified; halved while the edge between the
    // points (or the arc the turn makes of a chord) still meets rigid material.
    advance_verified(trial, advance);
    if (contacts_.changes() == known && advance <= kLeastAdvance) break;  // Nothing new to fit.
    // Sequential: each fit linearised about the last one's answer, so a
    // turn's second-order error (the edge keeps its length) is gone before
    // the walks judge it.
    EdgePose base = lock ? EdgePose{ideal_edge_.start_mm, lock_direction} : ideal_edge_;
    const std::span<const EdgeContact> contacts = contacts_.constraints();
    // The motion turns about the contact the pose is nearest to (the one it
    // rests on): that sample then moves straight off its plane.
    double nearest = std::numeric_limits<double>::infinity();
    for (const EdgeContact& c : contacts) {
      const double d = c.plane.signed_distance(ideal_edge_.point(c.fraction, length_mm_));
      if (d < nearest || (d == nearest && c.fraction < motion_pivot_)) {
        nearest = d;
        motion_pivot_ = c.fraction;
      }
    }
    for (int pass = 0; pass < (lock ? 1 : kFitPasses); ++pass) {
      if (fit_edge_constrained(base, fractions, targets, length_mm_, lock, contacts, margin,
                               trial) == EdgeFitStatus::Infeasible) {
        return false;
      }
      const bool settled =
          squared_norm(trial.start_mm - base.start_mm) +
              squared_norm(trial.direction - base.direction) * length_mm_ * length_mm_ <=
          margin * margin;
      base = trial;
      if (settled) break;
    }
  }
  return false;
}

BladeTick Blade::step_rigid(const Pose& pose, double dt_s, const RuntimeSettings& settings) {
  (void)pose;
  const std::size_t n = proxies_.size();
  const EdgePose device = device_edge();
  if (!seated_) {
    seated_ = seat_at(device);
    if (!seated_) {
      BladeTick tick;
      tick.unseated = true;
      ideal_pose_ = device_pose_;
      std::fill(point_forces_.begin(), point_forces_.end(), Vec3{});
      for (std::size_t i = 0; i < n; ++i) proxies_[i].force_N_ = Vec3{};
      count(tick);
      return tick;
    }
  }
  // 1. The targets: the paper's tick of every point from the ideal pose.
  // Where no material resists (free and rigid only), every target is the
  // device point and the walls are rigid: the points' ticks, which would
  // only walk round the bone the pose is held on, are not needed.
  if (!resisting_materials_) {
    std::copy(world_points_.begin(), world_points_.end(), targets_.begin());
    std::fill(point_ticks_.begin(), point_ticks_.end(), TickResult{});
  }
  BladeTick tick = resisting_materials_ ? step_points(dt_s, settings) : BladeTick{};
  for (std::size_t i = 0; resisting_materials_ && i < n; ++i) {
    const ProxyPlace& place = proxies_[i].place();
    const TickResult& r = point_ticks_[i];
    const bool held_by_material =
        (place.state == ProxyState::Tet || place.state == ProxyState::Outside) && !r.capped &&
        !r.deferred;
    targets_[i] = held_by_material ? place.q : world_points_[i];
    // A membrane the point reached and did not break is as hard as bone.
    walls_[i] = membrane_walls(place, world_points_[i], ideal_tets_[i]);
  }
  // 2-4. The pose.
  bool lock = orientation_ == BladeOrientation::Locked;
  const EdgePose start = ideal_edge_;
  std::copy(ideal_points_.begin(), ideal_points_.end(), start_points_.begin());
  std::copy(ideal_tets_.begin(), ideal_tets_.end(), start_tets_.begin());
  // The direction a locked edge keeps: the device's. While a switch of
  // orientation turns in, one moving from the edge's direction at the switch
  // to the new rule's (the device's, or where this tick's free solve turns
  // the edge), the pose solved about it as a locked one's.
  Vec3 lock_direction = device.direction;
  if (orientation_ramp_elapsed_s_ < orientation_ramp_s_) {
    orientation_ramp_elapsed_s_ += dt_s;
    const double s = std::min(1.0, orientation_ramp_elapsed_s_ / orientation_ramp_s_);
    Vec3 goal = device.direction;
    if (!lock) {
      int ignored = 0;
      solve_pose(false, device.direction, ignored);
      goal = ideal_edge_.direction;
      ideal_edge_ = start;
      std::copy(start_points_.begin(), start_points_.end(), ideal_points_.begin());
      std::copy(start_tets_.begin(), start_tets_.end(), ideal_tets_.begin());
    }
    const Vec3 mixed = ramp_from_direction_ + (goal - ramp_from_direction_) * s;
    const double size = norm(mixed);
    lock_direction = size > 1e-9 ? mixed / size : goal;
    lock = true;
  }
  int rounds = 0;
  const bool resolved = solve_pose(lock, lock_direction, rounds);
  apply_friction(start, lock);
  update_ideal_pose(device_pose_);
  place_proxies_on_ideal(settings);
  Vec3 force;
  Vec3 weighted_force;
  for (std::size_t i = 0; i < n; ++i) {
    force += point_forces_[i];
    weighted_force += point_forces_[i] * fractions_[i];
  }
  tick.force_N = force;
  tick.torque_N_mm = cross(world_lever_, force) + cross(world_span_, weighted_force);
  if (settings.force_shading) shade_rigid_force(tick.force_N, tick.torque_N_mm);
  tick.rigid_rounds = rounds;
  tick.contacts = static_cast<int>(contacts_.constraints().size());
  tick.unresolved = !resolved;
  count(tick);
  return tick;
}

}  // namespace hapticut
