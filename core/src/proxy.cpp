#include "hapticut/proxy.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <vector>

#include "hapticut/geometry.h"

namespace hapticut {

namespace {

// The nearest plane among some of a tet's faces that q->q1 exits through
// (docs/method.md, repair 1), and where. Without an exit, `touching` is the first of those
// faces whose plane q1 lies on (within eps), if asked for: FACE's edge arrival.
struct Exit {
  int face = -1;
  double parameter = 2.0;
  int touching = -1;
};

// The exit among `count` faces of tet t. Most moves end inside, so q1's
// distances come first, all at once; q's are computed only for a plane q1 is out of.
template <bool report_touching, std::size_t count>
inline Exit find_exit_among(const TetMesh& mesh, std::int32_t t,
                            const std::array<int, count>& faces, const Vec3& q, const Vec3& q1,
                            double eps) {
  const Plane* planes = &mesh.face_plane(t, 0);
  std::array<double, count> d1{};
  bool any_out = false;
  for (std::size_t k = 0; k < count; ++k) {
    d1[k] = planes[faces[k]].signed_distance(q1);
    any_out = any_out || strictly_beyond(d1[k], eps);
  }
  Exit best;
  if (!any_out) {
    if constexpr (report_touching) {
      for (std::size_t k = 0; k < count && best.touching < 0; ++k) {
        if (on_or_beyond(d1[k], eps)) best.touching = faces[k];
      }
    }
    return best;
  }
  for (std::size_t k = 0; k < count; ++k) {
    if (!strictly_beyond(d1[k], eps)) continue;
    const double s = segment_exit_parameter(planes[faces[k]].signed_distance(q), d1[k], eps);
    if (s >= 0.0 && s < best.parameter) best = {faces[k], s};
  }
  return best;
}

inline Exit find_tet_exit(const TetMesh& mesh, std::int32_t t, const Vec3& q, const Vec3& q1,
                          double eps) {
  static constexpr std::array<int, 4> kAllFaces{0, 1, 2, 3};
  return find_exit_among<false>(mesh, t, kAllFaces, q, q1, eps);
}

inline Exit find_face_exit(const TetMesh& mesh, std::int32_t t, int face, const Vec3& q,
                           const Vec3& q1, double eps) {
  return find_exit_among<true>(mesh, t, kOtherFaces[face], q, q1, eps);
}

// "Neighbour" in Table 2: the new state is owned by another tet than the old one.
bool is_neighbour(std::int32_t from_tet, std::int32_t to_tet) {
  return from_tet != kNoTet && to_tet != kNoTet && to_tet != from_tet;
}

// Up to this many boundary faces, OUTSIDE scans them all instead of walking the tree.
constexpr std::size_t kLinearEntryScanMax = 32;
// Rim hits resolved per OUTSIDE step before the safety net decides: a
// segment exactly through several boundary vertices or edges, each passed by
// outside, is all it takes to need more than one.
constexpr int kRimPassesMax = 4;

int local_index_of(const std::array<std::int32_t, 4>& tet, std::int32_t vertex) {
  for (int k = 0; k < 4; ++k) {
    if (tet[k] == vertex) return k;
  }
  return 0;
}

// A candidate of the (a-3) steps of EDGE and VERTEX: the widest constraint
// the target can move along. Ties keep the first found (faces before edges
// within a tet, tets in fan order), so the choice is deterministic.
struct Candidate {
  ProxyState state = ProxyState::Outside;
  std::int32_t tet = kNoTet;
  int local = 0;
  double score = -1.0;
};

}  // namespace

const char* proxy_state_name(ProxyState state) {
  switch (state) {
    case ProxyState::Tet:
      return "TET";
    case ProxyState::Face:
      return "FACE";
    case ProxyState::Edge:
      return "EDGE";
    case ProxyState::Vertex:
      return "VERTEX";
    case ProxyState::Outside:
      return "OUTSIDE";
  }
  return "?";
}

Proxy::Proxy(std::shared_ptr<const Space> space)
    : space_(space.get()), space_owner_(std::move(space)) {
  // The members every tick touches stay within the first two cache lines (proxy.h).
  static_assert(offsetof(Proxy, counters_) + offsetof(ProxyCounters, max_transitions_in_tick) +
                    sizeof(ProxyCounters::max_transitions_in_tick) <=
                128);
  if (space_ == nullptr) throw std::invalid_argument("a Proxy needs a Space");
  // One pass over the vertices for the three boxes.
  const Aabb tight = mesh_box(space_->mesh(), 0.0);
  reach_box_ = reach_box(tight);
  mesh_box_ = grown(tight, space_->tolerance());
  entry_box_ = entry_box(tight, space_->tolerance());
}

void Proxy::set_place(const ProxyPlace& place) {
  const auto state = static_cast<int>(place.state);
  if (state < 0 || state >= kProxyStateCount) {
    throw std::invalid_argument("proxy state " + std::to_string(state) + " is not a state (0-4)");
  }
  const bool outside = place.state == ProxyState::Outside;
  if (outside ? place.tet != kNoTet : place.tet < 0 || place.tet >= space_->mesh().tet_count()) {
    throw std::invalid_argument(
        "tet " + std::to_string(place.tet) + " for a " + proxy_state_name(place.state) +
        " proxy: expected " +
        (outside ? std::string("-1") : "0.." + std::to_string(space_->mesh().tet_count() - 1)));
  }
  const int locals = place.state == ProxyState::Edge                                        ? 6
                     : place.state == ProxyState::Face || place.state == ProxyState::Vertex ? 4
                                                                                            : 1;
  if (place.local < 0 || place.local >= locals) {
    throw std::invalid_argument("local index " + std::to_string(place.local) + " for a " +
                                proxy_state_name(place.state) + " proxy: expected 0.." +
                                std::to_string(locals - 1));
  }
  if (!is_finite(place.q)) throw std::invalid_argument("proxy q is not finite");
  place_ = place;
}

bool Proxy::seat(const ProxyPlace& place, const Vec3& p, const RuntimeSettings& settings) {
  const bool in_tet = place.state == ProxyState::Tet && place.tet >= 0 &&
                      place.tet < space_->mesh().tet_count() && !space_->tet_is_rigid(place.tet);
  const bool outside = place.state == ProxyState::Outside && place.tet == kNoTet;
  if (!(in_tet || outside) || place.local != 0 || !is_finite(place.q)) return false;
  place_ = place;
  force_N_ = spring_force(p, settings, nullptr);
  return true;
}

// (b-2) of TET and FACE, and EDGE's (b) short of the edge's ends: q moved
// within its tet, face or edge and stopped where the material put it. Called
// again, the material (same target, q now at its answer) holds q, and FACE's
// and EDGE's (a) tests see the same n . (p - q), since q moved in the plane
// or along the edge: nothing would change, so the tick ends here. State,
// owner and local index stay; only q moves.
Proxy::Outcome Proxy::settle_at(const Vec3& q) {
  const double tolerance = space_->tolerance();
  const bool changed = !within_tolerance(q - place_.q, tolerance);
  place_.q = q;
  return changed ? Outcome::Settled : Outcome::Unchanged;
}

Proxy::Outcome Proxy::go(ProxyState to, std::int32_t tet, int local, const Vec3& q) {
  const double tolerance = space_->tolerance();
  const bool changed = to != place_.state || tet != place_.tet || local != place_.local ||
                       !within_tolerance(q - place_.q, tolerance);
  place_ = {to, tet, static_cast<std::int8_t>(local), q};
  return changed ? Outcome::Changed : Outcome::Unchanged;
}

StartKind Proxy::reset(const Vec3& p) {
  if (!is_finite(p)) throw std::invalid_argument("proxy start point is not finite");
  if (!space_->in_workspace(p)) {
    throw std::invalid_argument("proxy start point (" + std::to_string(p.x) + ", " +
                                std::to_string(p.y) + ", " + std::to_string(p.z) +
                                ") mm is outside the scene's workspace");
  }
  const TetMesh& mesh = space_->mesh();
  force_N_ = {};
  finished_force_N_ = {};
  unfinished_in_row_ = 0;
  last_p_ = p;
  has_last_p_ = true;
  const std::int32_t t = mesh.locate(p);
  if (t == kNoTet) {
    place_ = {ProxyState::Outside, kNoTet, 0, p};
    return StartKind::Outside;
  }
  if (!space_->tet_is_rigid(t)) {
    place_ = {ProxyState::Tet, t, 0, p};
    return StartKind::InsideTet;
  }
  return push_out_of_rigid(t, p);
}

// A start inside rigid material: the proxy goes to the nearest point of the
// rigid region's boundary (searched over the connected rigid tets), so the
// first force pushes the hand out of the bone, as touching it would.
StartKind Proxy::push_out_of_rigid(std::int32_t start_tet, const Vec3& p) {
  const TetMesh& mesh = space_->mesh();
  std::vector<std::int32_t> queue{start_tet};
  std::vector<std::uint8_t> seen(mesh.tet_count(), 0);
  seen[start_tet] = 1;
  double best_distance = 1e300;
  ProxyPlace best;
  for (std::size_t k = 0; k < queue.size(); ++k) {
    const std::int32_t t = queue[k];
    for (int f = 0; f < 4; ++f) {
      const std::int32_t u = mesh.neighbour(t, f);
      if (u != kNoTet && space_->tet_is_rigid(u)) {
        if (!seen[u]) {
          seen[u] = 1;
          queue.push_back(u);
        }
        continue;
      }
      std::array<Vec3, 3> corner;
      int n = 0;
      for (int v = 0; v < 4; ++v) {
        if (v != f) corner[n++] = mesh.vertex(mesh.tet(t)[v]);
      }
      const Vec3 c = closest_point_on_triangle(p, corner[0], corner[1], corner[2]);
      const double d = norm(c - p);
      if (d < best_distance) {
        best_distance = d;
        best = u == kNoTet ? ProxyPlace{ProxyState::Outside, kNoTet, 0, c}
                           : ProxyPlace{ProxyState::Face, u,
                                        static_cast<std::int8_t>(mesh.neighbour_face(t, f)), c};
      }
    }
  }
  place_ = best;
  force_N_ = (place_.q - p) * space_->settings().stiffness_N_per_mm;
  finished_force_N_ = force_N_;
  return StartKind::PushedOutOfRigid;
}

TickResult Proxy::step(const Vec3& p, double dt_s) {
  return step(p, dt_s, space_->runtime_settings());
}

TickResult Proxy::step(const Vec3& p, double dt_s, const RuntimeSettings& settings,
                       const ForceShading* shading, const CutState* cuts) {
  TickResult result;
  ++counters_.ticks;
  if (!is_finite(p) || !space_->in_workspace(p) || !settings.valid()) {
    reject_input(is_finite(p) && !space_->in_workspace(p), result);
    return result;
  }
  tick(p, dt_s, settings, settings.max_transitions_per_tick, shading, false, result, cuts);
  return result;
}

void Proxy::reject_input(bool out_of_workspace, TickResult& result) {
  ++counters_.rejected_inputs;
  counters_.out_of_workspace_inputs += out_of_workspace ? 1 : 0;
  force_N_ = {};
  finished_force_N_ = {};
  result.rejected = true;
}

MoveContext Proxy::context_for(const Vec3& p, double dt_s, const RuntimeSettings& settings,
                               const CutState* cuts) const {
  MoveContext context;
  context.cuts = cuts;
  context.stiffness_N_per_mm = settings.stiffness_N_per_mm;
  context.tolerance_mm = space_->tolerance();
  if (space_->uses_speed() && has_last_p_ && dt_s > 0.0 && std::isfinite(dt_s)) {
    context.target_speed_mm_per_s = norm(p - last_p_) / dt_s;
  }
  return context;
}

// Out of line, with the loop and the tick's end inline: a point the settles
// decline makes one call (docs/decisions.md, "Build tuning and the hot path").
void Proxy::walk(const Vec3& p, double dt_s, const RuntimeSettings& settings, int limit,
                 const ForceShading* shading, bool keep_capped_open, TickResult& result,
                 const CutState* cuts) {
  const MoveContext context = context_for(p, dt_s, settings, cuts);
  int transitions = result.transitions;  // A local: no store-to-load round trip per transition.
  bool capped = false;
  for (;;) {
    if (transitions >= limit) {
      // The cap is exact: capped only if one more transition would still
      // change something. That probe is undone; the next walk redoes it.
      const ProxyPlace before = place_;
      if (advance(p, context) != Outcome::Unchanged) {
        place_ = before;
        capped = true;
      }
      break;
    }
    const ProxyState from = place_.state;
    const std::int32_t from_tet = place_.tet;
    const Outcome outcome = advance(p, context);
    if (outcome == Outcome::Unchanged) break;
    ++transitions;
    ++counters_.transitions[static_cast<int>(from)][static_cast<int>(place_.state)]
                           [is_neighbour(from_tet, place_.tet)];
    if (outcome == Outcome::Settled) break;
  }
  result.transitions = transitions;
  result.capped = capped;
  if (!capped || !keep_capped_open) end_tick(p, result, settings, shading);
}

void Proxy::defer_tick(TickResult& result, const RuntimeSettings& settings) {
  ++counters_.deferred_ticks;
  result.deferred = true;
  hold_force(settings);
}

void Proxy::hold_force(const RuntimeSettings& settings) {
  // force_N_ still holds the last finished tick's force when the first unfinished one begins.
  if (unfinished_in_row_ == 0) finished_force_N_ = force_N_;
  ++unfinished_in_row_;
  Vec3 held = finished_force_N_;
  const double magnitude = norm(held);
  if (unfinished_in_row_ > 1 && magnitude > settings.capped_tick_force_N) {
    held = held * (settings.capped_tick_force_N / magnitude);
  }
  force_N_ = held;
}

Transition Proxy::transition(const Vec3& p, const MoveContext& context) {
  const ProxyPlace before = place_;
  const Outcome outcome = advance(p, context);
  Transition result;
  result.from = before.state;
  result.to = place_.state;
  result.to_neighbour = is_neighbour(before.tet, place_.tet);
  result.changed = outcome != Outcome::Unchanged;
  result.settled = outcome == Outcome::Settled;
  return result;
}

Proxy::Outcome Proxy::advance(const Vec3& p, const MoveContext& context) {
  switch (place_.state) {
    case ProxyState::Tet:
      return step_tet(p, context);
    case ProxyState::Face:
      return step_face(p, context);
    case ProxyState::Edge:
      return step_edge(p, context);
    case ProxyState::Vertex:
      return step_vertex(p, context);
    case ProxyState::Outside:
      return step_outside(p);
  }
  return Outcome::Unchanged;
}

// TET: (a) nothing widens; (b-1) move; (b-2) stay inside; (b-3) stop on the
// nearest exit face (eqs. 2-4 with repair 1, docs/method.md).
Proxy::Outcome Proxy::step_tet(const Vec3& p, const MoveContext& context) {
  const TetMesh& mesh = space_->mesh();
  const std::int32_t t = place_.tet;
  const Vec3 q = place_.q;
  const MoveResult moved = move(space_->material_of_tet(t, context.cuts), p, q, context);
  if (!moved.moved) return Outcome::Unchanged;
  const Exit exit = find_tet_exit(mesh, t, q, moved.q, context.tolerance_mm);
  if (exit.face < 0) return settle_at(moved.q);
  // The FACE step next looks into the neighbour behind the exit face.
  const std::int32_t behind = mesh.neighbour(t, exit.face);
  if (behind != kNoTet) space_->prefetch_tet(behind);
  return go(ProxyState::Face, t, exit.face, q + (moved.q - q) * exit.parameter);
}

// FACE: (a-1) toward the outside of the owner (eq. 5): into the neighbour or
// OUTSIDE; (a-2) back into the owner; else (b), slide_on_face.
Proxy::Outcome Proxy::step_face(const Vec3& p, const MoveContext& context) {
  const TetMesh& mesh = space_->mesh();
  const std::int32_t t = place_.tet;
  const int face = place_.local;
  const Vec3 q = place_.q;
  const Plane& plane = mesh.face_plane(t, face);
  const double eps = context.tolerance_mm;
  const Material& material = space_->material_of_tet(t, context.cuts);
  if (strictly_beyond(dot(plane.normal, p - q), eps)) {
    const std::int32_t u = mesh.neighbour(t, face);
    // Leaving the mesh keeps q (docs/method.md, repair 3).
    if (u == kNoTet) return go(ProxyState::Outside, kNoTet, 0, q);
    // A rigid neighbour refuses at once (the common case of a slide on bone).
    if (!space_->tet_is_rigid(u) &&
        move(space_->material_of_tet(u, context.cuts), p, q, context).moved) {
      return go(ProxyState::Tet, u, 0, q);
    }
  } else if (move(material, p, q, context).moved) {
    return go(ProxyState::Tet, t, 0, q);
  }
  return slide_on_face(p, context);
}

// FACE's (b): the slide to p projected on the plane (eq. 6), stopping on the
// nearest edge, or where the material stops it.
[[gnu::always_inline]] inline Proxy::Outcome Proxy::slide_on_face(const Vec3& p,
                                                                  const MoveContext& context) {
  const TetMesh& mesh = space_->mesh();
  const std::int32_t t = place_.tet;
  const int face = place_.local;
  const Vec3 q = place_.q;
  const double eps = context.tolerance_mm;
  const Vec3 target = project_to_plane(p, mesh.face_plane(t, face));
  const MoveResult moved = move(space_->material_of_tet(t, context.cuts), target, q, context);
  if (!moved.moved) return Outcome::Unchanged;
  const Exit exit = find_face_exit(mesh, t, face, q, moved.q, eps);
  if (exit.face < 0) {
    // The slide ended on an edge of the face, its target not strictly back
    // inside: the edge's fan decides (a FACE held on the edge line never sees
    // the free tets around the edge, and would hold still there).
    if (exit.touching >= 0) {
      const Plane& side = mesh.face_plane(t, exit.touching);
      if (slide_reaches_edge(side.signed_distance(moved.q), dot(target - q, side.normal), eps)) {
        const int local_edge = kEdgeOfFaces[face][exit.touching];
        const std::int32_t e = mesh.edge_of(t, local_edge);
        space_->prefetch_edge_fan(t, local_edge);
        return go(ProxyState::Edge, t, local_edge,
                  project_to_line(moved.q, mesh.vertex(mesh.edge_vertices(e)[0]),
                                  mesh.edge_direction(e)));
      }
    }
    return settle_at(moved.q);
  }
  const int local_edge = kEdgeOfFaces[face][exit.face];
  space_->prefetch_edge_fan(t, local_edge);
  return go(ProxyState::Edge, t, local_edge, q + (moved.q - q) * exit.parameter);
}

// EDGE: (a-1) into a tet of the fan whose wedge holds p (eq. 7); (a-2) out
// of the mesh only from a boundary edge when p is outside every closed wedge
// (docs/method.md, repair 2); (a-3) onto the fan face the projected target moves furthest
// along (eq. 8); else (b), slide_along_edge.
Proxy::Outcome Proxy::step_edge(const Vec3& p, const MoveContext& context) {
  const TetMesh& mesh = space_->mesh();
  const std::int32_t t = place_.tet;
  const int local_edge = place_.local;
  const std::int32_t e = mesh.edge_of(t, local_edge);
  const Vec3 q = place_.q;
  const Vec3 d = p - q;
  const double eps = context.tolerance_mm;
  if (within_tolerance(d, eps)) return Outcome::Unchanged;
  const auto fan = mesh.edge_fan_of(t, local_edge);

  // One pass over the fan, as in step_vertex: (a-1) returns at once; the
  // (a-2) verdict and the best (a-3) candidate are gathered on the way.
  const double d_squared = squared_norm(d);
  bool any_toward = false;
  bool outside_every_wedge = true;
  // (a-2) is asked only on a boundary edge: round an inner edge a rigid tet
  // has nothing to give, and its planes are not even read (a slide round a
  // bone inside flesh reads only the fan's soft tets).
  const bool boundary = mesh.is_boundary_edge(e);
  Candidate best;
  for (const EdgeFanEntry& entry : fan) {
    if (!boundary && space_->tet_is_rigid(entry.tet)) continue;
    const std::array<const Plane*, 2> planes{&mesh.face_plane(entry.tet, entry.faces[0]),
                                             &mesh.face_plane(entry.tet, entry.faces[1])};
    const std::array<double, 2> along{dot(d, planes[0]->normal), dot(d, planes[1]->normal)};
    outside_every_wedge = outside_every_wedge && points_strictly_out_of(along, eps);
    const bool toward = points_strictly_into(along, eps);
    any_toward = any_toward || toward;
    // A rigid tet refuses every move: it can neither take the proxy (a-1)
    // nor offer a face to slide on (a-3), so only its (a-2) test counts.
    if (space_->tet_is_rigid(entry.tet)) continue;
    const Material& material = space_->material_of_tet(entry.tet, context.cuts);
    if (toward && move(material, p, q, context).moved) return go(ProxyState::Tet, entry.tet, 0, q);
    const double normals_dot = dot(planes[0]->normal, planes[1]->normal);
    for (int side = 0; side < 2; ++side) {
      // Eq. (8) on p' = p - n sd(p): (p' - q) . n_other = d . n_other - sd(p) (n . n_other).
      const double height = planes[side]->signed_distance(p);
      if (!projected_strictly_into(along[1 - side], height, normals_dot, eps)) continue;
      const double score =
          std::sqrt(std::max(0.0, d_squared - 2.0 * height * along[side] + height * height));
      if (score > best.score &&
          move(material, p - planes[side]->normal * height, q, context).moved) {
        best = {ProxyState::Face, entry.tet, entry.faces[side], score};
      }
    }
  }
  if (!any_toward && outside_every_wedge && boundary) {
    return go(ProxyState::Outside, kNoTet, 0, q);
  }
  if (best.tet != kNoTet) {
    mesh.prefetch_fan_ranges(best.tet);  // A slide on goes on to one of its edges.
    return go(best.state, best.tet, best.local, q);
  }
  return slide_along_edge(p, context);
}

// EDGE's (b): the slide to p projected on the line (eq. 9), stopping at an
// end (eq. 10), or where the material stops it.
[[gnu::always_inline]] inline Proxy::Outcome Proxy::slide_along_edge(const Vec3& p,
                                                                     const MoveContext& context) {
  const TetMesh& mesh = space_->mesh();
  const std::int32_t t = place_.tet;
  const std::int32_t e = mesh.edge_of(t, place_.local);
  const Vec3 q = place_.q;
  const auto& ends = mesh.edge_vertices(e);
  const Vec3& direction = mesh.edge_direction(e);
  const Vec3& o0 = mesh.vertex(ends[0]);
  const MoveResult moved =
      move(space_->material_of_tet(t, context.cuts), project_to_line(p, o0, direction), q, context);
  if (!moved.moved) return Outcome::Unchanged;
  if (beyond_edge_start(moved.q, o0, direction)) {
    return go(ProxyState::Vertex, t, local_index_of(mesh.tet(t), ends[0]), o0);
  }
  const Vec3& o1 = mesh.vertex(ends[1]);
  if (beyond_edge_end(moved.q, o1, direction)) {
    return go(ProxyState::Vertex, t, local_index_of(mesh.tet(t), ends[1]), o1);
  }
  // (b) ended on the line, short of its ends: the tick ends here, as after a
  // move within a tet or face (docs/decisions.md, "Ending a tick"). Called
  // again, every fan test reads the same d . n (q moved along the edge, every
  // fan normal is normal to it), and q' is nearer than q to p and to each
  // projected target, so every move that refused still refuses.
  return settle_at(moved.q);
}

// VERTEX: (a-1) into a tet whose corner cone holds p (eq. 11); (a-2) out of
// the mesh only from a boundary vertex, p outside every closed cone
// (docs/method.md, repair 2); (a-3) onto the face (eq. 12) or edge (eq. 13, sign fixed) the
// projected target moves furthest along; (b) no motion of its own.
Proxy::Outcome Proxy::step_vertex(const Vec3& p, const MoveContext& context) {
  const TetMesh& mesh = space_->mesh();
  const std::int32_t vertex = mesh.tet(place_.tet)[place_.local];
  const Vec3 q = place_.q;
  const Vec3 d = p - q;
  const double eps = context.tolerance_mm;
  const double d_squared = squared_norm(d);
  if (within_tolerance(d, eps)) return Outcome::Unchanged;

  // One pass over the fan: (a-1) returns at once; the (a-2) verdict and the
  // best (a-3) candidate are gathered on the way and used only if no tet
  // takes the proxy (move functions are pure, so an unused call is harmless).
  bool any_toward = false;
  bool outside_every_cone = true;
  // (a-2) is asked only at a boundary vertex: elsewhere a rigid tet is skipped
  // before its planes are read, as in step_edge.
  const bool boundary = mesh.is_boundary_vertex(vertex);
  Candidate best;
  for (const VertexFanEntry& entry : mesh.vertex_fan(vertex)) {
    if (!boundary && space_->tet_is_rigid(entry.tet)) continue;
    const int corner = entry.local_vertex;
    std::array<int, 3> faces{};
    std::array<const Plane*, 3> planes{};
    std::array<double, 3> along{};  // d . n_f for the three faces through the vertex.
    for (int k = 0, f = 0; f < 4; ++f) {
      if (f == corner) continue;
      faces[k] = f;
      planes[k] = &mesh.face_plane(entry.tet, f);
      along[k] = dot(d, planes[k]->normal);
      ++k;
    }
    const bool toward = points_strictly_into(along, eps);
    outside_every_cone = outside_every_cone && points_strictly_out_of(along, eps);
    any_toward = any_toward || toward;
    // A rigid tet refuses every move: no (a-1) tet, no (a-3) face or edge.
    if (space_->tet_is_rigid(entry.tet)) continue;
    const Material& material = space_->material_of_tet(entry.tet, context.cuts);
    if (toward && move(material, p, q, context).moved) return go(ProxyState::Tet, entry.tet, 0, q);
    for (int m = 0; m < 3; ++m) {
      // Eq. (12) on p' = p - n_m sd_m(p), without forming p' unless it wins:
      // (p' - q) . n_g = d . n_g - sd_m(p) (n_m . n_g).
      const double height = planes[m]->signed_distance(p);
      bool inside_wedge = true;
      for (int g = 0; g < 3 && inside_wedge; ++g) {
        if (g == m) continue;
        inside_wedge = projected_strictly_into(along[g], height,
                                               dot(planes[m]->normal, planes[g]->normal), eps);
      }
      if (!inside_wedge) continue;
      const double score =
          std::sqrt(std::max(0.0, d_squared - 2.0 * height * along[m] + height * height));
      if (score > best.score && move(material, p - planes[m]->normal * height, q, context).moved) {
        best = {ProxyState::Face, entry.tet, faces[m], score};
      }
    }
    for (int other = 0; other < 4; ++other) {
      if (other == corner) continue;
      const int local_edge = kEdgeOfVertices[corner][other];
      const std::int32_t e = mesh.edge_of(entry.tet, local_edge);
      // Eq. (13) with the sign fixed: a_j points from the vertex along the edge.
      const Vec3 along_edge =
          mesh.edge_vertices(e)[0] == vertex ? mesh.edge_direction(e) : -mesh.edge_direction(e);
      const double score = dot(d, along_edge);
      if (!strictly_beyond(score, eps) || score <= best.score) continue;
      if (move(material, q + along_edge * score, q, context).moved) {
        best = {ProxyState::Edge, entry.tet, local_edge, score};
      }
    }
  }
  if (!any_toward && outside_every_cone && boundary) {
    return go(ProxyState::Outside, kNoTet, 0, q);
  }
  if (best.tet != kNoTet) return go(best.state, best.tet, best.local, q);
  return Outcome::Unchanged;
}

// OUTSIDE: q' = p unless q->p enters through a boundary triangle (eq. 14,
// repairs 3 and 4); the nearest entry wins. The boundary tree makes this
// logarithmic in the number of boundary faces rather than linear. The search
// runs on q->p clipped to the reach box, exact for any finite p and q;
// see enter_beyond.
Proxy::Outcome Proxy::step_outside(const Vec3& p) {
  const Vec3& q = place_.q;
  // In free air beside the mesh (most OUTSIDE steps): no entry, and p is
  // outside the mesh, so q follows it; what the search below would find.
  // Both box tests on the segment's own box: six min/max, then twelve compares.
  const Aabb segment_bounds = segment_box(q, p);
  if (box_beyond_face(segment_bounds, entry_box_)) return go(ProxyState::Outside, kNoTet, 0, p);
  if (box_holds_box(reach_box_, segment_bounds)) return enter_beyond(q, p, p, 0.0, 0);
  const ClippedSegment segment = clip_far_segment_to_box(q, p, reach_box_);
  if (!segment.hits) return leave_outside(p);
  return enter_beyond(segment.start, segment.end, p, 0.0, 0);
}

// The nearest entry of q->end at parameter `lowest` or beyond. Rim hits are
// resolved nearest first: a rim the segment passes by outside
// sends the search on beyond it, up to kRimPassesMax rims; then the safety
// net. One function with the search inline: a separate search returning a
// record is a sizeable share of an OUTSIDE step on a small mesh
// (docs/decisions.md, "Entering the mesh from OUTSIDE").
Proxy::Outcome Proxy::enter_beyond(const Vec3& q, const Vec3& end, const Vec3& p, double lowest,
                                   int rims_passed) {
  const TetMesh& mesh = space_->mesh();
  const Vec3 d = end - q;
  const double eps = space_->tolerance();
  double best_parameter = 2.0;
  FaceRef best_face;
  // Repair 4 (docs/method.md): a path exactly through a boundary edge or vertex meets the
  // triangles there only on their rims, heading away from their own tets. The
  // nearest such rim hit is kept and resolved below against the whole fan.
  double rim_parameter = 2.0;
  FaceRef rim_face;
  std::array<int, 2> rim_sides{-1, -1};
  const auto& faces = mesh.boundary_faces();
  // Tests boundary face k, which q->end crosses at parameter s (eq. 14).
  auto try_face_at = [&](std::int32_t k, double s) {
    if (s < lowest || (s >= best_parameter && s >= rim_parameter)) return;
    const FaceRef& face = faces[k];
    const Vec3 c = q + d * s;
    std::array<int, 2> on_rim{-1, -1};
    bool heading_away = false;
    const Plane* sides = mesh.boundary_side_planes(static_cast<std::size_t>(k));
    for (int j = 0; j < 3; ++j) {
      const Plane& side = sides[j];
      const RimSide where = side_of_rim(side.signed_distance(c), eps);
      if (where == RimSide::Outside) return;  // Outside the triangle (eq. 14, "<= eps").
      if (where == RimSide::OnRim) {
        on_rim[on_rim[0] < 0 ? 0 : 1] = kOtherFaces[face.face][j];
        heading_away = heading_away || strictly_beyond(dot(d, side.normal), eps);
      }
    }
    if (!heading_away) {
      if (s < best_parameter) {
        best_parameter = s;
        best_face = face;
      }
    } else if (s < rim_parameter) {
      rim_parameter = s;
      rim_face = face;
      rim_sides = on_rim;
    }
  };
  auto try_face = [&](std::int32_t k) {
    const Plane& plane = mesh.boundary_plane(static_cast<std::size_t>(k));
    try_face_at(k,
                segment_entry_parameter(plane.signed_distance(q), plane.signed_distance(end), eps));
  };
  // A handful of boundary faces (the paper's cube has 12) is scanned faster
  // than the tree is walked; above that the tree keeps entry logarithmic.
  if (faces.size() <= kLinearEntryScanMax) {
    // Signed distances of q and end to every boundary plane in one vectorizable
    // pass; only a face that q is in front of and end behind is looked at further.
    const auto& column = mesh.boundary_plane_columns();
    const std::size_t n = faces.size();
    std::array<double, kLinearEntryScanMax> before;  // NOLINT: filled below, first n used.
    std::array<double, kLinearEntryScanMax> behind;  // NOLINT: filled below, first n used.
    for (std::size_t k = 0; k < n; ++k) {
      const double offset = column[3][k];
      before[k] = column[0][k] * q.x + column[1][k] * q.y + column[2][k] * q.z - offset;
      behind[k] = column[0][k] * end.x + column[1][k] * end.y + column[2][k] * end.z - offset;
    }
    // Every plane q->end enters through gets the triangle test, in scan
    // order: try_face_at keeps the nearest clean hit and the nearest rim hit
    // short of it, and skips a plane beyond both, as the tree's order does.
    // No sort nearest first: on a convex box the entry is the farthest of up
    // to three planes, so a sort would save no triangle test.
    for (std::size_t k = 0; k < n; ++k) {
      const double s = segment_entry_parameter(before[k], behind[k], eps);
      if (s >= 0.0) try_face_at(static_cast<std::int32_t>(k), s);
    }
  } else {
    mesh.boundary_tree().for_each_on_segment(q, end, eps, try_face);
  }
  if (rim_face.tet != kNoTet && rim_parameter < best_parameter) {
    const Outcome entered = enter_through_rim(rim_face, rim_sides, q + d * rim_parameter, p);
    if (entered != Outcome::Unchanged) return entered;
    // Passed by outside there: entries beyond it (a nearer face hit would have won).
    if (rims_passed + 1 < kRimPassesMax) {
      return enter_beyond(q, end, p, std::nextafter(rim_parameter, 3.0), rims_passed + 1);
    }
  }
  if (best_face.tet != kNoTet) {
    return go(ProxyState::Face, best_face.tet, best_face.face, q + d * best_parameter);
  }
  return leave_outside(p);
}

// The safety net: q = p only where p is not inside the mesh. Where an entry
// was missed, q holds outside: a push back, never a walk through bone.
[[gnu::always_inline]] inline Proxy::Outcome Proxy::leave_outside(const Vec3& p) {
  if (box_holds(mesh_box_, p) && lies_in_mesh_interior(space_->mesh(), p, space_->tolerance())) {
    return Outcome::Unchanged;
  }
  return go(ProxyState::Outside, kNoTet, 0, p);
}

// The segment meets boundary face `face` at c on its rim (one side: an edge;
// two: a vertex). The closed-cone rule of repair 2 (docs/method.md), at the rim, so a path
// along an inner face plane cannot fall through into rigid material:
// the proxy lands on the vertex or edge unless p - (that vertex or edge
// point) points strictly out of every closed cone (eq. 11) or wedge (eq. 7)
// around it; the landed state's own step, which applies the same test to the
// same p - q, then takes it on. A direction along a face plane between two
// tets is in their closed cones, so it does not pass into the mesh
// (docs/decisions.md, "Entering through the rim").
Proxy::Outcome Proxy::enter_through_rim(const FaceRef& face, const std::array<int, 2>& sides,
                                        const Vec3& c, const Vec3& p) {
  const TetMesh& mesh = space_->mesh();
  const double eps = space_->tolerance();
  if (sides[1] >= 0) {
    const int corner = 6 - face.face - sides[0] - sides[1];
    const std::int32_t vertex = mesh.tet(face.tet)[corner];
    const Vec3& o = mesh.vertex(vertex);
    const Vec3 d = p - o;
    for (const VertexFanEntry& entry : mesh.vertex_fan(vertex)) {
      std::array<double, 3> along{};
      for (int k = 0, f = 0; f < 4; ++f) {
        if (f != entry.local_vertex) along[k++] = dot(d, mesh.face_plane(entry.tet, f).normal);
      }
      if (!points_strictly_out_of(along, eps)) {
        return go(ProxyState::Vertex, face.tet, corner, o);
      }
    }
    return Outcome::Unchanged;
  }
  const int local_edge = kEdgeOfFaces[face.face][sides[0]];
  const std::int32_t e = mesh.edge_of(face.tet, local_edge);
  const Vec3 on_edge =
      project_to_line(c, mesh.vertex(mesh.edge_vertices(e)[0]), mesh.edge_direction(e));
  const Vec3 d = p - on_edge;
  for (const EdgeFanEntry& entry : mesh.edge_fan(e)) {
    const std::array<double, 2> along{dot(d, mesh.face_plane(entry.tet, entry.faces[0]).normal),
                                      dot(d, mesh.face_plane(entry.tet, entry.faces[1]).normal)};
    if (!points_strictly_out_of(along, eps)) {
      return go(ProxyState::Edge, face.tet, local_edge, on_edge);
    }
  }
  return Outcome::Unchanged;
}

std::string Proxy::check_invariants(double tolerance_factor) const {
  const TetMesh& mesh = space_->mesh();
  const double tol = tolerance_factor * space_->tolerance();
  const Vec3& q = place_.q;
  if (!is_finite(q)) return "q is not finite";
  if (!is_finite(force_N_)) return "force is not finite";
  // The promise first: never inside rigid material, whatever the state says.
  std::int32_t rigid = kNoTet;
  mesh.tet_tree().for_each_containing(q, 0.0, [&](std::int32_t u) {
    if (rigid == kNoTet && space_->tet_is_rigid(u) && mesh.outside_distance(u, q) < -tol) rigid = u;
  });
  if (rigid != kNoTet) return "q inside rigid tet " + std::to_string(rigid);
  const std::int32_t t = place_.tet;
  switch (place_.state) {
    case ProxyState::Tet:
      if (mesh.outside_distance(t, q) > tol) return "TET: q outside its tet";
      if (space_->tet_is_rigid(t)) return "TET: owner tet is rigid";
      break;
    case ProxyState::Face: {
      if (std::abs(mesh.face_plane(t, place_.local).signed_distance(q)) > tol) {
        return "FACE: q off its face plane";
      }
      if (mesh.outside_distance(t, q) > tol) return "FACE: q outside its triangle";
      break;
    }
    case ProxyState::Edge: {
      const std::int32_t e = mesh.edge_of(t, place_.local);
      const Vec3& o0 = mesh.vertex(mesh.edge_vertices(e)[0]);
      const Vec3& o1 = mesh.vertex(mesh.edge_vertices(e)[1]);
      const Vec3& a = mesh.edge_direction(e);
      if (norm(project_to_line(q, o0, a) - q) > tol) return "EDGE: q off its edge line";
      const double s = dot(q - o0, a);
      if (s < -tol || s > norm(o1 - o0) + tol) return "EDGE: q beyond its edge's ends";
      break;
    }
    case ProxyState::Vertex:
      if (norm(mesh.vertex(mesh.tet(t)[place_.local]) - q) > tol) return "VERTEX: q off its vertex";
      break;
    case ProxyState::Outside:
      // On the boundary is fine (a proxy leaving through a face keeps q there,
      // docs/method.md, repair 3); inside, even exactly on an inner face or vertex, is not.
      if (lies_in_mesh_interior(mesh, q, tol)) {
        return "OUTSIDE: q inside the mesh, farther than the tolerance from its boundary";
      }
      break;
  }
  return "";
}

}  // namespace hapticut
