// The replay device: plays one blade of a recording, one recorded tick per
// servo tick: the device status, pose, buttons and the dt the engine stepped
// with. With the same scene it gives bit-identical proxy paths and engine
// forces. Input only: nothing is rendered. A truncated recording (no end
// trailer) plays its whole records, with a warning on stderr.
#pragma once

#include <atomic>
#include <memory>
#include <vector>

#include "devices/device_args.h"
#include "devices/device_factory.h"

namespace hapticut::servo {

inline constexpr const char* kReplayDeviceUsage =
    "  replay:FILE[,blade=NAME]            plays a recording's blade NAME (default: the\n"
    "      bound blade's name) tick by tick, with the recorded dt (a truncated\n"
    "      recording: its whole records, with a warning)\n";

struct ReplayTick {
  DeviceStatus status;
  DeviceSample sample;
};

class ReplayDevice : public Device {
 public:
  explicit ReplayDevice(std::vector<ReplayTick> ticks) : ticks_(std::move(ticks)) {}

  const char* kind() const override { return "replay"; }
  DeviceLimits limits() const override { return {}; }
  void start() override {
    next_ = 0;
    finished_.store(ticks_.empty(), std::memory_order_relaxed);
  }
  DeviceStatus read(double now_s, DeviceSample& sample) override;
  void write(const Vec3& /*force_N*/, const Vec3& /*torque_N_mm*/) override {}
  bool finished() const override { return finished_.load(std::memory_order_relaxed); }

 private:
  std::vector<ReplayTick> ticks_;
  std::size_t next_ = 0;
  std::atomic<bool> finished_{false};
};

std::unique_ptr<Device> make_replay_device(const DeviceSpec& spec, const DeviceContext& context);

}  // namespace hapticut::servo
