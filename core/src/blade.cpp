#include "hapticut/blade.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hapticut {

Vec3 Quaternion::rotate(const Vec3& v) const {
  const Vec3 u{x, y, z};
  const Vec3 t = cross(u, v) * 2.0;
  return v + t * w + cross(u, t);
}

Quaternion Quaternion::normalized() const {
  const double n = std::sqrt(w * w + x * x + y * y + z * z);
  if (!(n > 0.0) || !std::isfinite(n)) return {};
  return {w / n, x / n, y / n, z / n};
}

Blade::Blade(const Space& space, const BladeSpec& spec) {
  if (spec.points < 1) throw std::invalid_argument("a blade needs at least one point");
  tool_points_.reserve(spec.points);
  for (int i = 0; i < spec.points; ++i) {
    const double s = spec.points == 1 ? 0.0 : double(i) / double(spec.points - 1);
    tool_points_.push_back(spec.start_mm + (spec.end_mm - spec.start_mm) * s);
  }
  world_points_ = tool_points_;
  proxies_.assign(tool_points_.size(), Proxy(space));
}

void Blade::place_points(const Pose& pose) {
  const Quaternion r = pose.rotation.normalized();
  for (std::size_t i = 0; i < tool_points_.size(); ++i) {
    world_points_[i] = pose.position_mm + r.rotate(tool_points_[i]);
  }
}

static bool pose_is_finite(const Pose& pose) {
  const Quaternion& r = pose.rotation;
  return is_finite(pose.position_mm) && std::isfinite(r.w) && std::isfinite(r.x) &&
         std::isfinite(r.y) && std::isfinite(r.z);
}

void Blade::reset(const Pose& pose) {
  if (!pose_is_finite(pose)) throw std::invalid_argument("blade pose is not finite");
  place_points(pose);
  for (std::size_t i = 0; i < proxies_.size(); ++i) proxies_[i].reset(world_points_[i]);
  last_tick_ = {};
}

BladeTick Blade::step(const Pose& pose, double dt_s) {
  BladeTick tick;
  if (!pose_is_finite(pose)) {
    tick.rejected = true;
    last_tick_ = tick;
    return tick;
  }
  place_points(pose);
  for (std::size_t i = 0; i < proxies_.size(); ++i) {
    const TickResult r = proxies_[i].step(world_points_[i], dt_s);
    const Vec3 f = proxies_[i].force_N();
    tick.force_N += f;
    tick.torque_N_mm += cross(world_points_[i] - pose.position_mm, f);
    tick.capped_points += r.capped ? 1 : 0;
    tick.max_transitions = std::max(tick.max_transitions, r.transitions);
  }
  last_tick_ = tick;
  return tick;
}

}  // namespace hapticut
