// Proxy: the ideal point q of one device point p, moving through the Space
// under the rules of Table 1 (ALGORITHM.md) with the paper's typos fixed and
// the listed repairs applied. Deterministic, bounded work per tick, no
// allocation, never NaN, never inside rigid material.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "hapticut/aabb_tree.h"
#include "hapticut/material.h"
#include "hapticut/space.h"

namespace hapticut {

enum class ProxyState : std::uint8_t { Tet = 0, Face = 1, Edge = 2, Vertex = 3, Outside = 4 };
inline constexpr int kProxyStateCount = 5;
const char* proxy_state_name(ProxyState state);

// Where the proxy is: its state, the tet that owns the state (ALGORITHM.md,
// "Every constrained state is owned by a tet") and which of that tet's faces
// (0-3), edges (0-5) or vertices (0-3) constrains it.
struct ProxyPlace {
  ProxyState state = ProxyState::Outside;
  std::int32_t tet = kNoTet;
  std::int8_t local = 0;
  Vec3 q;
};

// One call of Proxy::transition: the state before and after, whether the new
// state is owned by another tet than before ("neighbour" in Table 2), and
// whether anything changed (state, owner or |dq| > tolerance).
struct Transition {
  ProxyState from = ProxyState::Outside;
  ProxyState to = ProxyState::Outside;
  bool to_neighbour = false;
  bool changed = false;
  // The move stayed inside its tet or face: the next call in this tick would
  // change nothing (see docs/decisions.md, "Ending a tick"), so the tick ends.
  bool settled = false;
  // Pads the struct to 8 bytes, returned in one register: at 5 bytes GCC
  // returned it through memory and a TET move took 19 ns instead of 11.
  std::uint8_t padding0 = 0;
  std::uint8_t padding1 = 0;
  std::uint8_t padding2 = 0;
};

struct ProxyCounters {
  // transitions[from][to][to_neighbour]; "stay" transitions are not counted.
  std::array<std::array<std::array<std::uint64_t, 2>, kProxyStateCount>, kProxyStateCount>
      transitions{};
  std::uint64_t ticks = 0;
  std::uint64_t capped_ticks = 0;     // Ticks that hit max_transitions_per_tick.
  std::uint64_t rejected_inputs = 0;  // Ticks whose p was not finite (state kept).
  std::uint32_t max_transitions_in_tick = 0;
  std::uint64_t total_transitions = 0;
};

struct TickResult {
  int transitions = 0;
  bool capped = false;
  bool rejected = false;  // p was NaN/inf: nothing moved, force zero.
};

// How a reset went: where the proxy started.
enum class StartKind : std::uint8_t {
  InsideTet,         // p located in a non-rigid tet: TET, q = p.
  Outside,           // p outside the mesh: OUTSIDE, q = p.
  PushedOutOfRigid,  // p inside rigid material: q on the nearest face out of it.
};

class Proxy {
 public:
  explicit Proxy(const Space& space);

  // Places the proxy for device point p (ALGORITHM.md repair 6; docs/decisions.md).
  StartKind reset(const Vec3& p);
  // One servo tick: transitions until nothing changes or the cap is hit.
  // dt_s is the tick's duration (for the viscous material's speed).
  TickResult step(const Vec3& p, double dt_s);
  // A single transition of Table 1 (one pass of (a) then (b) for the current state).
  Transition transition(const Vec3& p, const MoveContext& context);

  const ProxyPlace& place() const { return place_; }
  void set_place(const ProxyPlace& place) { place_ = place; }
  const Vec3& q() const { return place_.q; }
  const Vec3& last_p() const { return last_p_; }
  // Force on the device point, eq. (15); on a capped tick clamped to
  // capped_tick_force_N. Zero after a rejected input.
  Vec3 force_N() const { return force_N_; }
  const ProxyCounters& counters() const { return counters_; }
  void clear_counters() { counters_ = {}; }

  // Does the state agree with q (within tolerance_factor x the mesh tolerance),
  // is q outside every rigid tet, and an OUTSIDE q outside the mesh (or on its
  // boundary)? Returns "" when it does, else the first reason found.
  std::string check_invariants(double tolerance_factor = 100.0) const;

 private:
  // What one step of a state did: nothing, moved (the tick goes on), or
  // moved within its tet or face and settled (the tick ends; see settle_at).
  enum class Outcome : std::uint8_t { Unchanged, Changed, Settled };
  Outcome advance(const Vec3& p, const MoveContext& context);
  Outcome step_tet(const Vec3& p, const MoveContext& context);
  Outcome step_face(const Vec3& p, const MoveContext& context);
  Outcome step_edge(const Vec3& p, const MoveContext& context);
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

  const Space* space_;
  // The mesh's box grown by its diagonal: OUTSIDE clips its entry search to it.
  Aabb reach_box_;
  // The mesh's box grown by the tolerance: a p outside it is outside the mesh.
  Aabb mesh_box_;
  ProxyPlace place_;
  Vec3 last_p_;
  bool has_last_p_ = false;
  Vec3 force_N_;
  ProxyCounters counters_;
};

}  // namespace hapticut
