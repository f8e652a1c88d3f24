#include "blade_frame.h"

namespace hapticut::servo {

void read_blade_frame(const Blade& blade, BladeFrame& frame) {
  const std::vector<Proxy>& proxies = blade.proxies();
  const std::vector<Vec3>& points = blade.world_points();
  frame.state_counts.fill(0);
  for (std::size_t i = 0; i < proxies.size() && i < frame.q_mm.size(); ++i) {
    const ProxyPlace& place = proxies[i].place();
    frame.q_mm[i] = place.q;
    frame.p_mm[i] = points[i];
    frame.state[i] = static_cast<std::uint8_t>(place.state);
    ++frame.state_counts[static_cast<std::size_t>(place.state)];
  }
  frame.tick = blade.last_tick();
}

}  // namespace hapticut::servo
