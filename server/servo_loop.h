// The servo loop: one tick per period on its own thread. A tick reads like
// its description: read every device, step every blade, pass the forces
// through safety, write them to the devices; then count, record and publish.
// Absolute-time wake-ups on CLOCK_MONOTONIC; a late tick is counted and the
// missed deadlines are skipped, never repaid with a burst. As fast as
// possible (baking): no sleeping, the time advances by the period each tick.
// Inside the tick: no allocation, no lock, no system call but the devices'
// own I/O, no logging.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>

#include "rt/histogram.h"
#include "rt/latest_value.h"
#include "rt/spsc_ring.h"
#include "rt/triple_buffer.h"
#include "session.h"

namespace hapticut::servo {

// Safety limits a control message asks for (lowered to each device's).
struct LimitsRequest {
  double max_force_N = 0.0;
  double max_torque_N_mm = 0.0;
  double ramp_time_s = 0.0;
};

// One blade's safety, as the other threads see it (published every tick).
struct SafetyReport {
  std::array<std::uint64_t, kSafetyFlagCount> events{};
  std::uint64_t faults = 0;
  std::uint32_t flags = 0;
  std::uint8_t device_status = 0;
  double ramp = 0.0;
  double force_N[3]{};
  double engine_force_N[3]{};
};

// Everything the loop shares with the other threads, all lock-free.
struct LoopShared {
  // In (control -> loop).
  std::atomic<bool> stop_requested{false};
  std::atomic<bool> engaged{false};
  // Settings per tick (set by the control channel, validated; none published:
  // the scene's). Read by the loop every tick.
  LatestValue<RuntimeSettings> settings;
  std::atomic<double> stream_interval_s{0.0};  // 0: nobody subscribed, no frames.
  std::atomic<bool> record_wanted{false};
  // reset_cuts while a run is on: the loop resets the scene's cuts at the
  // start of a tick while done lags requested (at the next run's start when
  // this one ends first).
  std::atomic<std::uint64_t> cut_resets_requested{0};
  LatestValue<LimitsRequest> limits;
  bool exit_when_done = false;  // Set before the run.
  double duration_s = 0.0;      // 0: no limit. Set before the run.

  // Out (loop -> others).
  std::atomic<bool> running{false};
  std::atomic<bool> recording{false};  // The loop is pushing records.
  std::atomic<bool> ended_by_itself{false};
  std::atomic<std::uint64_t> cut_resets_done{0};
  std::atomic<std::uint64_t> ticks{0};
  std::atomic<std::uint64_t> late_ticks{0};
  std::atomic<std::uint64_t> dropped_records{0};
  std::atomic<std::uint64_t> frames_published{0};
  std::atomic<double> time_s{0.0};
  std::atomic<std::uint32_t> session{0};
  LatencyHistogram compute_us;
  LatencyHistogram wake_us;
  TripleBuffer<FrameBytes> frames;
  std::atomic<SpscRing*> ring{nullptr};              // Records, when recording (the recorder's).
  std::array<LatestValue<SafetyReport>, 8> reports;  // Per binding (at most 8 blades).
};

inline constexpr std::size_t kMaxBlades = 8;

// Runs the session until stop_requested (then ramps the forces down), the
// duration ends, or (exit_when_done) every device has finished. Every
// device is written zero before it returns.
void run_loop(Session& session, LoopShared& shared);

}  // namespace hapticut::servo
