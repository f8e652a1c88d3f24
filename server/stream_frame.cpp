#include "stream_frame.h"

#include <algorithm>
#include <cstring>

namespace hapticut::servo {

namespace {

void put(double* out, const Vec3& v) {
  out[0] = v.x;
  out[1] = v.y;
  out[2] = v.z;
}

// x, y, z (mm), then the quaternion w, x, y, z: the layout's f64[7] pose.
void put_pose(double* out, const Pose& pose) {
  put(out, pose.position_mm);
  out[3] = pose.rotation.w;
  out[4] = pose.rotation.x;
  out[5] = pose.rotation.y;
  out[6] = pose.rotation.z;
}

}  // namespace

std::size_t write_blade_block(const BladeTickResult& result, const BladeTickSnapshot& snapshot,
                              unsigned char* out) {
  BladeBlock block;
  put_pose(block.pose, result.sample.pose);
  put_pose(block.ideal_pose, snapshot.ideal_pose);
  put(block.engine_force_N, result.engine_force_N);
  put(block.engine_torque_N_mm, result.engine_torque_N_mm);
  put(block.force_N, result.safety.force_N);
  put(block.torque_N_mm, result.safety.torque_N_mm);
  block.ramp = result.safety.ramp;
  block.step_dt_s = result.step == StepKind::None ? 0.0 : result.step_dt_s;
  const std::size_t points = snapshot.point_count();
  const BladeTick& tick = snapshot.header.tick;
  const BladeCounters& counters = snapshot.header.counters;
  block.point_count = static_cast<std::uint32_t>(points);
  block.buttons = result.sample.buttons;
  block.safety_flags = result.safety.flags;
  block.events = result.safety.events;
  for (int s = 0; s < kProxyStateCount; ++s) block.state_counts[s] = snapshot.state_counts[s];
  block.capped_points = static_cast<std::uint16_t>(tick.capped_points);
  block.device_status = static_cast<std::uint8_t>(result.status);
  block.step_kind = static_cast<std::uint8_t>(result.step);
  block.max_transitions = static_cast<std::uint16_t>(tick.max_transitions);
  block.stiffness_N_per_mm = result.stiffness_N_per_mm;
  block.rejected_ticks = counters.rejected_ticks;
  block.out_of_workspace_ticks = counters.out_of_workspace_ticks;
  block.unfinished_ticks = counters.unfinished_ticks;
  block.transitions = static_cast<std::uint32_t>(tick.transitions);
  block.deferred_points = static_cast<std::uint16_t>(tick.deferred_points);
  block.engine_rejected = result.engine_rejected ? 1 : 0;
  block.force_shading = result.force_shading ? 1 : 0;
  std::memcpy(out, &block, sizeof(block));
  unsigned char* points_out = out + sizeof(block);
  const std::size_t bytes = points_block_bytes(points);
  std::memset(points_out + points * 6 * sizeof(double), 0, bytes - points * 6 * sizeof(double));
  const PointsView view = points_view(points_out, points);
  for (std::size_t i = 0; i < points; ++i) {
    const ProxySnapshot& point = snapshot.points[i];
    std::memcpy(view.q + 3 * i, &point.place.q, 3 * sizeof(double));
    std::memcpy(view.p + 3 * i, &point.p, 3 * sizeof(double));
    view.state[i] = static_cast<std::uint8_t>(point.place.state);
  }
  return sizeof(block) + bytes;
}

void write_cut_block(const CutState& cuts, std::uint32_t before_tick, CutCursor& cursor,
                     unsigned char* out) {
  CutBlock block;
  block.generation = cuts.generation();
  if (cursor.generation != block.generation) cursor = {block.generation, 0};
  const std::span<const std::int32_t> order = cuts.cut_order();
  block.total = static_cast<std::uint32_t>(order.size());
  block.before_tick = before_tick;
  block.first = std::min(cursor.next, block.total);
  block.carried =
      static_cast<std::uint16_t>(std::min<std::uint32_t>(block.total - block.first, kCutBlockTets));
  block.capacity = kCutBlockTets;
  std::copy_n(order.begin() + block.first, block.carried, block.tets);
  cursor.next = block.first + block.carried;
  std::memcpy(out, &block, sizeof(block));
}

}  // namespace hapticut::servo
