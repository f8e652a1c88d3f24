// RigidEdge (rigid_edge.h): the verified pose, the walks of a motion and the
// rounds of a tick.
//
// One tick (Blade::step_rigid gives the targets and walls first):
//  1. The edge nearest the targets (fit_edge) is the first trial.
//  2. The motion from the verified pose to the trial is verified: in pieces
//     (swept_pieces), every sample walks its chord (probe_segment) and every
//     stretch between neighbours sweeps its patch against the rigid surface's
//     edges (rigid_edge_sweep.cpp); then the stretches are walked at the trial.
//     All free: the trial becomes the verified pose. Else the planes met join
//     the contact set (two samples per plane, edge_contact_set.h), the pose
//     advances as far as the earliest contact (a verified pose, or none), and
//     the fit with the contacts (fit_edge_constrained) from there is the next
//     trial.
//  3. After kMaxRounds rounds the tick ends on the last verified pose.
//  4. Friction (rigid_edge_friction.cpp) keeps the tick's first pose inside
//     the cone or shortens the slide.
#include "hapticut/rigid_edge.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hapticut {

namespace {

// A pose's advance below this fraction is no advance.
constexpr double kLeastAdvance = 1e-9;
// The swept test cuts a turn into pieces whose chords every sample's arc
// leaves by at most this fraction of the edge's length.
constexpr double kSweptDeviation = 1e-4;
// Linearised fits per round at most (free orientation).
constexpr int kFitPasses = 4;
// The farthest a fit keeps a contact beyond its plane for the motion's bow
// (bowed_contacts), far below what a hand feels as a gap; a round's turn is cut
// to one that bows no more (limit_turn).
constexpr double kMostBow = 0.01;
// How far off the ridge it met a warm contact's sample may lie and the ridge
// still hold it (over_feature): a sample beyond it rests on a face beside the
// ridge, and a ridge held farther keeps a sliding blade above a round bone.
constexpr double kRidgeReach = 0.001;

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

RigidEdge::RigidEdge(std::shared_ptr<const Space> space, std::span<const double> fractions,
                     double length_mm)
    : space_(std::move(space)),
      fractions_(fractions.begin(), fractions.end()),
      length_mm_(length_mm) {
  const std::size_t n = fractions_.size();
  ideal_points_.assign(n, Vec3{});
  ideal_tets_.assign(n, kNoTet);
  trial_points_.assign(n, Vec3{});
  trial_tets_.assign(n, kNoTet);
  targets_.assign(n, Vec3{});
  walls_.assign(n, ProbeWalls::Rigid);
  start_points_.assign(n, Vec3{});
  start_tets_.assign(n, kNoTet);
  held_points_.assign(n, Vec3{});
  held_tets_.assign(n, kNoTet);
  if (n > 1) {
    rigid_edges_ = std::make_unique<const RigidSurfaceEdges>(*space_);
    swept_candidates_.reserve(rigid_edges_->size());
    active_candidates_.reserve(rigid_edges_->size());
    stretch_candidates_.reserve(rigid_edges_->size());
  }
}

void RigidEdge::set_walls(std::size_t i, const ProxyPlace& place, const Vec3& device_point) {
  walls_[i] = membrane_walls(place, device_point, ideal_tets_[i]);
}

ProbeWalls RigidEdge::membrane_walls(const ProxyPlace& place, const Vec3& device_point,
                                     std::int32_t& start_tet) const {
  const Space& space = *space_;
  const CutState* cuts = cuts_;
  const auto is_membrane = [&space, cuts](std::int32_t t) {
    return t != kNoTet && space.tet_model(t, cuts) == MaterialModel::Membrane;
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

bool RigidEdge::seat(const EdgePose& edge) {
  const Space& space = *space_;
  const std::size_t n = fractions_.size();
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
  contacts_.clear();  // A new start rests on nothing yet.
  return true;
}

// The tool pose of the ideal edge: the device's rotation turned (the least
// turn) from the device's edge direction onto the ideal one, so the roll
// about the edge is the device's; the origin where that rotation puts the
// edge's start on the ideal one.

void RigidEdge::begin_tick() {
  start_edge_ = ideal_edge_;
  std::copy(ideal_points_.begin(), ideal_points_.end(), start_points_.begin());
  std::copy(ideal_tets_.begin(), ideal_tets_.end(), start_tets_.begin());
}

void RigidEdge::restart_tick() {
  ideal_edge_ = start_edge_;
  std::copy(start_points_.begin(), start_points_.end(), ideal_points_.begin());
  std::copy(start_tets_.begin(), start_tets_.end(), ideal_tets_.begin());
}

void RigidEdge::add_contact(double fraction, const Plane& plane, std::int32_t wall_tet,
                            const ContactFeature& feature) {
  if (wall_tet != kNoTet) {
    const Material& material = space_->material_of_tet(wall_tet, cuts_);
    contact_static_friction_ = std::max(contact_static_friction_, material.static_friction);
    contact_dynamic_friction_ = std::max(contact_dynamic_friction_, material.dynamic_friction);
  }
  // Planes a tolerance apart are one: coplanar faces of a tet mesh differ by
  // rounding. A plane the full set cannot keep: the walks still refuse every
  // pose that enters the material; the fit only lacks it.
  contacts_.add(fraction, plane, space_->tolerance(), feature);
}

std::span<const EdgeContact> RigidEdge::bowed_contacts(std::span<const EdgeContact> contacts,
                                                       const Vec3& direction) {
  std::size_t count = 0;
  for (const EdgeContact& c : contacts) {
    EdgeContact& bowed = bowed_contacts_[count++];
    bowed = c;
    bowed.plane.offset +=
        std::min(interpolation_bow_mm(ideal_edge_.direction, direction, c.fraction, motion_pivot_,
                                      length_mm_, c.plane.normal),
                 kMostBow);
  }
  return {bowed_contacts_.data(), count};
}

bool RigidEdge::probe_motion(const EdgePose& edge, double& advance, bool add_contacts) {
  const Space& space = *space_;
  const std::size_t n = fractions_.size();
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
      const SegmentProbe probe = probe_segment(space, a_tet, a, trial_points_[i], walls_[i], cuts_);
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
        probe_segment(space, trial_tets_[i], trial_points_[i], trial_points_[i + 1], walls, cuts_);
    if (!ahead.hit) continue;
    free = false;
    if (!add_contacts) return false;
    const SegmentProbe back = probe_segment(space, trial_tets_[i + 1], trial_points_[i + 1],
                                            trial_points_[i], walls, cuts_);
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

void RigidEdge::accept_trial(const EdgePose& edge) {
  ideal_edge_ = edge;
  ideal_points_.swap(trial_points_);
  ideal_tets_.swap(trial_tets_);
}

void RigidEdge::advance_verified(const EdgePose& trial, double advance) {
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

bool RigidEdge::over_feature(const ContactFeature& feature, const Plane& plane,
                             const Vec3& x) const {
  const TetMesh& mesh = space_->mesh();
  const Vec3 foot = x - plane.normal * plane.signed_distance(x);
  if (feature.kind == ContactFeature::Kind::Edge) {
    const std::array<std::int32_t, 2>& ends = mesh.edge_vertices(feature.index);
    const Vec3 a = mesh.vertex(ends[0]);
    const Vec3 ab = mesh.vertex(ends[1]) - a;
    // A ridge holds the edge only on it: off it, along the plane through it,
    // the edge lies over one of the faces beside it, whose own plane is lower.
    const double length_sq = squared_norm(ab);
    const double t = dot(foot - a, ab);
    if (!(t >= 0.0 && t <= length_sq) || !(length_sq > 0.0)) return false;
    return norm(foot - (a + ab * (t / length_sq))) <= kRidgeReach;
  }
  if (feature.kind != ContactFeature::Kind::Face) return false;
  // The face's corners: the owner tet's vertices other than the face's own.
  std::array<Vec3, 3> corner;
  int k = 0;
  for (int v = 0; v < 4; ++v) {
    if (v != feature.face) corner[k++] = mesh.vertex(mesh.tet(feature.index)[v]);
  }
  // Over the face: on the inner side of each of its edges (the sides' signs
  // agree with the face's own orientation).
  const Vec3 normal = cross(corner[1] - corner[0], corner[2] - corner[0]);
  for (int e = 0; e < 3; ++e) {
    const Vec3& a = corner[e];
    const Vec3& b = corner[(e + 1) % 3];
    if (dot(cross(b - a, foot - a), normal) < 0.0) return false;
  }
  return true;
}

bool RigidEdge::rigid_wall(const ContactFeature& feature) const {
  if (feature.kind != ContactFeature::Kind::Face) return true;
  const std::int32_t wall = space_->mesh().neighbour(feature.index, feature.face);
  return wall != kNoTet && space_->tet_is_rigid(wall);
}

void RigidEdge::keep_warm_contacts() {
  // The last tick's planes where a sample of the verified pose still touches
  // one and lies over the face or ridge it met there: the pose rests on them
  // still, and the first fit can hold them instead of the walks finding them
  // again. One that no longer lies over what it met (slid off a facet) is
  // left to the walks.
  const double touching = touching_distance();
  int count = 0;
  for (const EdgeContactSet::HeldPlane& held : contacts_.planes()) {
    held.for_each_end([&](double fraction, const ContactFeature& feature) {
      const Vec3 x = ideal_edge_.point(fraction, length_mm_);
      if (held.plane.signed_distance(x) <= touching && over_feature(feature, held.plane, x) &&
          rigid_wall(feature)) {
        warm_[count++] = {fraction, held.plane, feature};
      }
    });
  }
  contacts_.clear();
  if (count == 0) {
    contact_static_friction_ = 0.0;
    contact_dynamic_friction_ = 0.0;
  }
  for (int j = 0; j < count; ++j) {
    contacts_.add(warm_[j].fraction, warm_[j].plane, space_->tolerance(), warm_[j].feature);
  }
}

bool RigidEdge::warm_contacts_hold(const EdgePose& trial) const {
  // A plane holds a sample only over the face or ridge it came from: one that
  // holds the trial's sample past it (slid off a facet of a round bone onto
  // the next, lower one) keeps the edge off that facet, above the optimum.
  const double held = kMostBow + 8.0 * space_->tolerance();
  bool holds = true;
  for (const EdgeContactSet::HeldPlane& plane : contacts_.planes()) {
    plane.for_each_end([&](double fraction, const ContactFeature& feature) {
      const Vec3 x = trial.point(fraction, length_mm_);
      holds = holds &&
              !(plane.plane.signed_distance(x) <= held && !over_feature(feature, plane.plane, x));
    });
  }
  return holds;
}

void RigidEdge::start_cold() {
  contacts_.clear();
  contact_static_friction_ = 0.0;
  contact_dynamic_friction_ = 0.0;
  // The first motion moves the middle straight: a turn that swings a
  // resting sample into its plane is found by the walks.
  motion_pivot_ = 0.5;
}

bool RigidEdge::fit_with_contacts(bool lock, const Vec3& lock_direction, double margin,
                                  EdgePose& trial, bool& cut) {
  cut = false;
  const std::span<const double> fractions(fractions_);
  const std::span<const Vec3> targets(targets_);
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
    const std::span<const EdgeContact> kept = bowed_contacts(contacts, base.direction);
    if (fit_edge_constrained(base, fractions, targets, length_mm_, lock, kept, margin, trial) ==
        EdgeFitStatus::Infeasible) {
      return false;
    }
    const bool settled =
        squared_norm(trial.start_mm - base.start_mm) +
            squared_norm(trial.direction - base.direction) * length_mm_ * length_mm_ <=
        margin * margin;
    base = trial;
    if (settled) break;
  }
  cut = limit_turn(contacts, margin, trial);
  return true;
}

bool RigidEdge::limit_turn(std::span<const EdgeContact> contacts, double margin, EdgePose& trial) {
  double most = 0.0;
  for (const EdgeContact& c : contacts) {
    most = std::max(most, interpolation_bow_mm(ideal_edge_.direction, trial.direction, c.fraction,
                                               motion_pivot_, length_mm_, c.plane.normal));
  }
  if (!(most > kMostBow)) return false;
  // The bow grows as the square of the directions' difference: half the
  // largest bow allowed leaves room for the mix's normalisation.
  const double share = std::sqrt(0.5 * kMostBow / most);
  const Vec3 mixed = ideal_edge_.direction + (trial.direction - ideal_edge_.direction) * share;
  const double size = norm(mixed);
  if (!(size > 1e-9)) return false;
  const EdgePose base{ideal_edge_.start_mm, mixed / size};
  EdgePose partial;
  if (fit_edge_constrained(base, std::span<const double>(fractions_),
                           std::span<const Vec3>(targets_), length_mm_, true,
                           bowed_contacts(contacts, base.direction), margin,
                           partial) == EdgeFitStatus::Infeasible) {
    return false;
  }
  trial = partial;
  return true;
}

bool RigidEdge::solve(bool lock, const Vec3& lock_direction, int& rounds) {
  const EdgePose cold = fit_edge(std::span<const double>(fractions_),
                                 std::span<const Vec3>(targets_), length_mm_, lock_direction, lock);
  EdgePose trial = cold;
  // The fit keeps contacts this far on their free side: a rounding error of
  // the pose then never reads as a step into the plane.
  const double margin = 4.0 * space_->tolerance();
  // Warm start: the first trial already holds the planes the pose rests on.
  // Where that trial does not verify whole, the tick starts again cold (the
  // planes kept may have ended beyond their faces): a warm start costs at
  // most one round.
  motion_pivot_ = 0.5;
  keep_warm_contacts();
  bool cut = false;
  bool warm =
      contacts_.plane_count() > 0 && fit_with_contacts(lock, lock_direction, margin, trial, cut);
  if (!warm) {
    trial = cold;
    start_cold();
  }
  rounds = 0;
  const int limit = kColdRounds + (warm ? 1 : 0);
  while (rounds < limit) {
    ++rounds;
    const int known = contacts_.changes();
    double advance = 1.0;
    const bool verified = probe_motion(trial, advance, true);
    if (verified && !(warm && !warm_contacts_hold(trial))) {
      accept_trial(trial);
      // A turn cut short goes on from there with the same contacts.
      if (!cut) return true;
      warm = false;
      if (!fit_with_contacts(lock, lock_direction, margin, trial, cut)) return false;
      continue;
    }
    if (warm) {
      warm = false;
      cut = false;
      trial = cold;
      start_cold();
      continue;
    }
    // As far as every walk got, verified; halved while the edge between the
    // points (or the arc the turn makes of a chord) still meets rigid material.
    advance_verified(trial, advance);
    if (contacts_.changes() == known && advance <= kLeastAdvance) break;  // Nothing new to fit.
    if (!fit_with_contacts(lock, lock_direction, margin, trial, cut)) return false;
  }
  return false;
}

}  // namespace hapticut
