#include "hapticut/blade.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "hapticut/geometry.h"

namespace hapticut {

namespace {

// The same tet, and the same face, edge or vertex of it.
bool same_place(const ProxyPlace& a, const ProxyPlace& b) {
  return a.state == b.state && a.tet == b.tet && a.local == b.local;
}

const char* pose_check_message(PoseCheck check) {
  switch (check) {
    case PoseCheck::Fine:
      return "";
    case PoseCheck::NotFinite:
      return "blade pose is not finite";
    case PoseCheck::ZeroRotation:
      return "blade rotation quaternion has (near) zero norm";
    case PoseCheck::OutOfWorkspace:
      return "a blade point is outside the scene's workspace";
  }
  return "?";
}

PoseCheck check_rotation(const Pose& pose) {
  const Quaternion& r = pose.rotation;
  if (!is_finite(pose.position_mm) || !std::isfinite(r.w) || !std::isfinite(r.x) ||
      !std::isfinite(r.y) || !std::isfinite(r.z)) {
    return PoseCheck::NotFinite;
  }
  return r.valid() ? PoseCheck::Fine : PoseCheck::ZeroRotation;
}

// Points all lie in the Space's workspace exactly when it holds both ends of
// their segment: the workspace is a box, and every a + s b with s in [0, 1]
// rounds to within the ends' box (rounding is monotonic, and 1.0 * b is b).
inline PoseCheck ends_check(const Space& space, const Vec3& a, const Vec3& b) {
  const Aabb box = segment_box(a, a + b);
  return space.in_workspace(box.lo) && space.in_workspace(box.hi) ? PoseCheck::Fine
                                                                  : PoseCheck::OutOfWorkspace;
}

}  // namespace

Blade::Blade(std::shared_ptr<const Space> space, const BladeSpec& spec,
             std::shared_ptr<const ForceShading> shading, std::shared_ptr<CutState> cuts)
    : space_(std::move(space)), shading_(std::move(shading)), cuts_(std::move(cuts)) {
  if (!space_) throw std::invalid_argument("a Blade needs a Space");
  if (spec.points < 1 || spec.points > kMaxPoints) {
    throw std::invalid_argument("a blade has 1.." + std::to_string(kMaxPoints) + " points, got " +
                                std::to_string(spec.points));
  }
  if (!is_finite(spec.start_mm) || !is_finite(spec.end_mm)) {
    throw std::invalid_argument("blade '" + spec.name + "': start_mm and end_mm must be finite");
  }
  if (!shading_) shading_ = std::make_shared<const ForceShading>(*space_);
  if (!cuts_) cuts_ = std::make_shared<CutState>(space_);
  if (&cuts_->space() != space_.get()) {
    throw std::invalid_argument("blade '" + spec.name + "': its CutState is another scene's");
  }
  has_cuttable_materials_ = std::any_of(space_->materials().begin(), space_->materials().end(),
                                        [](const Material& m) { return is_cuttable(m.model); });
  tool_start_ = spec.start_mm;
  tool_span_ = spec.end_mm - spec.start_mm;
  if (!is_finite(tool_span_)) {
    throw std::invalid_argument("blade '" + spec.name + "': end_mm - start_mm is not finite");
  }
  fractions_.reserve(spec.points);
  tool_points_.reserve(spec.points);
  for (int i = 0; i < spec.points; ++i) {
    const double s = spec.points == 1 ? 0.0 : double(i) / double(spec.points - 1);
    fractions_.push_back(s);
    tool_points_.push_back(tool_start_ + tool_span_ * s);
  }
  world_points_ = tool_points_;
  proxies_.assign(tool_points_.size(), Proxy(space_));
  point_ticks_.assign(tool_points_.size(), TickResult{});
  start_places_.assign(tool_points_.size(), ProxyPlace{});
  edge_walks_.assign(tool_points_.size(), EdgeWalk{});
  coupling_ = spec.coupling;
  orientation_ = spec.orientation;
  length_mm_ = norm(tool_span_);
  tool_direction_ = length_mm_ > 0.0 ? tool_span_ / length_mm_ : Vec3{1.0, 0.0, 0.0};
  if (coupling_ == BladeCoupling::Rigid) {
    rigid_ = std::make_unique<RigidEdge>(space_, fractions_, length_mm_);
    point_forces_.assign(tool_points_.size(), Vec3{});
    resisting_materials_ =
        std::any_of(space_->materials().begin(), space_->materials().end(), [](const Material& m) {
          return m.model != MaterialModel::Free && m.model != MaterialModel::Rigid;
        });
  }
  set_cut_memory(true);
}

void Blade::set_cut_memory(bool on) {
  read_cuts_ = on ? cuts_.get() : nullptr;
  cuttable_materials_ = on && has_cuttable_materials_;
  if (rigid_) rigid_->set_cuts(read_cuts_);
}

// Checks the pose and places the points; on a refused pose the proxies are
// untouched (world_points() then shows the refused sample). The check needs
// only the segment's two ends (ends_check); placing is one multiply-add per
// coordinate and point, a loop the compiler vectorises.
PoseCheck Blade::place_checked(const Pose& pose) {
  const PoseCheck check = check_rotation(pose);
  if (check != PoseCheck::Fine) return check;
  // q and -q are one rotation: the one nearer the last keeps what the blade
  // streams from flipping sign when a device's does.
  const Quaternion r = same_hemisphere(pose.rotation.normalized(), device_pose_.rotation);
  device_pose_ = {pose.position_mm, r};
  world_lever_ = r.rotate(tool_start_);
  world_span_ = r.rotate(tool_span_);
  const Vec3 a = pose.position_mm + world_lever_;
  const Vec3 b = world_span_;
  const double* s = fractions_.data();
  Vec3* world = world_points_.data();
  const std::size_t n = fractions_.size();
  for (std::size_t i = 0; i < n; ++i) world[i] = a + b * s[i];
  return ends_check(*space_, a, b);
}

PoseCheck Blade::check_pose(const Pose& pose) const {
  const PoseCheck check = check_rotation(pose);
  if (check != PoseCheck::Fine) return check;
  const Quaternion r = pose.rotation.normalized();
  return ends_check(*space_, pose.position_mm + r.rotate(tool_start_), r.rotate(tool_span_));
}

void Blade::reset(const Pose& pose) {
  const PoseCheck check = place_checked(pose);
  if (check != PoseCheck::Fine) throw std::invalid_argument(pose_check_message(check));
  for (std::size_t i = 0; i < proxies_.size(); ++i) proxies_[i].reset(world_points_[i]);
  std::fill(point_ticks_.begin(), point_ticks_.end(), TickResult{});
  std::fill(edge_walks_.begin(), edge_walks_.end(), EdgeWalk{});
  first_ = 0;
  tick_index_ = 0;
  last_tick_ = {};
  ideal_pose_ = device_pose_;
  if (coupling_ == BladeCoupling::Rigid) {
    rigid_->clear_sliding();
    orientation_ramp_s_ = 0.0;
    std::fill(point_forces_.begin(), point_forces_.end(), Vec3{});
    seated_ = rigid_->seat(device_edge());
    if (seated_) place_proxies_on_ideal(space_->runtime_settings());
  }
}

void Blade::set_orientation(BladeOrientation orientation, double ramp_s) {
  if (orientation == orientation_) return;
  orientation_ = orientation;
  orientation_ramp_s_ = std::isfinite(ramp_s) && ramp_s > 0.0 ? ramp_s : 0.0;
  orientation_ramp_elapsed_s_ = 0.0;
  if (rigid_) ramp_from_direction_ = rigid_->edge().direction;
}

Vec3 Blade::ideal_point(int i) const {
  return coupling_ == BladeCoupling::Rigid ? rigid_->points()[i] : proxies_[i].q();
}

Vec3 Blade::point_force(int i) const {
  return coupling_ == BladeCoupling::Rigid ? point_forces_[i] : proxies_[i].force_N();
}

void Blade::clear_counters() {
  counters_ = {};
  for (Proxy& p : proxies_) p.clear_counters();
}

BladeTick Blade::reject(bool out_of_workspace) {
  BladeTick tick;
  tick.rejected = true;
  ++counters_.rejected_ticks;
  counters_.out_of_workspace_ticks += out_of_workspace ? 1 : 0;
  for (std::size_t i = 0; i < proxies_.size(); ++i) {
    point_ticks_[i] = {};
    ++proxies_[i].counters_.ticks;
    proxies_[i].reject_input(out_of_workspace, point_ticks_[i]);
  }
  last_tick_ = tick;
  return tick;
}

BladeTick Blade::step(const Pose& pose, double dt_s) {
  return step(pose, dt_s, space_->runtime_settings());
}

// How many points ahead the first pass asks the cache for a point's tet.
constexpr std::size_t kPrefetchAhead = 4;

// The work budget (docs/decisions.md, "Work budget per tick"): a first pass
// gives each point up to max_transitions_per_tick of what is left, in a round
// robin that starts where the last tick left points unfinished; a second pass
// lets the points still capped go on with the rest. A point the budget does
// not reach keeps its place and its force and catches up next tick.
BladeTick Blade::step(const Pose& pose, double dt_s, const RuntimeSettings& settings) {
  ++tick_index_;
  ++counters_.ticks;
  if (!settings.valid()) return reject(false);
  const PoseCheck check = place_checked(pose);
  if (check != PoseCheck::Fine) return reject(check == PoseCheck::OutOfWorkspace);
  // A rejected tick (above) moves no point, so it cuts nothing.
  if (cuttable_materials_) {
    for (std::size_t i = 0; i < proxies_.size(); ++i) start_places_[i] = proxies_[i].place();
  }
  if (coupling_ == BladeCoupling::Rigid) {
    const BladeTick tick = step_rigid(dt_s, settings);
    cut_swept();
    return tick;
  }
  ideal_pose_ = device_pose_;
  const BladeTick tick = step_points(dt_s, settings);
  count(tick);
  cut_swept();
  return tick;
}

// A chord from outside the mesh is not walked: its way in through the
// mesh's boundary cuts what the point leaves behind in later ticks.
void Blade::cut_swept() {
  if (!cuttable_materials_) return;
  CutState& cuts = *cuts_;
  for (std::size_t i = 0; i < proxies_.size(); ++i) {
    const ProxyPlace& start = start_places_[i];
    const ProxyPlace& end = proxies_[i].place();
    // Most ticks: still in the same tet, or on the same face, edge or vertex
    // of it. Then the chord lies in that tet's closure (a tet is convex) and
    // the point has left nothing: nothing to cut, and nothing to compute.
    if (same_place(start, end)) continue;
    if (start.state != ProxyState::Outside) cuts.cut_along(start.tet, start.q, end.q);
    cuts.cut_left_behind(start, end.q);
  }
  // The edge between neighbouring points, measured against where it was
  // last walked: again once one of its ends has moved kEdgeWalkStep_mm or to
  // another place (walking every stretch every tick cost several times the
  // rest of the memory); a tet the stretch crossed and left within that step
  // is a sliver thinner than it. Nothing lies between two points in one tet.
  for (std::size_t i = 0; i + 1 < proxies_.size(); ++i) {
    EdgeWalk& walked = edge_walks_[i];
    const ProxyPlace& a1 = proxies_[i].place();
    const ProxyPlace& b1 = proxies_[i + 1].place();
    if (!walked.valid) walked = {start_places_[i], start_places_[i + 1], true};
    const double moved = std::max(norm(a1.q - walked.a.q), norm(b1.q - walked.b.q));
    if (moved < kEdgeWalkStep_mm && same_place(walked.a, a1) && same_place(walked.b, b1)) {
      continue;
    }
    if (walked.a.tet != walked.b.tet) cuts.cut_left_by_edge(walked.a, walked.b, a1, b1);
    walked = {a1, b1, true};
  }
}

BladeTick Blade::step_points(double dt_s, const RuntimeSettings& settings) {
  const std::size_t n = proxies_.size();
  int remaining = settings.blade_budget(static_cast<int>(n));
  const int cap = settings.max_transitions_per_tick;
  const ForceShading* shading = settings.force_shading ? shading_.get() : nullptr;
  const CutState* cuts = read_cuts_;
  BladeTick tick;
  Vec3 weighted_force;  // Sum of s_i f_i, for the torque.
  auto index = [&](std::size_t k) { return first_ + k < n ? first_ + k : first_ + k - n; };
  // A point's tick is over (finished, capped for good, or deferred): add its force.
  auto account = [&](std::size_t i) {
    const TickResult& r = point_ticks_[i];
    const Vec3 f = proxies_[i].force_N();
    tick.force_N += f;
    weighted_force += f * fractions_[i];
    tick.capped_points += r.capped || r.deferred ? 1 : 0;
    tick.deferred_points += r.deferred ? 1 : 0;
    tick.max_transitions = std::max(tick.max_transitions, r.transitions);
    tick.transitions += r.transitions;
  };
  int capped_in_first_pass = 0;
  // The point kPrefetchAhead places on has its tet asked for while this one
  // ticks: after a sleep the mesh is cold, and one point's misses then
  // overlap another's work instead of adding up (the first few are asked for here).
  std::size_t ahead = first_;
  for (std::size_t k = 0; k < std::min(kPrefetchAhead, n); ++k) {
    proxies_[ahead].prefetch_place();
    ahead = ahead + 1 == n ? 0 : ahead + 1;
  }
  for (std::size_t k = 0, i = first_; k < n; ++k, i = i + 1 == n ? 0 : i + 1) {
    proxies_[ahead].prefetch_place();
    ahead = ahead + 1 == n ? 0 : ahead + 1;
    TickResult& r = point_ticks_[i];
    r = {};
    Proxy& proxy = proxies_[i];
    ++proxy.counters_.ticks;
    if (remaining <= 0) {
      proxy.defer_tick(r, settings);
      account(i);
      continue;
    }
    // Inline (proxy.h): most points settle in the blade's own loop, without a call.
    proxy.tick(world_points_[i], dt_s, settings, std::min(cap, remaining), shading, true, r, cuts);
    remaining -= r.transitions;
    if (r.capped) {
      ++capped_in_first_pass;
      continue;
    }
    account(i);
  }
  for (std::size_t k = 0; k < n && capped_in_first_pass > 0; ++k) {
    const std::size_t i = index(k);
    TickResult& r = point_ticks_[i];
    if (!r.capped) continue;
    --capped_in_first_pass;
    Proxy& proxy = proxies_[i];
    const Vec3& p = world_points_[i];
    // Walks on with what the budget has left, then ends the tick, still capped or not.
    if (remaining > 0) {
      const int before = r.transitions;
      proxy.walk(p, dt_s, settings, before + remaining, shading, false, r, cuts);
      remaining -= r.transitions - before;
    } else {
      proxy.end_tick(p, r, settings, shading);
    }
    account(i);
  }
  // Sum of (p_i - origin) x f_i with p_i - origin = lever + s_i span.
  tick.torque_N_mm = cross(world_lever_, tick.force_N) + cross(world_span_, weighted_force);
  if (tick.capped_points > 0) {
    // The next tick starts at the first point left unfinished.
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = index(k);
      if (point_ticks_[i].capped || point_ticks_[i].deferred) {
        first_ = i;
        break;
      }
    }
  }
  return tick;
}

void Blade::count(const BladeTick& tick) {
  counters_.unfinished_ticks += tick.capped_points > 0 ? 1 : 0;
  counters_.capped_points += static_cast<std::uint64_t>(tick.capped_points);
  counters_.deferred_points += static_cast<std::uint64_t>(tick.deferred_points);
  counters_.total_transitions += static_cast<std::uint64_t>(tick.transitions);
  counters_.max_transitions_in_tick =
      std::max(counters_.max_transitions_in_tick, static_cast<std::uint32_t>(tick.transitions));
  counters_.rigid_rounds += static_cast<std::uint64_t>(tick.rigid_rounds);
  counters_.max_rigid_rounds_in_tick =
      std::max(counters_.max_rigid_rounds_in_tick, static_cast<std::uint32_t>(tick.rigid_rounds));
  counters_.unresolved_ticks += tick.unresolved ? 1 : 0;
  counters_.unseated_ticks += tick.unseated ? 1 : 0;
  last_tick_ = tick;
}

std::size_t Blade::snapshot(BladeSnapshotHeader& header, std::span<ProxySnapshot> points) const {
  const std::size_t count = std::min(points.size(), proxies_.size());
  for (std::size_t i = 0; i < count; ++i) {
    points[i] = {proxies_[i].place(), world_points_[i], point_force(static_cast<int>(i)),
                 point_ticks_[i]};
  }
  header.tick_index = tick_index_;
  header.tick = last_tick_;
  header.counters = counters_;
  header.point_count = static_cast<std::int32_t>(proxies_.size());
  header.points_written = static_cast<std::int32_t>(count);
  return count;
}

}  // namespace hapticut
