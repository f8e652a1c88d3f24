// A recording read a part at a time (the replay device): opened under the file
// rules of every path the servo opens (client_files.h: a regular file, opened
// without waiting), its header and trailer checked at open, and its records
// read on demand, so that neither the time to open it nor the memory it takes
// grows with the file. Errors name the file and never quote its content.
#pragma once

#include <cstdint>
#include <string>

#include "recording/recording_file.h"

namespace hapticut::servo {

// The largest header (its JSON) a reader takes; a real one is a few kB.
inline constexpr std::uint64_t kMaxRecordingHeaderBytes = 1U << 20;

class RecordingReader {
 public:
  // Throws DeviceError naming the file and what is wrong.
  explicit RecordingReader(const std::string& path);
  ~RecordingReader();
  RecordingReader(const RecordingReader&) = delete;
  RecordingReader& operator=(const RecordingReader&) = delete;

  const RecordingInfo& info() const { return info_; }
  const std::string& path() const { return path_; }
  std::uint64_t record_count() const { return record_count_; }
  // No trailer: the run was cut short; record_count() counts the whole records.
  bool truncated() const { return truncated_; }
  std::size_t partial_bytes() const { return partial_bytes_; }
  std::uint64_t dropped_records() const { return dropped_records_; }
  // "recording 'P' is truncated (...): N whole records" when truncated, else "".
  std::string truncation_message() const;

  // Records [first, first + count) into `out` (count * record_bytes bytes);
  // false when the file cannot give them (a read error, a file cut since).
  bool read_records(std::uint64_t first, std::uint64_t count, unsigned char* out) const;
  // Asks the kernel to read these records ahead; never waits.
  void prefetch(std::uint64_t first, std::uint64_t count) const;

 private:
  std::string path_;
  int fd_ = -1;
  RecordingInfo info_;
  std::uint64_t data_offset_ = 0;  // Of the first record.
  std::uint64_t record_count_ = 0;
  bool truncated_ = false;
  std::size_t partial_bytes_ = 0;
  std::uint64_t dropped_records_ = 0;
};

}  // namespace hapticut::servo
