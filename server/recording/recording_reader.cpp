#include "recording/recording_reader.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <limits>
#include <vector>

#include "client_files.h"
#include "devices/device_args.h"
#include "hapticut/scene_io.h"
#include "hapticut/scene_tree.h"

namespace hapticut::servo {

namespace {

// Exactly `size` bytes at `offset`; false when the file ends first or fails.
bool read_at(int fd, std::uint64_t offset, std::size_t size, unsigned char* out) {
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::pread(fd, out + done, size - done, static_cast<off_t>(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

// The header's fields, each refused by its name (never with the file's text).
class HeaderFields {
 public:
  HeaderFields(const SceneTree& header, std::string where)
      : header_(header), where_(std::move(where)) {}

  const SceneTree& at(const SceneTree& object, const char* key, const std::string& pointer) const {
    if (!object.is_object() || !object.contains(key)) fail(pointer + "/" + key, "missing");
    return object.at(key);
  }
  double number(const char* key) const {
    const SceneTree& value = at(header_, key, "");
    if (!value.is_number()) fail(std::string("/") + key, "expected a number");
    return value.get<double>();
  }
  std::uint64_t count(const SceneTree& object, const char* key, const std::string& pointer) const {
    const SceneTree& value = at(object, key, pointer);
    if (!value.is_number_unsigned()) fail(pointer + "/" + key, "expected a whole number");
    return value.get<std::uint64_t>();
  }
  std::string text(const SceneTree& object, const char* key, const std::string& pointer,
                   bool required) const {
    if (!required && (!object.is_object() || !object.contains(key))) return "";
    const SceneTree& value = at(object, key, pointer);
    if (!value.is_string()) fail(pointer + "/" + key, "expected a string");
    return value.get<std::string>();
  }
  [[noreturn]] void fail(const std::string& pointer, const std::string& reason) const {
    throw DeviceError(where_ + "bad header: " + pointer + ": " + reason);
  }

 private:
  const SceneTree& header_;
  std::string where_;
};

}  // namespace

RecordingReader::RecordingReader(const std::string& path) : path_(path) {
  const std::string where = "recording '" + path + "': ";
  std::uint64_t size = 0;
  try {
    fd_ = open_regular_file(path, std::numeric_limits<std::uint64_t>::max(), size);
  } catch (const FileRefused& e) {
    throw DeviceError(std::string("recording ") + e.what());
  }
  try {
    unsigned char start[16];
    if (size < 16 || !read_at(fd_, 0, 16, start) || std::memcmp(start, kRecordingMagic, 8) != 0) {
      throw DeviceError(where + "not a hapticut recording (no HCREC001 magic)");
    }
    std::uint64_t length = 0;
    std::memcpy(&length, start + 8, 8);
    if (length > size - 16) throw DeviceError(where + "header longer than the file");
    if (length > kMaxRecordingHeaderBytes) {
      throw DeviceError(where + "header of " + std::to_string(length) +
                        " bytes is over the limit of " + std::to_string(kMaxRecordingHeaderBytes));
    }
    std::vector<unsigned char> text(length);
    if (!read_at(fd_, 16, text.size(), text.data())) {
      throw DeviceError(where + "cannot read its header");
    }
    SceneTree header;
    try {
      header = decode_scene_tree(
          std::string_view(reinterpret_cast<const char*>(text.data()), text.size()),
          SceneEncoding::Json);
    } catch (const SceneError& e) {
      throw DeviceError(where + "bad header (" + e.what() + ")");
    }
    const HeaderFields fields(header, where);
    const std::uint64_t version = header.is_object() && header.contains("version") &&
                                          header.at("version").is_number_unsigned()
                                      ? header.at("version").get<std::uint64_t>()
                                      : 0;
    if (version != static_cast<std::uint64_t>(kRecordVersion)) {
      throw DeviceError(where + "record version " + std::to_string(version) +
                        ", this servo reads version " + std::to_string(kRecordVersion) +
                        " only (record it again with this servo)");
    }
    info_.rate_Hz = fields.number("rate_Hz");
    info_.as_fast_as_possible = header.contains("as_fast_as_possible") &&
                                header.at("as_fast_as_possible").is_boolean() &&
                                header.at("as_fast_as_possible").get<bool>();
    info_.scene = fields.text(header, "scene", "", false);
    const SceneTree& blades = fields.at(header, "blades", "");
    if (!blades.is_array() || blades.empty()) fields.fail("/blades", "expected a non-empty list");
    for (std::size_t i = 0; i < blades.size(); ++i) {
      const std::string pointer = "/blades/" + std::to_string(i);
      const SceneTree& b = blades[i];
      const std::uint64_t points = fields.count(b, "points", pointer);
      if (points == 0 || points > 65535) fields.fail(pointer + "/points", "expected 1 to 65535");
      info_.blades.push_back(
          {fields.text(b, "name", pointer, true), fields.text(b, "device", pointer, false),
           static_cast<std::uint32_t>(points), 0, fields.text(b, "coupling", pointer, false)});
    }
    info_.tet_count = static_cast<std::uint32_t>(fields.count(header, "tet_count", ""));
    lay_out_record(info_);
    const std::uint64_t stated = fields.count(header, "record_bytes", "");
    if (info_.record_bytes != stated) {
      throw DeviceError(where + "record_bytes " + std::to_string(stated) +
                        " disagrees with this servo's layout (" +
                        std::to_string(info_.record_bytes) + ")");
    }
    data_offset_ = 16 + length;
    const std::uint64_t body = size - data_offset_;
    const std::uint64_t record_bytes = info_.record_bytes;
    record_count_ = body / record_bytes;
    // The trailer is shorter than a record: a complete file's body is whole
    // records and one trailer, which ends with the marker.
    RecordingTrailer trailer{};
    const bool has_trailer =
        body % record_bytes == sizeof(RecordingTrailer) &&
        read_at(fd_, size - sizeof(trailer), sizeof(trailer),
                reinterpret_cast<unsigned char*>(&trailer)) &&
        std::memcmp(trailer.end_marker, kRecordingEndMarker, sizeof(kRecordingEndMarker)) == 0;
    if (has_trailer) {
      if (trailer.record_count != record_count_) {
        throw DeviceError(where + "damaged: its trailer counts " +
                          std::to_string(trailer.record_count) + " records, the file holds " +
                          std::to_string(record_count_));
      }
      dropped_records_ = trailer.dropped_records;
    } else {
      truncated_ = true;
      partial_bytes_ = body - record_count_ * record_bytes;
    }
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    throw;
  }
}

RecordingReader::~RecordingReader() {
  if (fd_ >= 0) ::close(fd_);
}

std::string RecordingReader::truncation_message() const {
  if (!truncated_) return "";
  std::string text =
      "recording '" + path_ +
      "' is truncated (no end trailer: the run was cut short): " + std::to_string(record_count_) +
      " whole records";
  if (partial_bytes_ > 0) {
    text += ", a partial last record of " + std::to_string(partial_bytes_) + " bytes dropped";
  }
  return text;
}

bool RecordingReader::read_records(std::uint64_t first, std::uint64_t count,
                                   unsigned char* out) const {
  if (first > record_count_ || count > record_count_ - first) return false;
  return read_at(fd_, data_offset_ + first * info_.record_bytes, count * info_.record_bytes, out);
}

void RecordingReader::prefetch(std::uint64_t first, std::uint64_t count) const {
  if (first >= record_count_) return;
  count = std::min(count, record_count_ - first);
  (void)::posix_fadvise(fd_, static_cast<off_t>(data_offset_ + first * info_.record_bytes),
                        static_cast<off_t>(count * info_.record_bytes), POSIX_FADV_WILLNEED);
}

}  // namespace hapticut::servo
