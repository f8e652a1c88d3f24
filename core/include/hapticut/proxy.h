// Proxy: the ideal point q of one device point p, moving through the Space
// under the rules of Table 1 (docs/method.md) with the paper's typos fixed and
// the listed repairs applied. Deterministic, bounded work per tick, no
// allocation, never NaN, never inside rigid material.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "hapticut/aabb_tree.h"
#include "hapticut/force_shading.h"
#include "hapticut/geometry.h"
#include "hapticut/material.h"
#include "hapticut/proxy_place.h"
#include "hapticut/space.h"

namespace hapticut {

// One call of Proxy::transition: the state before and after, whether the new
// state is owned by another tet than before ("neighbour" in Table 2), and
// whether anything changed (state, owner or |dq| > tolerance).
struct Transition {
  ProxyState from = ProxyState::Outside;
  ProxyState to = ProxyState::Outside;
  bool to_neighbour = false;
  bool changed = false;
  // The move stayed inside its tet or face, or along its edge: the next call would
  // change nothing (see docs/decisions.md, "Ending a tick"), so the tick ends.
  bool settled = false;
  // Pads the struct to 8 bytes so that it is returned in one register, not
  // through memory (docs/decisions.md, "Build tuning and the hot path").
  std::uint8_t padding0 = 0;
  std::uint8_t padding1 = 0;
  std::uint8_t padding2 = 0;
};

// The scalars first: a tick touches them next to the proxy's place (see the
// member order of Proxy); the transition table is written only on a transition.
struct ProxyCounters {
  std::uint64_t ticks = 0;
  std::uint64_t total_transitions = 0;
  std::uint32_t max_transitions_in_tick = 0;
  // Ticks that ended unfinished: the cap was reached and one more transition
  // would still have changed something (a walk that converges exactly at the
  // cap is not capped).
  std::uint64_t capped_ticks = 0;
  // Ticks whose input was refused (state kept, force zero): p not finite or
  // outside the Space's workspace, or settings out of range.
  std::uint64_t rejected_inputs = 0;
  std::uint64_t out_of_workspace_inputs = 0;  // The part of rejected_inputs far outside.
  std::uint64_t deferred_ticks = 0;           // Blade ticks skipped by the work budget.
  // transitions[from][to][to_neighbour]; "stay" transitions are not counted.
  std::array<std::array<std::array<std::uint64_t, 2>, kProxyStateCount>, kProxyStateCount>
      transitions{};
};

struct TickResult {
  int transitions = 0;
  bool capped = false;    // Unfinished: q is valid but behind p; the force is held.
  bool rejected = false;  // p not finite or outside the workspace: nothing moved, force zero.
  bool deferred = false;  // Blade only: the tick's work budget ran out before this point.
};

// How a reset went: where the proxy started.
enum class StartKind : std::uint8_t {
  InsideTet,         // p located in a non-rigid tet: TET, q = p.
  Outside,           // p outside the mesh: OUTSIDE, q = p.
  PushedOutOfRigid,  // p inside rigid material: q on the nearest face out of it.
};

class alignas(64) Proxy {
 public:
  // The proxy shares ownership of its Space (space.h, "Who owns a Space").
  explicit Proxy(std::shared_ptr<const Space> space);
  explicit Proxy(const Space& space) : Proxy(owner_of(space)) {}

  // Places the proxy for device point p (docs/method.md, repair 6; docs/decisions.md).
  // May allocate (the search out of rigid material). Throws std::invalid_argument
  // when p is not finite or outside the Space's workspace.
  StartKind reset(const Vec3& p);
  // One servo tick: transitions until nothing changes or the cap is hit.
  // dt_s is the tick's duration (for the viscous material's speed). The
  // settings are the Space's (Space::runtime_settings()) unless given; a
  // shading, when given and settings.force_shading is on, shades the force.
  // Never allocates. Rejects (state kept, force zero, counted) a p that is not
  // finite or lies outside the Space's workspace, and settings out of range.
  // Capped (exact): max_transitions_per_tick transitions were made and one
  // more would still change something. On a capped tick the proxy keeps its
  // valid place (and catches up next tick) and the force of the last finished
  // tick is held, no jump; from the second unfinished tick in a row on, the
  // held force is limited to capped_tick_force_N. `cuts`, when given, are the
  // tets cut so far: a cut tet acts as its material's cut variant
  // (Space::material_of_tet); the proxy reads them, a Blade marks them.
  TickResult step(const Vec3& p, double dt_s);
  TickResult step(const Vec3& p, double dt_s, const RuntimeSettings& settings,
                  const ForceShading* shading = nullptr, const CutState* cuts = nullptr);
  // A single transition of Table 1 (one pass of (a) then (b) for the current
  // state), with the cut tets context.cuts names.
  Transition transition(const Vec3& p, const MoveContext& context);

  const ProxyPlace& place() const { return place_; }
  // Asks the cache for the tet this proxy's next tick starts in (Space::prefetch_tet).
  void prefetch_place() const {
    if (place_.tet != kNoTet) space_->prefetch_tet(place_.tet);
  }
  // Puts the proxy at a given place (tests and benchmarks). Throws
  // std::invalid_argument naming the value when the state, tet, local index or
  // q is out of range (tet must be kNoTet exactly when OUTSIDE).
  void set_place(const ProxyPlace& place);
  // Seats the proxy where another solver verified its point (the rigid
  // blade's ideal pose): a TET place in a tet of the mesh that is not rigid,
  // or an OUTSIDE one, q finite; the force is eq. (15) there for device point
  // p, unshaded. False, changing nothing, for any other place. Never allocates.
  bool seat(const ProxyPlace& place, const Vec3& p, const RuntimeSettings& settings);
  // Zero force, the place kept (a solver with no valid place for the point).
  void release_force() { force_N_ = {}; }
  const Vec3& q() const { return place_.q; }
  const Vec3& last_p() const { return last_p_; }
  // Force on the device point, eq. (15), shaded when asked; on a capped tick
  // the held force (see step). Zero after a rejected input.
  Vec3 force_N() const { return force_N_; }
  const ProxyCounters& counters() const { return counters_; }
  void clear_counters() { counters_ = {}; }

  // Does the state agree with q (within tolerance_factor x the mesh tolerance),
  // is q outside every rigid tet, and an OUTSIDE q outside the mesh (or on its
  // boundary)? Returns "" when it does, else the first reason found.
  std::string check_invariants(double tolerance_factor = 100.0) const;

 private:
  friend class Blade;  // Runs the pieces of step below under its work budget.
  // Table 2's timing loop (core/python/bind_benchmarks.cpp) restores a start
  // place it checked once through set_place without checking it again: the
  // check is not part of the transition timed, and subtracting it is noisier
  // than not making it.
  friend struct TransitionTimingAccess;
  // The test that the settles give what the walk gives (tests/cpp/tet_settle_test.cpp)
  // runs walk, settle_in_tet, settle_on_bone and settle_in_air apart.
  friend struct TetSettleTestAccess;

  // The pieces of step. A tick makes at most `limit` transitions in all
  // (exact, see step); a capped tick is left open when `keep_capped_open`
  // (the Blade then walks on with what its budget has left, and ends it).
  void reject_input(bool out_of_workspace, TickResult& result);
  // A point's tick (inline, defined below, so the blade's loop has it without
  // a call): the first settle that takes it, else walk. Every piece reads the
  // materials through `cuts` (null: nothing cut), fixed for the tick.
  void tick(const Vec3& p, double dt_s, const RuntimeSettings& settings, int limit,
            const ForceShading* shading, bool keep_capped_open, TickResult& result,
            const CutState* cuts = nullptr);
  // The settles: the ticks most points make, inline (defined below). Each one
  // decides whether its tick ends after one move within the proxy's place;
  // when it does, it makes that move and ends the tick with the same place,
  // counters and force as walk would give, bit for bit, without the walk's
  // machinery, which is most of such a tick's cost (docs/decisions.md, "The
  // settle in a tet and the slide on bone, inline"). Otherwise it returns
  // false, touching nothing, and walk does the tick. Each declines a tick
  // already under way.
  //
  // A TET proxy whose material moves it (free, drag, membrane) to a q' still
  // inside its tet stays there (step_tet's settle). Declines a viscous material.
  bool settle_in_tet(const Vec3& p, const RuntimeSettings& settings, int limit, TickResult& result,
                     const CutState* cuts = nullptr);
  // A FACE proxy pressed against bone: p strictly beyond the face, the
  // neighbour rigid, the slide's end inside the face and off its edges
  // (step_face's settle). Declines a viscous material and a shaded force.
  bool settle_on_bone(const Vec3& p, const RuntimeSettings& settings, int limit,
                      const ForceShading* shading, TickResult& result,
                      const CutState* cuts = nullptr);
  // An OUTSIDE proxy in free air beside the mesh: q -> p lies wholly beyond
  // one face of the entry box, so q follows p (step_outside's first test,
  // then the walk's probe that finds nothing more to do). Declines a shaded force.
  bool settle_in_air(const Vec3& p, const RuntimeSettings& settings, int limit,
                     const ForceShading* shading, TickResult& result);
  // A tick the settles declined: transitions toward p until converged or
  // `limit` in all this tick, then end_tick, unless the walk is capped and
  // `keep_capped_open`.
  void walk(const Vec3& p, double dt_s, const RuntimeSettings& settings, int limit,
            const ForceShading* shading, bool keep_capped_open, TickResult& result,
            const CutState* cuts = nullptr);
  MoveContext context_for(const Vec3& p, double dt_s, const RuntimeSettings& settings,
                          const CutState* cuts) const;
  // The end of every tick walked or settled (inline, defined below): the
  // counters, p, and the force, eq. (15), or the held force when capped.
  void end_tick(const Vec3& p, TickResult& result, const RuntimeSettings& settings,
                const ForceShading* shading);
  // The end of a settled tick: q moved to q1 within its place, a transition
  // of `state` to itself when that changed q (as settle_at decides), then end_tick.
  void end_tick_at(const Vec3& p, const Vec3& q1, ProxyState state, const RuntimeSettings& settings,
                   TickResult& result);
  // A Blade point its work budget did not reach: place kept, force held.
  void defer_tick(TickResult& result, const RuntimeSettings& settings);
  // An unfinished tick: the last finished force, limited from the second in a row on.
  void hold_force(const RuntimeSettings& settings);
  // Eq. (15), f = k (q - p), shaded when a shading is given and on; zero
  // where not finite.
  Vec3 spring_force(const Vec3& p, const RuntimeSettings& settings,
                    const ForceShading* shading) const;

  // What one step of a state did: nothing, moved (the tick goes on), or
  // moved within its tet, face or edge and settled (the tick ends; see settle_at).
  enum class Outcome : std::uint8_t { Unchanged, Changed, Settled };
  Outcome advance(const Vec3& p, const MoveContext& context);
  Outcome step_tet(const Vec3& p, const MoveContext& context);
  Outcome step_face(const Vec3& p, const MoveContext& context);
  Outcome slide_on_face(const Vec3& p, const MoveContext& context);
  Outcome step_edge(const Vec3& p, const MoveContext& context);
  Outcome slide_along_edge(const Vec3& p, const MoveContext& context);
  Outcome step_vertex(const Vec3& p, const MoveContext& context);
  Outcome step_outside(const Vec3& p);
  Outcome enter_beyond(const Vec3& q, const Vec3& end, const Vec3& p, double lowest,
                       int rims_passed);
  Outcome leave_outside(const Vec3& p);
  Outcome enter_through_rim(const FaceRef& face, const std::array<int, 2>& sides, const Vec3& c,
                            const Vec3& p);
  Outcome go(ProxyState to, std::int32_t tet, int local, const Vec3& q);
  Outcome settle_at(const Vec3& q);
  StartKind push_out_of_rigid(std::int32_t start_tet, const Vec3& p);

  // Member order is for the cache: what every tick reads and writes (the
  // Space pointer, the place, p, the force, the scalar counters up to
  // max_transitions_in_tick) fills the first two cache lines exactly; a
  // 500-point blade's proxies do not fit L1, and each line more per proxy
  // is a miss more per point and tick (static_assert in proxy.cpp;
  // docs/decisions.md, "Build tuning and the hot path"). The Space
  // goes through a plain pointer on the hot path; space_owner_ (last, away
  // from the hot members) keeps it alive.
  const Space* space_;
  ProxyPlace place_;
  Vec3 last_p_;
  Vec3 force_N_;
  int unfinished_in_row_ = 0;  // Capped or deferred ticks since the last finished one.
  bool has_last_p_ = false;
  ProxyCounters counters_;
  // The force of the last finished tick, held on a capped or deferred one:
  // saved when the first of them begins (hold_force), not on every tick.
  Vec3 finished_force_N_;
  // The mesh's box grown by its diagonal: OUTSIDE clips its entry search to it.
  Aabb reach_box_;
  // The mesh's box grown by the tolerance: a p outside it is outside the mesh.
  Aabb mesh_box_;
  // OUTSIDE's first test: a move beyond one face of this box enters nowhere.
  Aabb entry_box_;
  std::shared_ptr<const Space> space_owner_;
};

[[gnu::always_inline]] inline Vec3 Proxy::spring_force(const Vec3& p,
                                                       const RuntimeSettings& settings,
                                                       const ForceShading* shading) const {
  Vec3 force = (place_.q - p) * settings.stiffness_N_per_mm;
  if (shading != nullptr && settings.force_shading) force = shading->shade(place_, force);
  return is_finite(force) ? force : Vec3{};
}

[[gnu::always_inline]] inline void Proxy::end_tick(const Vec3& p, TickResult& result,
                                                   const RuntimeSettings& settings,
                                                   const ForceShading* shading) {
  // A branch, not std::max: GCC vectorises the max through a 16-byte reload of
  // a 4-byte store, a store-forwarding stall on every step (docs/decisions.md,
  // "Build tuning and the hot path").
  const auto transitions = static_cast<std::uint32_t>(result.transitions);
  counters_.total_transitions += transitions;
  if (transitions > counters_.max_transitions_in_tick) {
    counters_.max_transitions_in_tick = transitions;
  }
  last_p_ = p;
  has_last_p_ = true;
  if (result.capped) {
    // The proxy is valid but behind: its lag is the computation's, not the
    // material's. The hand keeps feeling the last finished force while the
    // proxy catches up; a proxy that stays behind is limited to the capped force.
    ++counters_.capped_ticks;
    hold_force(settings);
    return;
  }
  force_N_ = spring_force(p, settings, shading);
  unfinished_in_row_ = 0;
}

// No shading: settle_in_tet's force is a TET force, which shading leaves as it
// is (ForceShading::shade), and the other settles decline a shaded force.
[[gnu::always_inline]] inline void Proxy::end_tick_at(const Vec3& p, const Vec3& q1,
                                                      ProxyState state,
                                                      const RuntimeSettings& settings,
                                                      TickResult& result) {
  int transitions = 0;
  if (!within_tolerance(q1 - place_.q, space_->tolerance())) {
    transitions = 1;
    const auto s = static_cast<int>(state);
    ++counters_.transitions[s][s][0];  // To itself, same owner: not a neighbour.
  }
  place_.q = q1;
  result.transitions = transitions;
  end_tick(p, result, settings, nullptr);
}

// step_tet's (b-2): the material's move, no exit plane strictly crossed.
[[gnu::always_inline]] inline bool Proxy::settle_in_tet(const Vec3& p,
                                                        const RuntimeSettings& settings, int limit,
                                                        TickResult& result, const CutState* cuts) {
  if (place_.state != ProxyState::Tet || result.transitions != 0 || limit < 1) return false;
  const std::int32_t t = place_.tet;
  const MaterialModel model = space_->tet_model(t, cuts);
  if (model == MaterialModel::Viscous) return false;  // Its move needs the tick's speed.
  const double eps = space_->tolerance();
  MoveResult moved{true, p};
  if (model != MaterialModel::Free) {
    MoveContext context;
    context.stiffness_N_per_mm = settings.stiffness_N_per_mm;
    context.tolerance_mm = eps;
    moved = move(space_->material_of_tet(t, cuts), p, place_.q, context);
  }
  if (moved.moved) {
    const Plane* planes = &space_->mesh().face_plane(t, 0);
    bool leaves = false;
    for (int k = 0; k < 4; ++k) {
      leaves = leaves || strictly_beyond(planes[k].signed_distance(moved.q), eps);
    }
    if (leaves) return false;
  }
  end_tick_at(p, moved.q, ProxyState::Tet, settings, result);
  return true;
}

// step_face's (a-1) refused by a rigid neighbour, then (b): the slide to p
// projected on the plane (eq. 6), no other face plane strictly crossed nor
// touched (touching it, the edge's fan may decide: the walk does it).
[[gnu::always_inline]] inline bool Proxy::settle_on_bone(const Vec3& p,
                                                         const RuntimeSettings& settings, int limit,
                                                         const ForceShading* shading,
                                                         TickResult& result, const CutState* cuts) {
  if (place_.state != ProxyState::Face || result.transitions != 0 || limit < 1) return false;
  if (shading != nullptr && settings.force_shading) return false;
  const TetMesh& mesh = space_->mesh();
  const std::int32_t t = place_.tet;
  const int face = place_.local;
  const Vec3 q = place_.q;
  const double eps = space_->tolerance();
  const Plane* planes = &mesh.face_plane(t, 0);
  if (!strictly_beyond(dot(planes[face].normal, p - q), eps)) return false;
  const std::int32_t u = mesh.neighbour(t, face);
  if (u == kNoTet || !space_->tet_is_rigid(u)) return false;
  const MaterialModel model = space_->tet_model(t, cuts);
  if (model == MaterialModel::Viscous) return false;  // Its move needs the tick's speed.
  const Vec3 target = project_to_plane(p, planes[face]);
  MoveResult moved{true, target};
  if (model != MaterialModel::Free) {
    MoveContext context;
    context.stiffness_N_per_mm = settings.stiffness_N_per_mm;
    context.tolerance_mm = eps;
    moved = move(space_->material_of_tet(t, cuts), target, q, context);
  }
  if (moved.moved) {
    bool reaches = false;
    for (int k = 0; k < 4; ++k) {
      reaches = reaches || (k != face && on_or_beyond(planes[k].signed_distance(moved.q), eps));
    }
    if (reaches) return false;
  }
  end_tick_at(p, moved.q, ProxyState::Face, settings, result);
  return true;
}

// step_outside's box test: q -> p meets nothing of the mesh, q' = p, and
// the walk's next step would change nothing.
[[gnu::always_inline]] inline bool Proxy::settle_in_air(const Vec3& p,
                                                        const RuntimeSettings& settings, int limit,
                                                        const ForceShading* shading,
                                                        TickResult& result) {
  if (place_.state != ProxyState::Outside || result.transitions != 0 || limit < 1) return false;
  if (shading != nullptr && settings.force_shading) return false;
  if (!box_beyond_face(segment_box(place_.q, p), entry_box_)) return false;
  end_tick_at(p, p, ProxyState::Outside, settings, result);
  return true;
}

[[gnu::always_inline]] inline void Proxy::tick(const Vec3& p, double dt_s,
                                               const RuntimeSettings& settings, int limit,
                                               const ForceShading* shading, bool keep_capped_open,
                                               TickResult& result, const CutState* cuts) {
  if (settle_in_tet(p, settings, limit, result, cuts) ||
      settle_on_bone(p, settings, limit, shading, result, cuts) ||
      settle_in_air(p, settings, limit, shading, result)) {
    return;
  }
  walk(p, dt_s, settings, limit, shading, keep_capped_open, result, cuts);
}

}  // namespace hapticut
