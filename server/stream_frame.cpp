#include "stream_frame.h"

#include <cstring>

namespace hapticut::servo {

namespace {

void put(double* out, const Vec3& v) {
  out[0] = v.x;
  out[1] = v.y;
  out[2] = v.z;
}

}  // namespace

std::size_t write_blade_block(const BladeTickResult& result, const BladeFrame& frame,
                              unsigned char* out) {
  BladeBlock block;
  const Pose& pose = result.sample.pose;
  block.pose[0] = pose.position_mm.x;
  block.pose[1] = pose.position_mm.y;
  block.pose[2] = pose.position_mm.z;
  block.pose[3] = pose.rotation.w;
  block.pose[4] = pose.rotation.x;
  block.pose[5] = pose.rotation.y;
  block.pose[6] = pose.rotation.z;
  put(block.engine_force_N, result.engine_force_N);
  put(block.engine_torque_N_mm, result.engine_torque_N_mm);
  put(block.force_N, result.safety.force_N);
  put(block.torque_N_mm, result.safety.torque_N_mm);
  block.ramp = result.safety.ramp;
  block.step_dt_s = result.step == StepKind::None ? 0.0 : result.step_dt_s;
  const std::size_t points = frame.q_mm.size();
  block.point_count = static_cast<std::uint32_t>(points);
  block.buttons = result.sample.buttons;
  block.safety_flags = result.safety.flags;
  block.events = result.safety.events;
  for (int s = 0; s < kProxyStateCount; ++s) block.state_counts[s] = frame.state_counts[s];
  block.capped_points = static_cast<std::uint16_t>(frame.tick.capped_points);
  block.device_status = static_cast<std::uint8_t>(result.status);
  block.step_kind = static_cast<std::uint8_t>(result.step);
  block.max_transitions = static_cast<std::uint16_t>(frame.tick.max_transitions);
  std::memcpy(out, &block, sizeof(block));
  unsigned char* points_out = out + sizeof(block);
  const std::size_t bytes = points_block_bytes(points);
  std::memset(points_out + points * 6 * sizeof(double), 0, bytes - points * 6 * sizeof(double));
  const PointsView view = points_view(points_out, points);
  for (std::size_t i = 0; i < points; ++i) {
    std::memcpy(view.q + 3 * i, &frame.q_mm[i], 3 * sizeof(double));
    std::memcpy(view.p + 3 * i, &frame.p_mm[i], 3 * sizeof(double));
  }
  std::memcpy(view.state, frame.state.data(), points);
  return sizeof(block) + bytes;
}

}  // namespace hapticut::servo
