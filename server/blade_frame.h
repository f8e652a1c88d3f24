// BladeFrame: what the servo publishes and records of one blade after a tick
// (device points p, proxies q, proxy states, the tick's force and torque),
// read from Blade's public accessors by the one function below. Sized once
// for the blade's points; filling it never allocates.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "hapticut/blade.h"

namespace hapticut::servo {

struct BladeFrame {
  explicit BladeFrame(int points = 0)
      : q_mm(static_cast<std::size_t>(points)),
        p_mm(static_cast<std::size_t>(points)),
        state(static_cast<std::size_t>(points)) {}

  std::vector<Vec3> q_mm;
  std::vector<Vec3> p_mm;
  std::vector<std::uint8_t> state;  // ProxyState per point.
  std::array<std::uint16_t, kProxyStateCount> state_counts{};
  BladeTick tick;
};

// Copies the blade's state after its last step into `frame` (sized for it).
void read_blade_frame(const Blade& blade, BladeFrame& frame);

}  // namespace hapticut::servo
