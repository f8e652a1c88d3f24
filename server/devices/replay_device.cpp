#include "devices/replay_device.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <limits>

#include "safety.h"

namespace hapticut::servo {

ReplayDevice::ReplayDevice(std::unique_ptr<RecordingReader> reader, std::size_t blade_offset,
                           const std::string& describe)
    : reader_(std::move(reader)), blade_offset_(blade_offset) {
  const std::size_t record_bytes = reader_->info().record_bytes;
  chunk_records_ = std::max<std::uint64_t>(1, kReplayChunkBytes / record_bytes);
  chunk_.resize(chunk_records_ * record_bytes);
  read_initial_cuts(describe);
}

CutBlock ReplayDevice::cut_block(std::uint64_t index) const {
  CutBlock block;
  std::memcpy(&block,
              chunk_.data() + (index - chunk_first_) * reader_->info().record_bytes +
                  reader_->info().cut_block_offset,
              sizeof(block));
  return block;
}

void ReplayDevice::read_initial_cuts(const std::string& describe) {
  const std::uint64_t count = reader_->record_count();
  if (count == 0) return;
  if (!load_chunk(0)) throw DeviceError(describe + ": its first records cannot be read");
  const CutBlock first = cut_block(0);
  cut_generation_ = first.generation;
  const std::uint32_t wanted = first.before_tick;
  initial_cuts_.reserve(wanted);
  for (std::uint64_t i = 0; i < count && initial_cuts_.size() < wanted; ++i) {
    if (i >= chunk_first_ + chunk_count_ && !load_chunk(i)) break;
    const CutBlock block = cut_block(i);
    if (block.generation != first.generation || block.first != initial_cuts_.size() ||
        block.carried > kCutBlockTets) {
      break;
    }
    for (std::uint16_t k = 0; k < block.carried && initial_cuts_.size() < wanted; ++k) {
      initial_cuts_.push_back(block.tets[k]);
    }
  }
  if (initial_cuts_.size() != wanted) {
    throw DeviceError(describe + ": the recording started with " + std::to_string(wanted) +
                      " tets cut and its records carry " + std::to_string(initial_cuts_.size()) +
                      " of them (damaged or cut short)");
  }
  chunk_count_ = 0;  // start() reads from the first record again.
}

bool ReplayDevice::cut_reset_due() {
  const std::uint64_t count = reader_->record_count();
  if (next_ >= count) return false;
  if (next_ < chunk_first_ || next_ >= chunk_first_ + chunk_count_) {
    if (!load_chunk(next_)) return false;  // read() finds the file changed and ends.
  }
  const std::uint32_t generation = cut_block(next_).generation;
  const bool due = next_ > 0 && generation != cut_generation_;
  cut_generation_ = generation;
  return due;
}

void ReplayDevice::start() {
  next_ = 0;
  cut_generation_ = 0;
  sequence_ = 0;
  chunk_count_ = 0;
  last_sample_ = DeviceSample{};
  finished_.store(reader_->record_count() == 0, std::memory_order_relaxed);
  reader_->prefetch(0, chunk_records_);
}

bool ReplayDevice::load_chunk(std::uint64_t index) {
  chunk_first_ = index;
  chunk_count_ = std::min(chunk_records_, reader_->record_count() - index);
  if (!reader_->read_records(chunk_first_, chunk_count_, chunk_.data())) {
    chunk_count_ = 0;
    return false;
  }
  // The kernel reads the next chunk while this one plays.
  reader_->prefetch(chunk_first_ + chunk_count_, chunk_records_);
  return true;
}

DeviceStatus ReplayDevice::read(double now_s, DeviceSample& sample) {
  const std::uint64_t count = reader_->record_count();
  if (next_ >= count) {
    finished_.store(true, std::memory_order_relaxed);
    if (count == 0) return DeviceStatus::Lost;
    sample = last_sample_;
    return DeviceStatus::Stale;
  }
  if (next_ < chunk_first_ || next_ >= chunk_first_ + chunk_count_) {
    if (!load_chunk(next_)) {
      // The file changed under the replay (cut, unreadable): it ends here, lost.
      finished_.store(true, std::memory_order_relaxed);
      return DeviceStatus::Lost;
    }
  }
  const std::size_t record_bytes = reader_->info().record_bytes;
  BladeBlock block;
  std::memcpy(&block, chunk_.data() + (next_ - chunk_first_) * record_bytes + blade_offset_,
              sizeof(block));
  ++next_;
  if (next_ == count) finished_.store(true, std::memory_order_relaxed);
  const DeviceStatus status = block.device_status <= 2
                                  ? static_cast<DeviceStatus>(block.device_status)
                                  : DeviceStatus::Lost;
  const double* pose = block.pose;
  sample.pose = {{pose[0], pose[1], pose[2]}, {pose[3], pose[4], pose[5], pose[6]}};
  sample.buttons = block.buttons;
  sample.dt_s = block.step_dt_s;
  // A recorded late tick did not step; a gap no watchdog admits makes the
  // replay's safety refuse it the same way.
  if ((block.safety_flags & kSafetyLateTick) != 0U && block.step_kind == 0) {
    sample.dt_s = std::numeric_limits<double>::infinity();
  }
  if (status == DeviceStatus::Fresh) ++sequence_;
  sample.sequence = sequence_;
  sample.time_s = now_s;
  last_sample_ = sample;
  return status;
}

std::unique_ptr<Device> make_replay_device(const DeviceSpec& spec, const DeviceContext& context) {
  spec.check_options({"blade"});
  if (spec.value.empty()) throw DeviceError(spec.describe() + ": replay needs a recording file");
  const std::string blade = spec.string("blade", context.blade);
  auto reader = std::make_unique<RecordingReader>(spec.value);
  // A cut recording still holds a usable stroke up to its cut: play that
  // and say so, so that a short replay is not taken for the whole run.
  if (reader->truncated()) {
    if (reader->record_count() == 0) {
      throw DeviceError(spec.describe() + ": " + reader->truncation_message() +
                        ": nothing to replay");
    }
    std::fprintf(stderr, "warning: %s: %s; replaying those\n", spec.describe().c_str(),
                 reader->truncation_message().c_str());
  }
  const RecordingBlade* found = nullptr;
  std::string names;
  for (const RecordingBlade& b : reader->info().blades) {
    if (b.name == blade) found = &b;
    names += (names.empty() ? "" : ", ") + b.name;
  }
  if (found == nullptr) {
    throw DeviceError(spec.describe() + ": recording has no blade '" + blade +
                      "' (it has: " + names + ")");
  }
  const std::size_t offset = found->offset;
  return std::make_unique<ReplayDevice>(std::move(reader), offset, spec.describe());
}

}  // namespace hapticut::servo
