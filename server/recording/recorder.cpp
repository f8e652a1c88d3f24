#include "recording/recorder.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>

namespace hapticut::servo {

namespace {

std::size_t slots_for(std::size_t record_bytes, double rate_Hz, double buffer_s) {
  const auto wanted = static_cast<std::size_t>(std::max(1.0, rate_Hz * buffer_s));
  const std::size_t by_memory =
      std::max<std::size_t>(64, (64U << 20) / std::max<std::size_t>(record_bytes, 1));
  return std::clamp<std::size_t>(std::min(wanted, by_memory), 64, 65536);
}

}  // namespace

Recorder::Recorder(const RecordingInfo& info, double rate_Hz, double buffer_s)
    : info_(info), slot_count_(slots_for(info.record_bytes, rate_Hz, buffer_s)) {}

Recorder::~Recorder() {
  if (thread_.joinable()) {
    stop_.store(true);
    thread_.join();
  }
  if (file_ != nullptr) std::fclose(file_);
}

void Recorder::start(std::FILE* file, const std::string& path, LoopShared& shared) {
  if (active()) {
    std::fclose(file);
    throw std::runtime_error("already recording to '" + path_ + "'");
  }
  const std::vector<unsigned char> preamble = recording_preamble(info_);
  if (std::fwrite(preamble.data(), 1, preamble.size(), file) != preamble.size()) {
    std::fclose(file);
    throw std::runtime_error("cannot write recording '" + path + "': " + std::strerror(errno));
  }
  if (!ring_) ring_ = std::make_unique<SpscRing>(info_.record_bytes, slot_count_);
  // Anything left in the ring from an earlier recording is not this one's.
  while (ring_->front() != nullptr) ring_->pop();
  shared.ring.store(ring_.get(), std::memory_order_release);
  file_ = file;
  path_ = path;
  {
    std::lock_guard<std::mutex> lock(error_mutex_);
    error_.clear();
  }
  written_.store(0);
  stop_.store(false);
  thread_ = std::thread([this] { run(); });
  shared.record_wanted.store(true, std::memory_order_release);
}

void Recorder::stop(LoopShared& shared) {
  if (!active()) return;
  shared.record_wanted.store(false, std::memory_order_release);
  // The loop acknowledges at its next tick; a stopped loop pushes nothing.
  for (int i = 0;
       i < 2000 && shared.recording.load(std::memory_order_acquire) && shared.running.load(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
  drain();
  // The trailer says the file is complete, so a file with a failed write
  // gets none: readers then report it truncated.
  if (!has_error()) {
    const std::uint64_t dropped =
        written_.load() == 0 ? 0 : shared.dropped_records.load() - first_dropped_;
    const RecordingTrailer trailer = recording_trailer(written_.load(), dropped);
    if (std::fwrite(&trailer, 1, sizeof(trailer), file_) != sizeof(trailer)) {
      note_error(std::string("write failed: ") + std::strerror(errno));
    }
  }
  if (std::fclose(file_) != 0) note_error(std::strerror(errno));
  file_ = nullptr;
}

void Recorder::drain() {
  while (const unsigned char* record = ring_->front()) {
    if (written_.load(std::memory_order_relaxed) == 0) {
      // The ring is empty when a recording starts, so nothing is lost before
      // its first record: drops from here on are this recording's.
      RecordHeader header;
      std::memcpy(&header, record, sizeof(header));
      first_dropped_ = header.dropped_records;
    }
    // After a failed write the file's records are no longer in step: none
    // is written after it.
    if (!has_error()) {
      if (std::fwrite(record, 1, ring_->slot_bytes(), file_) == ring_->slot_bytes()) {
        written_.fetch_add(1, std::memory_order_relaxed);
      } else {
        note_error(std::string("write failed: ") + std::strerror(errno));
      }
    }
    ring_->pop();
  }
}

bool Recorder::has_error() const {
  std::lock_guard<std::mutex> lock(error_mutex_);
  return !error_.empty();
}

void Recorder::note_error(const std::string& error) {
  std::lock_guard<std::mutex> lock(error_mutex_);
  if (error_.empty()) error_ = error;
}

std::string Recorder::error() const {
  std::lock_guard<std::mutex> lock(error_mutex_);
  return error_;
}

void Recorder::run() {
  while (!stop_.load()) {
    drain();
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

}  // namespace hapticut::servo
