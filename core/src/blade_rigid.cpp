// The rigid coupling of a Blade (docs/decisions.md, "The rigid blade"): one
// ideal pose for the whole edge, solved by the Blade's RigidEdge
// (rigid_edge.h).
//
// One tick:
//  1. The point proxies, placed on the last ideal pose, tick toward their
//     device points as in the paper: where a resisting material (drag,
//     viscous, membrane) holds one back, its q is the spring's target t_i;
//     elsewhere t_i is the device point. A membrane a point reached without
//     breaking it is a wall for that point's walks, as bone is.
//  2. The RigidEdge solves the pose nearest the targets that the walks
//     verify, then applies friction.
//  3. Each proxy is seated on its point of that pose; force and torque are
//     the sums of the points' springs, q_i = x_i(ideal pose), shaded at the
//     contacts when the settings ask (RigidEdge::shade_force).
#include <algorithm>
#include <cmath>

#include "hapticut/blade.h"

namespace hapticut {

EdgePose Blade::device_edge() const {
  return {
      device_pose_.position_mm + world_lever_,
      length_mm_ > 0.0 ? world_span_ / length_mm_ : device_pose_.rotation.rotate(tool_direction_)};
}

// The tool pose of the ideal edge: the device's rotation turned (the least
// turn) from the device's edge direction onto the ideal one, so the roll
// about the edge is the device's; the origin where that rotation puts the
// edge's start on the ideal one.
void Blade::update_ideal_pose(const Pose& device) {
  const EdgePose& edge = rigid_->edge();
  const Vec3 device_direction = device.rotation.rotate(tool_direction_);
  const Quaternion turn = rotation_between(device_direction, edge.direction);
  const Quaternion rotation =
      same_hemisphere(multiply(turn, device.rotation).normalized(), ideal_pose_.rotation);
  ideal_pose_ = {edge.start_mm - rotation.rotate(tool_start_), rotation};
}

// Each proxy at its point of the ideal pose, in the tet that holds it (a TET
// state owned by a non-rigid tet, or OUTSIDE), with the point's force: the
// next tick's walks start there.
void Blade::place_proxies_on_ideal(const RuntimeSettings& settings) {
  const std::span<const Vec3> points = rigid_->points();
  const std::span<const std::int32_t> tets = rigid_->tets();
  for (std::size_t i = 0; i < proxies_.size(); ++i) {
    const std::int32_t t = tets[i];
    const ProxyPlace place{t == kNoTet ? ProxyState::Outside : ProxyState::Tet, t, 0, points[i]};
    // The edge's walks never leave a sample in a rigid tet; a refused place
    // would be a solver fault, and then the point pushes nothing.
    if (!proxies_[i].seat(place, world_points_[i], settings)) proxies_[i].release_force();
    point_forces_[i] = proxies_[i].force_N();
  }
}

BladeTick Blade::step_rigid(double dt_s, const RuntimeSettings& settings) {
  const std::size_t n = proxies_.size();
  const EdgePose device = device_edge();
  if (!seated_) {
    seated_ = rigid_->seat(device);
    if (!seated_) {
      BladeTick tick;
      tick.unseated = true;
      ideal_pose_ = device_pose_;
      std::fill(point_forces_.begin(), point_forces_.end(), Vec3{});
      for (Proxy& proxy : proxies_) proxy.release_force();
      count(tick);
      return tick;
    }
  }
  // 1. The targets: the paper's tick of every point from the ideal pose.
  // Where no material resists (free and rigid only), every target is the
  // device point and the walls are rigid: the points' ticks, which would
  // only walk round the bone the pose is held on, are not needed.
  const std::span<Vec3> targets = rigid_->targets();
  if (!resisting_materials_) {
    std::copy(world_points_.begin(), world_points_.end(), targets.begin());
    std::fill(point_ticks_.begin(), point_ticks_.end(), TickResult{});
  }
  BladeTick tick = resisting_materials_ ? step_points(dt_s, settings) : BladeTick{};
  for (std::size_t i = 0; resisting_materials_ && i < n; ++i) {
    const ProxyPlace& place = proxies_[i].place();
    const TickResult& r = point_ticks_[i];
    const bool held_by_material =
        (place.state == ProxyState::Tet || place.state == ProxyState::Outside) && !r.capped &&
        !r.deferred;
    targets[i] = held_by_material ? place.q : world_points_[i];
    // A membrane the point reached and did not break is as hard as bone.
    rigid_->set_walls(i, place, world_points_[i]);
  }
  // 2. The pose.
  bool lock = orientation_ == BladeOrientation::Locked;
  rigid_->begin_tick();
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
      rigid_->solve(false, device.direction, ignored);
      goal = rigid_->edge().direction;
      rigid_->restart_tick();
    }
    const Vec3 mixed = ramp_from_direction_ + (goal - ramp_from_direction_) * s;
    const double size = norm(mixed);
    lock_direction = size > 1e-9 ? mixed / size : goal;
    lock = true;
  }
  int rounds = 0;
  const bool resolved = rigid_->solve(lock, lock_direction, rounds);
  rigid_->apply_friction(lock);
  // 3. The points on it, and their forces.
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
  if (settings.force_shading && shading_) {
    rigid_->shade_force(*shading_, device, device_pose_.position_mm, tick.force_N,
                        tick.torque_N_mm);
  }
  tick.rigid_rounds = rounds;
  tick.contacts = static_cast<int>(rigid_->contacts().size());
  tick.unresolved = !resolved;
  count(tick);
  return tick;
}

}  // namespace hapticut
