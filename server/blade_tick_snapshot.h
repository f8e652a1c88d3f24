// BladeTickSnapshot: what the servo publishes and records of one blade after a
// tick: the engine's own snapshot (Blade::snapshot: per point the proxy place,
// the device point p and the force; the tick with its work budget; the blade's
// counters), the blade's ideal pose and the proxies per state. Sized once for the blade's points;
// filling it never allocates. (Not a stream frame, stream_frame.h: that is the
// UDP datagram a snapshot is written into.)
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "hapticut/blade.h"

namespace hapticut::servo {

struct BladeTickSnapshot {
  explicit BladeTickSnapshot(int points = 0) : points(static_cast<std::size_t>(points)) {}

  std::size_t point_count() const { return points.size(); }

  BladeSnapshotHeader header;  // header.tick: the last step; header.counters: since the run began.
  std::vector<ProxySnapshot> points;
  std::array<std::uint16_t, kProxyStateCount> state_counts{};
  // Blade::ideal_pose after the last step: the rigid blade's solved tool pose,
  // or the last device pose for independent points (what the viewport draws).
  Pose ideal_pose;
};

// Copies the blade's state after its last step into `snapshot` (sized for it).
void read_blade_tick_snapshot(const Blade& blade, BladeTickSnapshot& snapshot);

}  // namespace hapticut::servo
