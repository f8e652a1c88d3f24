#include "recording/recording_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>

#include "client_files.h"
#include "devices/device_args.h"

namespace hapticut::servo {

void lay_out_record(RecordingInfo& info) {
  std::size_t offset = sizeof(RecordHeader);
  for (RecordingBlade& blade : info.blades) {
    blade.offset = offset;
    offset += sizeof(BladeBlock) + points_block_bytes(blade.points);
  }
  info.record_bytes = offset;
}

std::vector<unsigned char> recording_preamble(const RecordingInfo& info) {
  nlohmann::json header;
  header["format"] = "hapticut.recording";
  header["version"] = kRecordVersion;
  header["rate_Hz"] = info.rate_Hz;
  header["as_fast_as_possible"] = info.as_fast_as_possible;
  header["scene"] = info.scene;
  header["record_bytes"] = info.record_bytes;
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
  const std::string where = "recording '" + path + "': ";
  // A FIFO or a device would block the caller (the control thread, for a
  // `load`) or never end (/dev/zero): refused before a byte is read.
  std::vector<unsigned char> bytes;
  try {
    bytes = read_regular_file(path, std::numeric_limits<std::uint64_t>::max());
  } catch (const FileRefused& e) {
    throw DeviceError(std::string("recording ") + e.what());
  }
  if (bytes.size() < 16 || std::memcmp(bytes.data(), kRecordingMagic, 8) != 0) {
    throw DeviceError(where + "not a hapticut recording (no HCREC001 magic)");
  }
  std::uint64_t length = 0;
  std::memcpy(&length, bytes.data() + 8, 8);
  if (length > bytes.size() - 16) throw DeviceError(where + "header longer than the file");
  RecordingContents out;
  try {
    const auto header = nlohmann::json::parse(bytes.begin() + 16, bytes.begin() + 16 + length);
    const int version = header.value("version", 0);
    if (version != kRecordVersion) {
      throw DeviceError(where + "record version " + std::to_string(version) +
                        ", this servo reads version " + std::to_string(kRecordVersion) +
                        " only (record it again with this servo)");
    }
    out.info.rate_Hz = header.at("rate_Hz").get<double>();
    out.info.as_fast_as_possible = header.value("as_fast_as_possible", false);
    out.info.scene = header.value("scene", "");
    for (const auto& b : header.at("blades")) {
      out.info.blades.push_back({b.at("name").get<std::string>(), b.value("device", ""),
                                 b.at("points").get<std::uint32_t>(), 0, b.value("coupling", "")});
    }
    lay_out_record(out.info);
    if (out.info.record_bytes != header.at("record_bytes").get<std::size_t>()) {
      throw DeviceError(
          where + "record_bytes " + std::to_string(header.at("record_bytes").get<std::size_t>()) +
          " disagrees with this servo's layout (" + std::to_string(out.info.record_bytes) + ")");
    }
  } catch (const nlohmann::json::exception& e) {
    throw DeviceError(where + "bad header (" + e.what() + ")");
  }
  const std::size_t data = 16 + length;
  const std::size_t body = bytes.size() - data;
  const std::size_t record_bytes = out.info.record_bytes;
  const std::size_t trailer_bytes = sizeof(RecordingTrailer);
  std::size_t count = body / record_bytes;
  // The trailer is shorter than a record: a complete file's body is whole
  // records and one trailer, which ends with the marker.
  const bool has_trailer = body % record_bytes == trailer_bytes &&
                           std::memcmp(bytes.data() + bytes.size() - sizeof(kRecordingEndMarker),
                                       kRecordingEndMarker, sizeof(kRecordingEndMarker)) == 0;
  if (has_trailer) {
    RecordingTrailer trailer;
    std::memcpy(&trailer, bytes.data() + bytes.size() - trailer_bytes, trailer_bytes);
    if (trailer.record_count != count) {
      throw DeviceError(where + "damaged: its trailer counts " +
                        std::to_string(trailer.record_count) + " records, the file holds " +
                        std::to_string(count));
    }
    out.dropped_records = trailer.dropped_records;
  } else {
    out.truncated = true;
    out.partial_bytes = body - count * record_bytes;
  }
  out.path = path;
  out.records.assign(bytes.begin() + static_cast<std::ptrdiff_t>(data),
                     bytes.begin() + static_cast<std::ptrdiff_t>(data + count * record_bytes));
  return out;
}

}  // namespace hapticut::servo
