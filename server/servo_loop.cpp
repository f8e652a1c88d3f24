#include "servo_loop.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "rt/clock.h"

namespace hapticut::servo {

namespace {

// Whether the engine would take `pose` for `blade` (Blade::check_pose, the
// check Blade::reset and Blade::step run), as a safety fault flag (0: taken).
// Asked only before a reset, which throws for a refused pose.
std::uint32_t engine_refusal(const Blade& blade, const Pose& pose) {
  switch (blade.check_pose(pose)) {
    case PoseCheck::Fine:
      return 0;
    case PoseCheck::OutOfWorkspace:
      return kSafetyOutsideWorkspace;
    case PoseCheck::NotFinite:
    case PoseCheck::ZeroRotation:
      return kSafetyEngineRejected;
  }
  return kSafetyEngineRejected;
}

// One blade: read, admit, step with this tick's settings (the stiffness
// lowered to the device's limit), render, write. Returns the tick's result in
// binding.result. A change of the sample's kEngageRequestBit (a HID puck's
// engage button toggles it) sets the servo's engage state, from this tick on.
// A tick late after the last one does not step (admit), and one whose compute
// outlasted the watchdog time writes zero: its force was computed from a pose
// the stall made stale (never when as fast as possible, whose time is virtual).
void tick_blade(Binding& b, double now_s, double dt_s, bool fast, std::atomic<bool>& engage_state,
                bool stopping, const RuntimeSettings& tick_settings) {
  RuntimeSettings settings = tick_settings;  // Trivially copyable: no allocation.
  settings.stiffness_N_per_mm =
      stiffness_in_force(tick_settings.stiffness_N_per_mm, b.max_stiffness_N_per_mm);
  BladeTickResult& r = b.result;
  r.status = b.device->read(now_s, r.sample);
  r.step = StepKind::None;
  r.engine_force_N = Vec3{};
  r.engine_torque_N_mm = Vec3{};
  r.stiffness_N_per_mm = settings.stiffness_N_per_mm;
  r.force_shading = settings.force_shading;
  r.engine_rejected = false;
  bool engine_ok = false;
  const bool admitted = b.safety->admit(r.status, r.sample, dt_s);
  if (admitted) {
    const bool engage_bit = (r.sample.buttons & kEngageRequestBit) != 0U;
    if (engage_bit != b.engage_bit) {
      b.engage_bit = engage_bit;
      engage_state.store(engage_bit, std::memory_order_relaxed);
    }
  }
  const bool engaged = engage_state.load(std::memory_order_relaxed);
  if (admitted) {
    const std::uint32_t refusal = b.has_reset ? 0U : engine_refusal(*b.blade, r.sample.pose);
    if (refusal != 0) {
      r.engine_rejected = true;
      b.safety->engine_refused(refusal);
    } else {
      r.step = b.has_reset ? StepKind::Step : StepKind::ResetAndStep;
      if (!b.has_reset) {
        b.blade->reset(r.sample.pose);
        b.has_reset = true;
      }
      r.step_dt_s = r.sample.dt_s > 0.0 ? r.sample.dt_s : dt_s;
      const std::uint64_t far_before = b.blade->counters().out_of_workspace_ticks;
      const BladeTick tick = b.blade->step(r.sample.pose, r.step_dt_s, settings);
      engine_ok = !tick.rejected;
      if (tick.rejected) {
        r.engine_rejected = true;
        b.safety->engine_refused(b.blade->counters().out_of_workspace_ticks > far_before
                                     ? kSafetyOutsideWorkspace
                                     : kSafetyEngineRejected);
      }
      r.engine_force_N = tick.force_N;
      r.engine_torque_N_mm = tick.torque_N_mm;
    }
    b.snapshot_stale = true;
  }
  if (!fast && monotonic_now_s() - now_s > b.safety->settings().late_tick_s) {
    b.safety->late_in_tick();
  }
  r.safety =
      b.safety->render(r.engine_force_N, r.engine_torque_N_mm, engine_ok, dt_s, engaged, stopping);
  b.device->write(r.safety.force_N, r.safety.torque_N_mm);
}

// The blade's snapshot, brought up to its last step (every point: taken off
// the tick's compute, and only on the ticks that record or stream).
const BladeTickSnapshot& current_snapshot(Binding& b) {
  if (b.snapshot_stale) {
    read_blade_tick_snapshot(*b.blade, b.snapshot);
    b.snapshot_stale = false;
  }
  return b.snapshot;
}

void publish_report(const Binding& b, LatestValue<SafetyReport>& out) {
  SafetyReport report;
  report.events = b.safety->event_counts();
  report.faults = b.safety->fault_count();
  report.flags = b.result.safety.flags;
  report.device_status = static_cast<std::uint8_t>(b.result.status);
  report.ramp = b.result.safety.ramp;
  const Vec3& f = b.result.safety.force_N;
  const Vec3& e = b.result.engine_force_N;
  report.force_N[0] = f.x;
  report.force_N[1] = f.y;
  report.force_N[2] = f.z;
  report.engine_force_N[0] = e.x;
  report.engine_force_N[1] = e.y;
  report.engine_force_N[2] = e.z;
  out.publish(report);
}

void apply_limits(Session& session, const LimitsRequest& request) {
  for (Binding& b : session.bindings()) {
    SafetySettings s = b.requested;
    if (request.max_force_N > 0.0) s.max_force_N = std::min(s.max_force_N, request.max_force_N);
    if (request.max_torque_N_mm > 0.0) {
      s.max_torque_N_mm = std::min(s.max_torque_N_mm, request.max_torque_N_mm);
    }
    if (request.ramp_time_s > 0.0) s.ramp_time_s = request.ramp_time_s;
    b.safety->set_settings(limit_to_device(s, b.device->limits()));
  }
}

std::uint32_t servo_flags(bool stopping, bool fast, bool recording) {
  return kServoRunning | (stopping ? kServoStopping : 0U) | (fast ? kServoAsFastAsPossible : 0U) |
         (recording ? kServoRecording : 0U);
}

}  // namespace

void run_loop(Session& session, LoopShared& shared) {
  std::vector<Binding>& bindings = session.bindings();
  const double period_s = 1.0 / session.rate_Hz();
  const bool fast = session.as_fast_as_possible();
  const std::uint32_t session_number = shared.session.load();
  for (Binding& b : bindings) {
    b.safety->restart();
    b.has_reset = false;
    b.result = BladeTickResult{};
    b.blade->clear_counters();  // The frames' engine counters count this run.
  }
  // Settings per tick: the scene's until the control channel publishes others.
  RuntimeSettings settings = session.runtime_settings();
  shared.settings.read(settings);
  std::uint64_t limits_seen = 0;
  const double start_s = monotonic_now_s();
  double deadline_s = start_s + period_s;
  double last_now_s = start_s;
  double next_frame_s = 0.0;
  bool stopping = false;
  double stop_started_s = 0.0;
  double stop_ramp_s = 0.0;
  for (const Binding& b : bindings)
    stop_ramp_s = std::max(stop_ramp_s, b.safety->settings().stop_ramp_time_s);
  std::uint64_t tick = 0;
  std::uint64_t late = 0;
  std::uint64_t dropped = 0;
  std::uint64_t frame_sequence = 0;
  CutState& cuts = session.cut_state();
  CutFeed& cut_feed = session.cut_feed();
  // Every run's stream starts at the cut order's first entry (a client that
  // joined late asks for the rest); every recording does too.
  CutCursor frame_cuts{cuts.generation(), 0};
  CutCursor record_cuts;
  bool recorded_last_tick = false;
  shared.running.store(true);

  for (;; ++tick) {
    // Wake.
    double now_s = 0.0;
    double wake_latency_s = 0.0;
    if (fast) {
      now_s = start_s + double(tick + 1) * period_s;
    } else {
      sleep_until(deadline_s);
      now_s = monotonic_now_s();
      wake_latency_s = now_s - deadline_s;
    }
    const double woke_s = fast ? monotonic_now_s() : now_s;
    const double dt_s = tick == 0 ? period_s : now_s - last_now_s;
    last_now_s = now_s;

    // Control inputs (plain atomic loads).
    LimitsRequest limits;
    const std::uint64_t limits_version = shared.limits.read(limits);
    if (limits_version != limits_seen) {
      limits_seen = limits_version;
      apply_limits(session, limits);
    }
    if (!stopping && shared.stop_requested.load(std::memory_order_relaxed)) {
      stopping = true;
      stop_started_s = now_s;
    }
    shared.settings.read(settings);  // Newest settings (a sequence lock, no waiting).
    const bool recording = shared.record_wanted.load(std::memory_order_acquire);
    shared.recording.store(recording, std::memory_order_release);

    // Fresh tissue when asked (a control message, a replay's recorded reset),
    // before any blade steps.
    bool reset_cuts = false;
    const std::uint64_t resets = shared.cut_resets_requested.load(std::memory_order_relaxed);
    if (resets != shared.cut_resets_done.load(std::memory_order_relaxed)) {
      shared.cut_resets_done.store(resets, std::memory_order_relaxed);
      reset_cuts = true;
    }
    for (Binding& b : bindings) reset_cuts = b.device->cut_reset_due() || reset_cuts;
    if (reset_cuts) cuts.reset_cuts();
    const auto cut_before_tick = static_cast<std::uint32_t>(cuts.cut_count());

    // The tick: devices -> engine -> safety -> devices.
    for (Binding& b : bindings) {
      tick_blade(b, now_s, dt_s, fast, shared.engaged, stopping, settings);
    }
    const double compute_us = (monotonic_now_s() - woke_s) * 1e6;
    cut_feed.follow(cuts);

    // Counters.
    shared.compute_us.add(compute_us);
    if (!fast) shared.wake_us.add(wake_latency_s * 1e6);
    for (std::size_t i = 0; i < bindings.size() && i < kMaxBlades; ++i) {
      publish_report(bindings[i], shared.reports[i]);
    }

    // Record.
    SpscRing* ring = recording ? shared.ring.load(std::memory_order_acquire) : nullptr;
    if (ring != nullptr && !recorded_last_tick) record_cuts = {cuts.generation(), 0};
    recorded_last_tick = ring != nullptr;
    if (ring != nullptr) {
      unsigned char* slot = ring->begin_push();
      if (slot == nullptr) {
        ++dropped;
        shared.dropped_records.store(dropped, std::memory_order_relaxed);
      } else {
        RecordHeader header;
        header.tick = tick;
        header.time_s = now_s;
        header.dt_s = dt_s;
        header.compute_us = compute_us;
        header.wake_latency_us = wake_latency_s * 1e6;
        header.late_ticks = late;
        header.dropped_records = dropped;
        header.servo_flags = servo_flags(stopping, fast, true);
        header.blade_count = static_cast<std::uint32_t>(bindings.size());
        std::memcpy(slot, &header, sizeof(header));
        std::size_t offset = sizeof(header);
        for (Binding& b : bindings)
          offset += write_blade_block(b.result, current_snapshot(b), slot + offset);
        write_cut_block(cuts, cut_before_tick, record_cuts, slot + offset);
        ring->end_push();
      }
    }

    // Publish a stream frame when one is due.
    const double interval_s = shared.stream_interval_s.load(std::memory_order_relaxed);
    if (interval_s > 0.0 && now_s >= next_frame_s) {
      next_frame_s = std::max(next_frame_s + interval_s, now_s);
      FrameBytes& frame = shared.frames.back();
      FrameHeader header;
      std::memcpy(header.magic, kFrameMagic, 4);
      header.version = kFrameVersion;
      header.blade_count = static_cast<std::uint16_t>(bindings.size());
      header.session = session_number;
      header.sequence = ++frame_sequence;
      header.tick = tick;
      header.servo_time_s = now_s;
      header.dt_s = dt_s;
      // The timing percentiles are filled in by the network thread (off the tick).
      header.late_ticks = late;
      header.dropped_records = dropped;
      header.servo_flags = servo_flags(stopping, fast, recording);
      std::size_t offset = sizeof(header);
      for (Binding& b : bindings)
        offset += write_blade_block(b.result, current_snapshot(b), frame.bytes + offset);
      write_cut_block(cuts, cut_before_tick, frame_cuts, frame.bytes + offset);
      offset += sizeof(CutBlock);
      header.frame_bytes = static_cast<std::uint32_t>(offset);
      std::memcpy(frame.bytes, &header, sizeof(header));
      frame.size = static_cast<std::uint32_t>(offset);
      shared.frames.publish();
      shared.frames_published.store(frame_sequence, std::memory_order_relaxed);
    }
    shared.ticks.store(tick + 1, std::memory_order_relaxed);
    shared.time_s.store(now_s, std::memory_order_relaxed);

    // End of the run?
    if (stopping) {
      bool all_zero = true;
      for (const Binding& b : bindings) all_zero = all_zero && b.result.safety.ramp == 0.0;
      if (all_zero || now_s - stop_started_s > stop_ramp_s + 2.0 * period_s) break;
    } else {
      bool done = shared.exit_when_done;
      for (const Binding& b : bindings) done = done && b.device->finished();
      const bool timed_out = shared.duration_s > 0.0 && now_s - start_s >= shared.duration_s;
      if (done || timed_out) {
        shared.ended_by_itself.store(true);
        shared.stop_requested.store(true);
      }
    }

    // Next deadline: a late tick is counted, the deadlines it missed skipped.
    deadline_s += period_s;
    if (!fast) {
      const double after_s = monotonic_now_s();
      if (after_s > deadline_s) {
        ++late;
        shared.late_ticks.store(late, std::memory_order_relaxed);
        deadline_s += std::ceil((after_s - deadline_s) / period_s) * period_s;
      }
    }
  }
  for (Binding& b : bindings) b.device->write(Vec3{}, Vec3{});
  shared.recording.store(false, std::memory_order_release);
  shared.running.store(false);
}

}  // namespace hapticut::servo
