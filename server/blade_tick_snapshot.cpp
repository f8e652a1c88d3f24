#include "blade_tick_snapshot.h"

#include <span>

namespace hapticut::servo {

void read_blade_tick_snapshot(const Blade& blade, BladeTickSnapshot& snapshot) {
  const std::size_t written =
      blade.snapshot(snapshot.header, std::span<ProxySnapshot>(snapshot.points));
  snapshot.ideal_pose = blade.ideal_pose();
  snapshot.state_counts.fill(0);
  for (std::size_t i = 0; i < written; ++i) {
    ++snapshot.state_counts[static_cast<std::size_t>(snapshot.points[i].place.state)];
  }
}

}  // namespace hapticut::servo
