// RigidEdge: the rigid blade's solver (docs/decisions.md, "The rigid blade"),
// a six degree-of-freedom god-object (Ortega, Redon and Coquillart 2007) for a
// straight edge of n samples, with the tet walk as its collision detector.
// Split the way contact solvers are:
//  - the narrow phase: each sample walks its chord (segment_probe.h), each
//    stretch between neighbours sweeps its patch (swept_stretch.h);
//  - the contact set, reduced per plane (edge_contact_set.h), and the walls a
//    membrane makes for the samples it holds (membrane_walls);
//  - the edge fit (edge_fit.h) and its least-distance solve (least_distance.h);
//  - this class: the verified pose, the rounds of walk and fit between them
//    (solve), and friction at the contacts (apply_friction).
// The Blade owns one: it gives each tick's targets and walls, and turns the
// pose into the points' places and forces. Never allocates after construction.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "hapticut/edge_contact_set.h"
#include "hapticut/edge_fit.h"
#include "hapticut/force_shading.h"
#include "hapticut/proxy_place.h"
#include "hapticut/segment_probe.h"
#include "hapticut/space.h"
#include "hapticut/swept_stretch.h"

namespace hapticut {

class RigidEdge {
 public:
  // Rounds of a tick (walk, fit, walk again) from its unconstrained fit, a
  // round more for a warm start's trial (solve), and the halvings of one
  // conservative advance: bounded work.
  static constexpr int kColdRounds = 8;
  static constexpr int kMaxRounds = kColdRounds + 1;
  static constexpr int kMaxAdvanceHalvings = 4;

  // Samples at `fractions` (ascending, in [0, 1]) of an edge `length_mm` long.
  RigidEdge(std::shared_ptr<const Space> space, std::span<const double> fractions,
            double length_mm);

  // Makes `edge` the verified pose when no sample and no stretch between
  // neighbours lies in rigid material; false (nothing changed) otherwise.
  bool seat(const EdgePose& edge);
  // The springs' targets t_i of this tick, one per sample: the fits pull the
  // samples toward them.
  std::span<Vec3> targets() { return targets_; }
  // The walls of sample i's walks this tick: a membrane is one where the
  // point's own tick (at `place`, toward `device_point`) reached it and did not
  // break it (its spring, not its neighbours' pull, breaks it; once broken in,
  // it resists as a target). May start the sample's walks in the tet outside
  // the membrane it lies on.
  void set_walls(std::size_t i, const ProxyPlace& place, const Vec3& device_point);
  // The tets cut so far (cut_state.h; null: none): the walls and the
  // contacts' friction read the material a tet acts as through them.
  void set_cuts(const CutState* cuts) { cuts_ = cuts; }

  // Keeps the verified pose as the tick's first (friction and a restart go back to it).
  void begin_tick();
  // Goes back to the tick's first pose.
  void restart_tick();
  // From the verified pose toward the targets: rounds of walks and constrained
  // fits, the direction kept at lock_direction when `lock`; ends on a verified
  // pose. True when the last trial verified whole (resolved); `rounds` gets
  // the rounds used.
  bool solve(bool lock, const Vec3& lock_direction, int& rounds);
  // Friction at the contacts the solve met (docs/decisions.md, "Friction at
  // rigid contacts"): from the tick's first pose, rolled on its support (not
  // when `locked`), to the frictionless pose, the edge sticks while the
  // springs' pull along the contacts stays within the static coefficient
  // times their push, else slides as far as leaves the pull at the dynamic
  // coefficient times the push.
  void apply_friction(bool locked);
  // Force shading at the contacts (rigid_edge_shading.cpp; docs/decisions.md,
  // "The rigid blade"): the part of the springs' force `force_N` along the
  // touching contacts' normals takes their shaded normals, its size kept; the
  // torque about `origin` takes the change at the contacts' samples of the
  // device's edge `device`.
  void shade_force(const ForceShading& shading, const EdgePose& device, const Vec3& origin,
                   Vec3& force_N, Vec3& torque_N_mm) const;
  // Forgets a slide in progress (the static coefficient decides next).
  void clear_sliding() { sliding_ = false; }

  const EdgePose& edge() const { return ideal_edge_; }
  // The fraction of the edge whose sample the last motion probed moved
  // straight (interpolate_edge's pivot).
  double motion_pivot() const { return motion_pivot_; }
  double length_mm() const { return length_mm_; }
  // The samples on the verified pose, and the tets holding them (kNoTet
  // outside the mesh; never a rigid tet).
  std::span<const Vec3> points() const { return ideal_points_; }
  std::span<const std::int32_t> tets() const { return ideal_tets_; }
  // The contacts of the last solve, reduced per plane.
  std::span<const EdgeContact> contacts() { return contacts_.constraints(); }

 private:
  // Walks every sample from the verified pose to `edge` and then the
  // stretches between neighbours there; true when nothing met rigid material.
  // `advance` gets the least fraction any sample got; contacts found are
  // added when asked.
  bool probe_motion(const EdgePose& edge, double& advance, bool add_contacts);
  // The swept test of every stretch between neighbours over one piece of the
  // motion, from pose `first` to `last` (at from..to of the whole motion;
  // swept_stretch.h): true when no rigid surface edge crosses any; else
  // `advance` gets the earliest crossing and contacts are added when asked.
  bool sweep_stretches(const EdgePose& first, const EdgePose& last, double from, double to,
                       double& advance, bool add_contacts);
  // The same with each stretch's own query of the rigid edges (where the
  // broad phase would gather too many).
  bool sweep_stretches_each(const EdgePose& first, const EdgePose& last, double from, double to,
                            double& advance, bool add_contacts);
  // A stretch's hit (between fractions f0 and f1): the earliest sets the
  // advance and the sample met first; a contact when asked.
  void take_swept_hit(const SweptHit& hit, double f0, double f1, double& advance,
                      bool add_contacts);
  ProbeWalls membrane_walls(const ProxyPlace& place, const Vec3& device_point,
                            std::int32_t& start_tet) const;
  // `wall_tet` is the tet whose material holds the edge there (its friction);
  // `feature` what the sample met (its force shading).
  void add_contact(double fraction, const Plane& plane, std::int32_t wall_tet,
                   const ContactFeature& feature);
  // How far from the verified edge a contact's sample may lie and still touch
  // it: the nearest one's distance and a margin.
  double touching_distance() const;
  // From the verified pose toward `trial`, as far as the walks got
  // (`advance`), halved while the motion still meets rigid material; verified.
  void advance_verified(const EdgePose& trial, double advance);
  // The contacts with each plane moved out by as far as the sample bows off its
  // chord on the motion from the verified pose to a pose of `direction`
  // (interpolate_edge): a trial that keeps them keeps the samples free of the
  // planes all along the motion, not only at its end. Valid until the next call.
  std::span<const EdgeContact> bowed_contacts(std::span<const EdgeContact> contacts,
                                              const Vec3& direction);
  // Whether x, moved onto `plane`, lies over the face or ridge `feature`
  // names (false for none).
  bool over_feature(const ContactFeature& feature, const Plane& plane, const Vec3& x) const;
  // Whether what a contact met is rigid material: a membrane's plane is not
  // kept from one tick to the next (its walls are the points' own each tick).
  bool rigid_wall(const ContactFeature& feature) const;
  // Starts the contact set with the last tick's contacts that still hold the
  // verified pose (their friction with them), and no others.
  void keep_warm_contacts();
  // Whether every warm contact the trial rests on still lies over the face or
  // ridge it came from (else the warm trial is not taken).
  bool warm_contacts_hold(const EdgePose& trial) const;
  // Starts the contact set empty, with no friction, the motion about the middle.
  void start_cold();
  // The constrained fit from the verified pose with the contacts met so far
  // (up to kFitPasses sequential fits when free), the motion's pivot the
  // contact the pose rests on; false when infeasible. `cut` says whether its
  // turn was cut short (limit_turn).
  bool fit_with_contacts(bool lock, const Vec3& lock_direction, double margin, EdgePose& trial,
                         bool& cut);
  // A trial (free or locked) whose motion would bow a contact's sample farther
  // than the fit keeps it off its plane (the walks would stop it at once on a plane
  // already held) is cut to part of its turn, fitted with that direction
  // locked; true when cut. The rest of the turn is left to later rounds.
  bool limit_turn(std::span<const EdgeContact> contacts, double margin, EdgePose& trial);
  // Makes the probed edge (trial_*) the verified one.
  void accept_trial(const EdgePose& edge);
  // Sum |x_i - t_i|^2 over the samples of the verified edge.
  double spring_energy() const;
  // The verified pose turned about the contacts it rests on, toward the
  // springs' least energy, as far as the walks allow: an edge rolls on its
  // support where friction holds the support still.
  void roll_on_support(bool locked);

  std::shared_ptr<const Space> space_;  // Shared ownership (space.h, "Who owns a Space").
  const CutState* cuts_ = nullptr;      // The Blade's, set_cuts.
  std::vector<double> fractions_;
  double length_mm_ = 0.0;
  EdgePose ideal_edge_;
  // Storage sized once: the verified samples and the tets that hold them, a
  // trial pose's, the targets and the walls each sample's walks meet.
  std::vector<Vec3> ideal_points_;
  std::vector<std::int32_t> ideal_tets_;
  std::vector<Vec3> trial_points_;
  std::vector<std::int32_t> trial_tets_;
  std::vector<Vec3> targets_;
  std::vector<ProbeWalls> walls_;
  EdgeContactSet contacts_;
  std::array<EdgeContact, kMaxEdgeContacts> bowed_contacts_{};
  // The contacts kept from the last tick (keep_warm_contacts' storage).
  struct WarmContact {
    double fraction = 0.0;
    Plane plane;
    ContactFeature feature;
  };
  std::array<WarmContact, 2 * EdgeContactSet::kMaxPlanes> warm_{};
  // The sample of the edge a motion moves in a straight line (interpolate_edge):
  // the middle, or once there are contacts the one the pose rests on, so a
  // turn does not swing the held sample into its plane.
  double motion_pivot_ = 0.5;
  // The sample of the edge where the last probe_motion met rigid material
  // first (a sample, or a place between two).
  double earliest_hit_fraction_ = 0.5;
  // The largest friction coefficients of the materials met this tick, and
  // whether the edge slid on the last tick (then the dynamic one decides).
  double contact_static_friction_ = 0.0;
  double contact_dynamic_friction_ = 0.0;
  bool sliding_ = false;
  // The tick's first verified pose with its samples and tets, and the
  // frictionless pose's while a slide is verified.
  EdgePose start_edge_;
  std::vector<Vec3> start_points_;
  std::vector<std::int32_t> start_tets_;
  std::vector<Vec3> held_points_;
  std::vector<std::int32_t> held_tets_;
  // The rigid surface's edges, for the stretches' swept test (two samples or more).
  std::unique_ptr<const RigidSurfaceEdges> rigid_edges_;
  // The swept test's broad phase (sized to every rigid surface edge once):
  // the edges near a piece of the motion with the span along the edge where
  // each can meet a stretch, and those of one stretch.
  struct SweptCandidate {
    std::int32_t edge = 0;
    double least_mm = 0.0;
    double greatest_mm = 0.0;
  };
  std::vector<SweptCandidate> swept_candidates_;
  std::vector<SweptCandidate> active_candidates_;
  std::vector<std::int32_t> stretch_candidates_;
};

}  // namespace hapticut
