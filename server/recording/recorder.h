// Recorder: writes the records the loop pushes into its ring to a recording
// file (recording/recording_file.h) on its own thread, so the tick never waits
// for the disk. A full ring drops records (the loop counts them).
#pragma once

#include <atomic>
#include <cstdio>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "recording/recording_file.h"
#include "rt/spsc_ring.h"
#include "servo_loop.h"

namespace hapticut::servo {

class Recorder {
 public:
  // The ring, allocated when a recording starts, holds about `buffer_s`
  // seconds of records (64 to 65536 slots, at most 64 MiB).
  Recorder(const RecordingInfo& info, double rate_Hz, double buffer_s);
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // Takes `file` (opened for `path` by client_files.h; closed here on every
  // path), writes the header (std::runtime_error naming the path when it
  // cannot) and asks the loop for records.
  void start(std::FILE* file, const std::string& path, LoopShared& shared);
  // Asks the loop to stop pushing, waits until it has, writes what is left
  // and the trailer (record count, records dropped) and closes the file. A
  // recording with a failed write gets no trailer. Does nothing when not
  // recording.
  void stop(LoopShared& shared);

  bool active() const { return file_ != nullptr; }
  const std::string& path() const { return path_; }
  std::uint64_t written() const { return written_.load(); }
  // The first write or close error, or "": the recorder thread may set it while the
  // control thread asks.
  std::string error() const;

 private:
  void drain();
  void note_error(const std::string& error);
  bool has_error() const;
  void run();

  RecordingInfo info_;
  std::size_t slot_count_;
  std::unique_ptr<SpscRing> ring_;  // Kept until the recorder goes (the loop may hold it).
  std::FILE* file_ = nullptr;
  std::string path_;
  mutable std::mutex error_mutex_;
  std::string error_;  // Under error_mutex_.
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> written_{0};
  // The loop's dropped_records count in this recording's first record.
  std::uint64_t first_dropped_ = 0;
};

}  // namespace hapticut::servo
