// The recording file: every tick of a run, readable with numpy alone.
//   bytes 0-7   magic "HCREC001"
//   bytes 8-15  header length H, u64 little-endian
//   16..16+H    the header, JSON (UTF-8), padded with spaces so that the
//               records start at a multiple of 8
//   then        fixed-size records (layout.h: RecordHeader, then per blade a
//               BladeBlock and its points block, then a CutBlock),
//               record_bytes each
//   last        the trailer (layout.h: RecordingTrailer, ending "HCRECEND"),
//               written when the recording is closed cleanly
// A file without the trailer was cut short (killed, disk full): readers
// return its whole records, drop a partial last one and say it is truncated.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "layout.h"

namespace hapticut::servo {

inline constexpr char kRecordingMagic[8] = {'H', 'C', 'R', 'E', 'C', '0', '0', '1'};

struct RecordingBlade {
  std::string name;
  std::string device;  // The --device text it was bound to.
  std::uint32_t points = 0;
  std::size_t offset = 0;  // Of its BladeBlock within a record.
  std::string coupling;    // "rigid" or "independent": what its ideal pose means.
};

struct RecordingInfo {
  double rate_Hz = 1000.0;
  bool as_fast_as_possible = false;
  std::string scene;
  std::vector<RecordingBlade> blades;
  std::uint32_t tet_count = 0;       // The scene's: what the cut tets index.
  std::size_t cut_block_offset = 0;  // Of the CutBlock within a record.
  std::size_t record_bytes = 0;
};

// Offsets of every blade's block and the record size, from the point counts.
void lay_out_record(RecordingInfo& info);
// The bytes before the first record.
std::vector<unsigned char> recording_preamble(const RecordingInfo& info);

// The trailer that closes a recording of `record_count` records.
RecordingTrailer recording_trailer(std::uint64_t record_count, std::uint64_t dropped_records);

struct RecordingContents {
  RecordingInfo info;
  std::vector<unsigned char> records;  // record_count() * info.record_bytes bytes.
  // No trailer: the run was cut short. The whole records are all in `records`.
  bool truncated = false;
  std::size_t partial_bytes = 0;      // Of a cut last record, dropped.
  std::uint64_t dropped_records = 0;  // From the trailer (0 when truncated).
  std::string path;
  // "recording 'P' is truncated (...): N whole records" when truncated, else "".
  std::string truncation_message() const;
  std::size_t record_count() const {
    return info.record_bytes ? records.size() / info.record_bytes : 0;
  }
  const unsigned char* record(std::size_t i) const {
    return records.data() + i * info.record_bytes;
  }
};

// Reads a whole recording (tests and tools; the replay device reads a part at a
// time, recording_reader.h); throws DeviceError naming the file and what is
// wrong. A truncated file is read (see RecordingContents::truncated).
RecordingContents read_recording(const std::string& path);

}  // namespace hapticut::servo
