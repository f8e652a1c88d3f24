// Blade: N points spread evenly on a segment in the tool frame, placed in the
// world by the tool's pose; one Proxy per point. Point i sits at fraction s_i
// of the segment, so in the world it is a + s_i b, a the placed start and b
// the rotated segment (docs/decisions.md, "A blade's points are placed as a + s_i b"). The device
// gets the summed force and the torque about the tool origin (beyond the paper).
//
// Per tick (docs/decisions.md): settings come with the tick (RuntimeSettings,
// space.h); the points share a work budget of transitions; force shading is
// applied when the settings ask; snapshot() copies the tick into caller
// storage. step() and snapshot() never allocate; the constructor and reset do.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "hapticut/edge_contact_set.h"
#include "hapticut/edge_fit.h"
#include "hapticut/force_shading.h"
#include "hapticut/pose.h"
#include "hapticut/proxy.h"
#include "hapticut/scene.h"
#include "hapticut/segment_probe.h"
#include "hapticut/swept_stretch.h"

namespace hapticut {

// Whether a pose can be used, and why not.
enum class PoseCheck : std::uint8_t { Fine, NotFinite, ZeroRotation, OutOfWorkspace };

struct BladeTick {
  // Sum of the points' forces k (q_i - p_i), shaded when asked: each point's
  // (independent), or at the contacts (rigid, shade_rigid_force).
  Vec3 force_N;
  // Sum of (p_i - origin) x f_i, as (a - origin) x F + b x (sum of s_i f_i).
  Vec3 torque_N_mm;
  // Points left unfinished when the work budget ran out: their proxies keep
  // their last valid place and force and catch up next tick.
  int capped_points = 0;
  int deferred_points = 0;  // Of those, the points that did not move at all.
  int max_transitions = 0;  // Most transitions of one point.
  int transitions = 0;      // All points together (<= the budget).
  // Input refused, nothing moved, force zero: pose or rotation not finite, a
  // rotation of (near) zero norm, a point outside the Space's workspace, or
  // settings out of range.
  bool rejected = false;
  // Rigid coupling only (docs/decisions.md, "The rigid blade"): the solve's
  // rounds (walk, fit, walk again; at most Blade::kMaxRigidRounds), the
  // contact planes it used, whether it ended short of the constrained optimum
  // (on its last verified pose), and whether the blade has no valid pose yet
  // (reset inside rigid material: zero force until the device leaves it).
  int rigid_rounds = 0;
  int contacts = 0;
  bool unresolved = false;
  bool unseated = false;
};

struct BladeCounters {
  std::uint64_t ticks = 0;
  std::uint64_t rejected_ticks = 0;
  std::uint64_t out_of_workspace_ticks = 0;  // The part of rejected_ticks far outside.
  std::uint64_t unfinished_ticks = 0;        // Ticks with a capped point.
  std::uint64_t capped_points = 0;           // Summed over ticks.
  std::uint64_t deferred_points = 0;         // Summed over ticks.
  std::uint64_t total_transitions = 0;
  std::uint32_t max_transitions_in_tick = 0;  // Most in one tick, all points together.
  std::uint64_t rigid_rounds = 0;             // Rigid coupling: summed over ticks.
  std::uint32_t max_rigid_rounds_in_tick = 0;
  std::uint64_t unresolved_ticks = 0;
  std::uint64_t unseated_ticks = 0;
};

// One point of a snapshot.
struct ProxySnapshot {
  ProxyPlace place;
  Vec3 p;  // The device point.
  Vec3 force_N;
  TickResult tick;
};

struct BladeSnapshotHeader {
  std::uint64_t tick_index = 0;  // Blade ticks stepped since reset (rejected ones included).
  BladeTick tick;
  BladeCounters counters;
  std::int32_t point_count = 0;  // Points of the blade (the snapshot may hold fewer).
  std::int32_t points_written = 0;
};

// A whole tick in one trivially copyable value, for a blade of at most N
// points: what the servo thread publishes (server/rt/latest_value.h) and another
// thread reads.
template <std::size_t N>
struct BladeSnapshot {
  BladeSnapshotHeader header;
  std::array<ProxySnapshot, N> points;
};

class Blade {
 public:
  static constexpr int kMaxPoints = 10000;
  // Rounds of a rigid tick (walk, fit, walk again), and the halvings of one
  // conservative advance: bounded work, counted in BladeTick.
  static constexpr int kMaxRigidRounds = 8;
  static constexpr int kMaxAdvanceHalvings = 4;

  // Throws std::invalid_argument naming the value when spec.points is outside
  // 1..kMaxPoints or an end is not finite. Builds its own ForceShading from
  // the Space unless one is given (shared between blades of one Space).
  Blade(std::shared_ptr<const Space> space, const BladeSpec& spec,
        std::shared_ptr<const ForceShading> shading = nullptr);
  Blade(const Space& space, const BladeSpec& spec) : Blade(owner_of(space), spec) {}

  // Places every proxy (may allocate). Throws std::invalid_argument for a pose
  // Blade::step would reject.
  void reset(const Pose& pose);
  // One tick with the Space's settings, or with the given ones. Never allocates.
  BladeTick step(const Pose& pose, double dt_s);
  BladeTick step(const Pose& pose, double dt_s, const RuntimeSettings& settings);
  // Whether step and reset would take this pose, and why not: the same check
  // they run (not finite, a rotation of (near) zero norm, a point outside the
  // Space's workspace), without placing anything. Never allocates.
  PoseCheck check_pose(const Pose& pose) const;

  // Copies the last tick into caller storage, up to points.size() points;
  // never allocates. Returns the points written.
  std::size_t snapshot(BladeSnapshotHeader& header, std::span<ProxySnapshot> points) const;
  template <std::size_t N>
  void snapshot(BladeSnapshot<N>& out) const {
    snapshot(out.header, std::span<ProxySnapshot>(out.points));
  }

  int point_count() const { return static_cast<int>(proxies_.size()); }
  const Space& space() const { return *space_; }
  const ForceShading& shading() const { return *shading_; }
  const std::vector<Vec3>& tool_points() const { return tool_points_; }
  const std::vector<Vec3>& world_points() const { return world_points_; }
  const std::vector<Proxy>& proxies() const { return proxies_; }
  const std::vector<TickResult>& point_ticks() const { return point_ticks_; }
  const BladeTick& last_tick() const { return last_tick_; }
  const BladeCounters& counters() const { return counters_; }
  void clear_counters();

  BladeCoupling coupling() const { return coupling_; }
  BladeOrientation orientation() const { return orientation_; }
  // Takes effect from the next tick, turned in over ramp_s: a rigid blade's
  // edge turns from its direction at the switch to the new rule's (the
  // device's, or the free fit's) over that time, so the force does not jump.
  // Never allocates.
  void set_orientation(BladeOrientation orientation, double ramp_s = 0.0);
  // The rigid blade's ideal tool pose (its edge, with the roll about the edge
  // taken from the device); for independent points, the last device pose.
  const Pose& ideal_pose() const { return ideal_pose_; }
  // The rigid blade's points on its ideal pose (independent: the proxies' q).
  Vec3 ideal_point(int i) const;
  // The point forces k (x_i - p_i) of the last tick (independent: the proxies').
  Vec3 point_force(int i) const;

 private:
  PoseCheck place_checked(const Pose& pose);
  BladeTick reject(bool out_of_workspace);
  // Today's per-point tick (the paper's blade): every proxy toward its
  // device point under the work budget; the summed force and torque.
  BladeTick step_points(double dt_s, const RuntimeSettings& settings);
  void count(const BladeTick& tick);
  // The rigid coupling (blade_rigid.cpp).
  BladeTick step_rigid(const Pose& pose, double dt_s, const RuntimeSettings& settings);
  // The device's edge from the last placed pose.
  EdgePose device_edge() const;
  // Whether every point and every stretch between neighbours of `edge` lies
  // outside rigid material; if so, makes it the ideal pose (seated).
  bool seat_at(const EdgePose& edge);
  // The walls of a point's walks this tick: a membrane is one where the
  // point's own tick reached it and did not break it (its spring, not its
  // neighbours' pull, breaks it; once broken in, it resists as a target).
  // May move start_tet to the tet outside the membrane the point lies on.
  ProbeWalls membrane_walls(const ProxyPlace& place, const Vec3& device_point,
                            std::int32_t& start_tet) const;
  // Walks every point from the ideal pose to `edge` and then the stretches
  // between neighbours there; true when nothing met rigid material. `advance`
  // gets the least fraction any point got; contacts found are added when asked.
  bool probe_motion(const EdgePose& edge, double& advance, bool add_contacts);
  // The swept test of every stretch between neighbours over one piece of the
  // motion, from pose `first` to `last` (at from..to of the whole motion;
  // swept_stretch.h): true when no rigid surface edge crosses any; else
  // `advance` gets the earliest crossing and contacts are added when asked.
  bool sweep_stretches(const EdgePose& first, const EdgePose& last, double from, double to,
                       double& advance, bool add_contacts);
  // A stretch's hit (between fractions f0 and f1): the earliest sets the
  // advance and the sample met first; a contact when asked.
  void take_swept_hit(const SweptHit& hit, double f0, double f1, double& advance,
                      bool add_contacts);
  // The same with each stretch's own query of the rigid edges (where the
  // broad phase would gather too many).
  bool sweep_stretches_each(const EdgePose& first, const EdgePose& last, double from, double to,
                            double& advance, bool add_contacts);
  // `wall_tet` is the tet whose material holds the edge there (its friction);
  // `feature` what the sample met (its force shading).
  void add_contact(double fraction, const Plane& plane, std::int32_t wall_tet,
                   const ContactFeature& feature);
  // Friction at the contacts (docs/decisions.md, "Friction at rigid
  // contacts"): from `start` (the tick's first verified pose, its points in
  // start_points_), rolled on its support, to the frictionless ideal pose, the
  // blade sticks while the springs' pull along the contacts stays within the
  // static coefficient times their push, else slides as far as leaves the
  // pull at the dynamic coefficient times the push.
  void apply_friction(const EdgePose& start, bool locked);
  // Steps 2-4 of a rigid tick (blade_rigid.cpp): from the ideal pose toward
  // the targets, rounds of walks and constrained fits, the direction kept at
  // lock_direction when `lock`. True when the last trial verified whole.
  bool solve_pose(bool lock, const Vec3& lock_direction, int& rounds);
  // From the ideal pose toward `trial`, as far as the walks got (`advance`),
  // halved while the motion still meets rigid material; verified.
  void advance_verified(const EdgePose& trial, double advance);
  // How far from the ideal edge a contact's sample may lie and still touch
  // it: the nearest one's distance and a margin.
  double touching_distance() const;
  // Force shading of the rigid blade (blade_shading.cpp; docs/decisions.md,
  // "The rigid blade"): the force's part along the touching contacts' normals
  // takes their shaded normals, its size kept; the torque takes the change at
  // the contacts' device points.
  void shade_rigid_force(Vec3& force_N, Vec3& torque_N_mm) const;
  // Sum |x_i - t_i|^2 over the points of the ideal edge.
  double spring_energy() const;
  // The ideal pose turned about the contacts it rests on, toward the springs'
  // least energy, as far as the walks allow: a blade rolls on its support
  // where friction holds the support still.
  void roll_on_support(bool locked);
  // Makes the probed edge (trial_*) the ideal one.
  void accept_trial(const EdgePose& edge);
  void update_ideal_pose(const Pose& device);
  void place_proxies_on_ideal(const RuntimeSettings& settings);

  std::shared_ptr<const Space> space_;
  std::shared_ptr<const ForceShading> shading_;
  Vec3 tool_start_;  // The segment's start and its span (end - start), in the tool frame.
  Vec3 tool_span_;
  std::vector<double> fractions_;  // s_i: point i is tool_start_ + s_i tool_span_.
  std::vector<Vec3> tool_points_;
  std::vector<Vec3> world_points_;
  // The last placed pose's a - origin (the rotated start) and b (the rotated span).
  Vec3 world_lever_;
  Vec3 world_span_;
  std::vector<Proxy> proxies_;
  std::vector<TickResult> point_ticks_;
  std::size_t first_ = 0;  // Where the next tick starts: the budget's round robin.
  std::uint64_t tick_index_ = 0;
  BladeTick last_tick_;
  BladeCounters counters_;

  BladeCoupling coupling_ = BladeCoupling::Rigid;
  BladeOrientation orientation_ = BladeOrientation::Free;
  double length_mm_ = 0.0;  // |end - start|.
  Vec3 tool_direction_;     // (end - start) / length, or +x for a zero length.
  Pose device_pose_;        // The last placed pose.
  Pose ideal_pose_;
  EdgePose ideal_edge_;
  bool seated_ = false;
  // The rigid solve's storage, sized once: the ideal points and the tets that
  // hold them (kNoTet outside the mesh), a trial pose's, the targets t_i, the
  // walls each point's walks meet and the point forces.
  std::vector<Vec3> ideal_points_;
  std::vector<std::int32_t> ideal_tets_;
  std::vector<Vec3> trial_points_;
  std::vector<std::int32_t> trial_tets_;
  std::vector<Vec3> targets_;
  std::vector<ProbeWalls> walls_;
  std::vector<Vec3> point_forces_;
  EdgeContactSet contacts_;
  // The sample of the edge a motion moves in a straight line (interpolate_edge):
  // the middle, or once there are contacts the one the pose rests on, so a
  // turn does not swing the held sample into its plane.
  double motion_pivot_ = 0.5;
  // The sample of the edge where the last probe_motion met rigid material
  // first (a point, or a place between two).
  double earliest_hit_fraction_ = 0.5;
  // Whether the Space has a material that holds a point back (drag, viscous,
  // membrane): only then do a rigid blade's points tick for their targets.
  bool resisting_materials_ = true;
  // The largest friction coefficients of the materials met this tick, and
  // whether the blade slid on the last tick (then the dynamic one decides).
  double contact_static_friction_ = 0.0;
  double contact_dynamic_friction_ = 0.0;
  bool sliding_ = false;
  // An orientation switch being turned in (set_orientation): the ideal
  // edge's direction at the switch, the ramp's length and the time since.
  Vec3 ramp_from_direction_;
  double orientation_ramp_s_ = 0.0;
  double orientation_ramp_elapsed_s_ = 0.0;
  // The tick's first verified pose's points and tets, and the frictionless
  // pose's while a slide is verified.
  std::vector<Vec3> start_points_;
  std::vector<std::int32_t> start_tets_;
  std::vector<Vec3> held_points_;
  std::vector<std::int32_t> held_tets_;
  // The rigid surface's edges, for the stretches' swept test (two points or more).
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
