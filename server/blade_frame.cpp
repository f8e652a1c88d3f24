#include "blade_frame.h"

#include <span>

namespace hapticut::servo {

void read_blade_frame(const Blade& blade, BladeFrame& frame) {
  const std::size_t written = blade.snapshot(frame.header, std::span<ProxySnapshot>(frame.points));
  frame.ideal_pose = blade.ideal_pose();
  frame.state_counts.fill(0);
  for (std::size_t i = 0; i < written; ++i) {
    ++frame.state_counts[static_cast<std::size_t>(frame.points[i].place.state)];
  }
}

}  // namespace hapticut::servo
