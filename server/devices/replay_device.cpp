#include "devices/replay_device.h"

#include <cstdio>
#include <cstring>
#include <limits>

#include "recording/recording_file.h"
#include "safety.h"

namespace hapticut::servo {

DeviceStatus ReplayDevice::read(double now_s, DeviceSample& sample) {
  if (next_ >= ticks_.size()) {
    finished_.store(true, std::memory_order_relaxed);
    if (ticks_.empty()) return DeviceStatus::Lost;
    sample = ticks_.back().sample;
    return DeviceStatus::Stale;
  }
  const ReplayTick& tick = ticks_[next_++];
  if (next_ == ticks_.size()) finished_.store(true, std::memory_order_relaxed);
  sample = tick.sample;
  sample.time_s = now_s;
  return tick.status;
}

std::unique_ptr<Device> make_replay_device(const DeviceSpec& spec, const DeviceContext& context) {
  spec.check_options({"blade"});
  if (spec.value.empty()) throw DeviceError(spec.describe() + ": replay needs a recording file");
  const std::string blade = spec.string("blade", context.blade);
  RecordingContents recording = read_recording(spec.value);
  // A cut recording still holds a usable stroke up to its cut: play that
  // and say so, so that a short replay is not taken for the whole run.
  if (recording.truncated) {
    if (recording.record_count() == 0) {
      throw DeviceError(spec.describe() + ": " + recording.truncation_message() +
                        ": nothing to replay");
    }
    std::fprintf(stderr, "warning: %s: %s; replaying those\n", spec.describe().c_str(),
                 recording.truncation_message().c_str());
  }
  const RecordingBlade* found = nullptr;
  std::string names;
  for (const RecordingBlade& b : recording.info.blades) {
    if (b.name == blade) found = &b;
    names += (names.empty() ? "" : ", ") + b.name;
  }
  if (found == nullptr) {
    throw DeviceError(spec.describe() + ": recording has no blade '" + blade +
                      "' (it has: " + names + ")");
  }
  std::vector<ReplayTick> ticks;
  ticks.reserve(recording.record_count());
  std::uint64_t sequence = 0;
  for (std::size_t i = 0; i < recording.record_count(); ++i) {
    BladeBlock block;
    std::memcpy(&block, recording.record(i) + found->offset, sizeof(block));
    ReplayTick tick{};
    tick.status = block.device_status <= 2 ? static_cast<DeviceStatus>(block.device_status)
                                           : DeviceStatus::Lost;
    const double* pose = block.pose;
    tick.sample.pose = {{pose[0], pose[1], pose[2]}, {pose[3], pose[4], pose[5], pose[6]}};
    tick.sample.buttons = block.buttons;
    tick.sample.dt_s = block.step_dt_s;
    // A recorded late tick did not step; a gap no watchdog admits makes the
    // replay's safety refuse it the same way.
    if ((block.safety_flags & kSafetyLateTick) != 0U && block.step_kind == 0) {
      tick.sample.dt_s = std::numeric_limits<double>::infinity();
    }
    if (tick.status == DeviceStatus::Fresh) ++sequence;
    tick.sample.sequence = sequence;
    ticks.push_back(tick);
  }
  return std::make_unique<ReplayDevice>(std::move(ticks));
}

}  // namespace hapticut::servo
