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

#include "hapticut/cut_state.h"
#include "hapticut/edge_fit.h"
#include "hapticut/force_shading.h"
#include "hapticut/pose.h"
#include "hapticut/proxy.h"
#include "hapticut/rigid_edge.h"
#include "hapticut/scene.h"

namespace hapticut {

// Whether a pose can be used, and why not.
enum class PoseCheck : std::uint8_t { Fine, NotFinite, ZeroRotation, OutOfWorkspace };

struct BladeTick {
  // Sum of the points' forces k (q_i - p_i), shaded when asked: each point's
  // (independent), or at the contacts (rigid, RigidEdge::shade_force).
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
  // Rounds of a rigid tick (walk, fit, walk again): bounded work, counted in BladeTick.
  static constexpr int kMaxRigidRounds = RigidEdge::kMaxRounds;

  // Throws std::invalid_argument naming the value when spec.points is outside
  // 1..kMaxPoints or an end is not finite. Builds its own ForceShading from
  // the Space unless one is given (shared between blades of one Space), and
  // its own CutState unless one is given (shared between the blades of one
  // loaded scene: what one cuts, the others find cut; made for this Space).
  Blade(std::shared_ptr<const Space> space, const BladeSpec& spec,
        std::shared_ptr<const ForceShading> shading = nullptr,
        std::shared_ptr<CutState> cuts = nullptr);
  Blade(const Space& space, const BladeSpec& spec) : Blade(owner_of(space), spec) {}

  // Places every proxy (may allocate). Throws std::invalid_argument for a pose
  // Blade::step would reject. The cut tets stay cut (reset_cuts uncuts them).
  void reset(const Pose& pose);
  // One tick with the Space's settings, or with the given ones. Never allocates.
  // The tick reads the materials through the cut state as it was when the
  // tick began; at its end every point cuts what it has passed and left
  // (cut_state.h, the rule for cutting), which later ticks feel.
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
  // The cut tets this blade reads and marks (shared with the scene's other blades).
  const CutState& cuts() const { return *cuts_; }
  // Uncuts every tet of the shared cut state (cut_state.h). Never allocates.
  void reset_cuts() { cuts_->reset_cuts(); }
  // CutState::set_cuts on the blade's cut state (shared with the scene's other blades).
  void set_cuts(std::span<const std::int32_t> tets) { cuts_->set_cuts(tets); }
  // Off: this blade reads every tet as its own material and cuts nothing, the
  // paper's blade without memory (what `hapticut bench blade` weighs the
  // memory's cost against); the shared cut state is kept as it is. On by
  // default; takes effect from the next tick. Never allocates.
  void set_cut_memory(bool on);
  bool cut_memory() const { return read_cuts_ != nullptr; }
  const std::vector<Vec3>& tool_points() const { return tool_points_; }
  const std::vector<Vec3>& world_points() const { return world_points_; }
  const std::vector<Proxy>& proxies() const { return proxies_; }
  const std::vector<TickResult>& point_ticks() const { return point_ticks_; }
  const BladeTick& last_tick() const { return last_tick_; }
  // The fraction of the edge whose sample the rigid blade's last move carried
  // on a straight line (interpolate_edge's pivot); 0.5 for independent points.
  double rigid_motion_pivot() const { return rigid_ ? rigid_->motion_pivot() : 0.5; }
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
  BladeTick step_rigid(double dt_s, const RuntimeSettings& settings);
  // The device's edge from the last placed pose.
  EdgePose device_edge() const;
  void update_ideal_pose(const Pose& device);
  void place_proxies_on_ideal(const RuntimeSettings& settings);
  // The rule for cutting (cut_state.h): what each point left behind over the
  // tick, from start_places_ to its place now, and what the edge between
  // neighbouring points lies across.
  void cut_swept();

  std::shared_ptr<const Space> space_;
  std::shared_ptr<const ForceShading> shading_;
  std::shared_ptr<CutState> cuts_;
  // What the walks read: cuts_, or null with the cut memory off.
  const CutState* read_cuts_ = nullptr;
  // Whether the Space has a cuttable material (drag, viscous, membrane): only
  // then do the points look for tets to cut.
  bool has_cuttable_materials_ = true;
  // Whether the points look for tets to cut: the above, with the memory on.
  bool cuttable_materials_ = true;
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
  std::vector<ProxyPlace> start_places_;  // The points' places when this tick began.
  // Where the stretch between points i and i + 1 was when cut_swept last
  // walked it (valid: since the last reset).
  struct EdgeWalk {
    ProxyPlace a;
    ProxyPlace b;
    bool valid = false;
  };
  std::vector<EdgeWalk> edge_walks_;
  static constexpr double kEdgeWalkStep_mm = 0.25;
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
  // The rigid coupling: the solver of its pose (rigid_edge.h), whether it has
  // a verified one yet, and the points' forces on it.
  std::unique_ptr<RigidEdge> rigid_;
  bool seated_ = false;
  std::vector<Vec3> point_forces_;
  // Whether the Space has a material that holds a point back (drag, viscous,
  // membrane): only then do a rigid blade's points tick for their targets.
  bool resisting_materials_ = true;
  // An orientation switch being turned in (set_orientation): the ideal
  // edge's direction at the switch, the ramp's length and the time since.
  Vec3 ramp_from_direction_;
  double orientation_ramp_s_ = 0.0;
  double orientation_ramp_elapsed_s_ = 0.0;
};

}  // namespace hapticut
