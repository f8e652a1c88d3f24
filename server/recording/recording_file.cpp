#include "recording/recording_file.h"

#include <cstring>
#include <nlohmann/json.hpp>

#include "devices/device_args.h"
#include "recording/recording_reader.h"

namespace hapticut::servo {

void lay_out_record(RecordingInfo& info) {
  std::size_t offset = sizeof(RecordHeader);
  for (RecordingBlade& blade : info.blades) {
    blade.offset = offset;
    offset += sizeof(BladeBlock) + points_block_bytes(blade.points);
  }
  info.cut_block_offset = offset;
  info.record_bytes = offset + sizeof(CutBlock);
}

std::vector<unsigned char> recording_preamble(const RecordingInfo& info) {
  nlohmann::json header;
  header["format"] = "hapticut.recording";
  header["version"] = kRecordVersion;
  header["rate_Hz"] = info.rate_Hz;
  header["as_fast_as_possible"] = info.as_fast_as_possible;
  header["scene"] = info.scene;
  header["record_bytes"] = info.record_bytes;
  header["tet_count"] = info.tet_count;
  header["cut_block"] = info.cut_block_offset;
  header["blades"] = nlohmann::json::array();
  for (const RecordingBlade& b : info.blades) {
    header["blades"].push_back({{"name", b.name},
                                {"device", b.device},
                                {"points", b.points},
                                {"offset", b.offset},
                                {"coupling", b.coupling}});
  }
  header["layout"] = nlohmann::json::parse(layout_json());
  std::string text = header.dump();
  while ((16 + text.size()) % 8 != 0) text.push_back(' ');
  std::vector<unsigned char> out(16 + text.size());
  std::memcpy(out.data(), kRecordingMagic, 8);
  const std::uint64_t length = text.size();
  std::memcpy(out.data() + 8, &length, 8);
  std::memcpy(out.data() + 16, text.data(), text.size());
  return out;
}

RecordingTrailer recording_trailer(std::uint64_t record_count, std::uint64_t dropped_records) {
  RecordingTrailer trailer;
  trailer.record_count = record_count;
  trailer.dropped_records = dropped_records;
  std::memcpy(trailer.end_marker, kRecordingEndMarker, sizeof(trailer.end_marker));
  return trailer;
}

std::string RecordingContents::truncation_message() const {
  if (!truncated) return "";
  std::string text =
      "recording '" + path +
      "' is truncated (no end trailer: the run was cut short): " + std::to_string(record_count()) +
      " whole records";
  if (partial_bytes > 0)
    text += ", a partial last record of " + std::to_string(partial_bytes) + " bytes dropped";
  return text;
}

RecordingContents read_recording(const std::string& path) {
  const RecordingReader reader(path);
  RecordingContents out;
  out.info = reader.info();
  out.truncated = reader.truncated();
  out.partial_bytes = reader.partial_bytes();
  out.dropped_records = reader.dropped_records();
  out.path = path;
  out.records.resize(reader.record_count() * reader.info().record_bytes);
  if (!reader.read_records(0, reader.record_count(), out.records.data())) {
    throw DeviceError("recording '" + path + "': cannot read its records");
  }
  return out;
}

}  // namespace hapticut::servo
