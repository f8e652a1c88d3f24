// Blade: N points spread evenly on a segment in the tool frame, placed in the
// world by the tool's pose; one Proxy per point. The device gets the summed
// force and the torque about the tool origin (beyond the paper).
#pragma once

#include <vector>

#include "hapticut/proxy.h"
#include "hapticut/scene.h"

namespace hapticut {

// Unit quaternion (w, x, y, z) rotating the tool frame into the world.
struct Quaternion {
  double w = 1.0;
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
  Vec3 rotate(const Vec3& v) const;
  Quaternion normalized() const;
};

struct Pose {
  Vec3 position_mm;  // The tool origin in the world.
  Quaternion rotation;
};

struct BladeTick {
  Vec3 force_N;      // Sum of k (q_i - p_i).
  Vec3 torque_N_mm;  // Sum of (p_i - origin) x f_i.
  int capped_points = 0;
  int max_transitions = 0;
  bool rejected = false;  // Pose not finite: nothing moved, force zero.
};

class Blade {
 public:
  Blade(const Space& space, const BladeSpec& spec);

  void reset(const Pose& pose);
  BladeTick step(const Pose& pose, double dt_s);

  int point_count() const { return static_cast<int>(proxies_.size()); }
  const std::vector<Vec3>& tool_points() const { return tool_points_; }
  const std::vector<Vec3>& world_points() const { return world_points_; }
  const std::vector<Proxy>& proxies() const { return proxies_; }
  const BladeTick& last_tick() const { return last_tick_; }

 private:
  void place_points(const Pose& pose);

  std::vector<Vec3> tool_points_;
  std::vector<Vec3> world_points_;
  std::vector<Proxy> proxies_;
  BladeTick last_tick_;
};

}  // namespace hapticut
