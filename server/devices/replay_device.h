// The replay device: plays one blade of a recording, one recorded tick per
// servo tick: the device status, pose, buttons and the dt the engine stepped
// with, from the cuts the recording started with, reset where the recorded
// run's were. With the same scene it gives bit-identical proxy paths and engine
// forces. Input only: nothing is rendered. A truncated recording (no end
// trailer) plays its whole records, with a warning on stderr. The file is read
// a chunk of records at a time (the next one read ahead by the kernel), so its
// memory does not grow with the recording and opening it reads only its
// header and trailer.
#pragma once

#include <atomic>
#include <memory>
#include <vector>

#include "devices/device_args.h"
#include "devices/device_factory.h"
#include "recording/recording_reader.h"

namespace hapticut::servo {

inline constexpr const char* kReplayDeviceUsage =
    "  replay:FILE[,blade=NAME]            plays a recording's blade NAME (default: the\n"
    "      bound blade's name) tick by tick, with the recorded dt (a truncated\n"
    "      recording: its whole records, with a warning)\n";

// The bytes of records held at once.
inline constexpr std::size_t kReplayChunkBytes = 1U << 20;

class ReplayDevice : public Device {
 public:
  // Plays the blade whose block is at `blade_offset` in each record.
  // Throws DeviceError (`describe` names the device) when the first records
  // do not hold the cuts the recording started with.
  ReplayDevice(std::unique_ptr<RecordingReader> reader, std::size_t blade_offset,
               const std::string& describe);

  const char* kind() const override { return "replay"; }
  DeviceLimits limits() const override { return {}; }
  void start() override;
  DeviceStatus read(double now_s, DeviceSample& sample) override;
  void write(const Vec3& /*force_N*/, const Vec3& /*torque_N_mm*/) override {}
  bool finished() const override { return finished_.load(std::memory_order_relaxed); }
  std::span<const std::int32_t> initial_cuts() const override { return initial_cuts_; }
  bool cut_reset_due() override;

 private:
  // Makes the chunk hold record `index`; false when the file cannot give it.
  bool load_chunk(std::uint64_t index);
  // Record `index`'s CutBlock (it must be in the chunk).
  CutBlock cut_block(std::uint64_t index) const;
  // The tets cut before the first record: the first records carry them
  // (layout.h, CutBlock). Throws DeviceError when the file does not hold them.
  void read_initial_cuts(const std::string& describe);

  std::unique_ptr<RecordingReader> reader_;
  std::size_t blade_offset_ = 0;
  std::uint64_t chunk_records_ = 1;
  std::vector<unsigned char> chunk_;  // Sized once: no allocation in a tick.
  std::uint64_t chunk_first_ = 0;
  std::uint64_t chunk_count_ = 0;
  std::uint64_t next_ = 0;
  std::uint64_t sequence_ = 0;
  DeviceSample last_sample_;
  std::vector<std::int32_t> initial_cuts_;
  std::uint32_t cut_generation_ = 0;  // Of the last record played.
  std::atomic<bool> finished_{false};
};

std::unique_ptr<Device> make_replay_device(const DeviceSpec& spec, const DeviceContext& context);

}  // namespace hapticut::servo
