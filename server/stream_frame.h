// Writing one blade's BladeBlock and points block, and the CutBlock (layout.h),
// from the tick's results: the same bytes go into stream frames and recording
// records.
#pragma once

#include <cstdint>

#include "blade_tick_snapshot.h"
#include "devices/device.h"
#include "hapticut/cut_state.h"
#include "layout.h"
#include "safety.h"

namespace hapticut::servo {

// A stream frame as the network thread sends it.
struct FrameBytes {
  std::uint32_t size = 0;
  unsigned char bytes[kMaxFrameBytes];
};

// What the loop knows of one blade after a tick.
struct BladeTickResult {
  DeviceStatus status = DeviceStatus::Lost;
  DeviceSample sample;
  StepKind step = StepKind::None;
  double step_dt_s = 0.0;
  Vec3 engine_force_N;
  Vec3 engine_torque_N_mm;
  double stiffness_N_per_mm = 0.0;  // Stepped with: the settings', lowered to the device's limit.
  bool force_shading = false;
  bool engine_rejected = false;  // The engine refused this tick's sample.
  SafetyOutput safety;
};

// Writes the blade's block at `out` (sizeof(BladeBlock) + points_block_bytes
// bytes); returns the bytes written.
std::size_t write_blade_block(const BladeTickResult& result, const BladeTickSnapshot& snapshot,
                              unsigned char* out);

// Where the next CutBlock of one output (the stream, a recording) goes on in
// the cut order: a new generation starts it again from the first entry.
struct CutCursor {
  std::uint32_t generation = 0;
  std::uint32_t next = 0;
};

// Writes the CutBlock at `out` (sizeof(CutBlock) bytes): the cut order's next
// entries after `cursor`, which it advances; `before_tick` is the count of
// tets cut when the tick began.
void write_cut_block(const CutState& cuts, std::uint32_t before_tick, CutCursor& cursor,
                     unsigned char* out);

}  // namespace hapticut::servo
