// The recording reader: a complete file (trailer) against files cut short
// at every kind of place, and files it must refuse.
#include "recording/recording_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "devices/device_args.h"

namespace hapticut::servo {
namespace {

RecordingInfo two_blade_info() {
  RecordingInfo info;
  info.rate_Hz = 1000.0;
  info.scene = "test.hapticut.json";
  info.blades = {{"scalpel", "sim", 5, 0}, {"retractor", "viewport", 2, 0}};
  lay_out_record(info);
  return info;
}

// Records whose header.tick is their index, so a test can tell them apart.
std::vector<unsigned char> records_of(const RecordingInfo& info, std::size_t count) {
  std::vector<unsigned char> out(count * info.record_bytes, 0);
  for (std::size_t i = 0; i < count; ++i) {
    RecordHeader header;
    header.tick = i;
    header.blade_count = 2;
    std::memcpy(out.data() + i * info.record_bytes, &header, sizeof(header));
  }
  return out;
}

std::vector<unsigned char> complete_file(const RecordingInfo& info, std::size_t count,
                                         std::uint64_t dropped) {
  std::vector<unsigned char> bytes = recording_preamble(info);
  const std::vector<unsigned char> records = records_of(info, count);
  bytes.insert(bytes.end(), records.begin(), records.end());
  const RecordingTrailer trailer = recording_trailer(count, dropped);
  const auto* raw = reinterpret_cast<const unsigned char*>(&trailer);
  bytes.insert(bytes.end(), raw, raw + sizeof(trailer));
  return bytes;
}

std::string write_file(const std::string& name, const std::vector<unsigned char>& bytes) {
  std::string path = ::testing::TempDir() + name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  return path;
}

std::string error_of(const std::string& path) {
  try {
    read_recording(path);
  } catch (const DeviceError& e) {
    return e.what();
  }
  return "";
}

void expect_ticks(const RecordingContents& contents, std::size_t count) {
  ASSERT_EQ(contents.record_count(), count);
  for (std::size_t i = 0; i < count; ++i) {
    RecordHeader header;
    std::memcpy(&header, contents.record(i), sizeof(header));
    EXPECT_EQ(header.tick, i);
  }
}

TEST(RecordingFile, ACompleteRecordingIsCompleteWithItsTrailersCounts) {
  const RecordingInfo info = two_blade_info();
  const std::string path = write_file("complete.rec", complete_file(info, 7, 3));
  const RecordingContents contents = read_recording(path);
  EXPECT_FALSE(contents.truncated);
  EXPECT_EQ(contents.truncation_message(), "");
  EXPECT_EQ(contents.dropped_records, 3U);
  expect_ticks(contents, 7);
}

TEST(RecordingFile, AnEmptyCompleteRecordingIsComplete) {
  const std::string path = write_file("empty.rec", complete_file(two_blade_info(), 0, 0));
  const RecordingContents contents = read_recording(path);
  EXPECT_FALSE(contents.truncated);
  EXPECT_EQ(contents.record_count(), 0U);
}

TEST(RecordingFile, CutOnARecordBoundaryIsTruncatedWithEveryWholeRecord) {
  const RecordingInfo info = two_blade_info();
  std::vector<unsigned char> bytes = complete_file(info, 7, 0);
  bytes.resize(bytes.size() - sizeof(RecordingTrailer));
  const std::string path = write_file("boundary.rec", bytes);
  const RecordingContents contents = read_recording(path);
  EXPECT_TRUE(contents.truncated);
  EXPECT_EQ(contents.partial_bytes, 0U);
  expect_ticks(contents, 7);
  EXPECT_EQ(contents.truncation_message(),
            "recording '" + path +
                "' is truncated (no end trailer: the run was cut short): " + "7 whole records");
}

TEST(RecordingFile, CutInsideTheTrailerOrARecordIsTruncated) {
  const RecordingInfo info = two_blade_info();
  const std::vector<unsigned char> full = complete_file(info, 4, 0);
  const std::size_t records_start = full.size() - sizeof(RecordingTrailer) - 4 * info.record_bytes;
  // Around every record boundary from the second record on, and every byte of the trailer.
  std::vector<std::size_t> sizes;
  for (std::size_t record = 2; record < 4; ++record) {
    for (const std::size_t into :
         {std::size_t{0}, std::size_t{1}, info.record_bytes / 2, info.record_bytes - 1}) {
      sizes.push_back(records_start + record * info.record_bytes + into);
    }
  }
  for (std::size_t into = 0; into < sizeof(RecordingTrailer); ++into) {
    sizes.push_back(records_start + 4 * info.record_bytes + into);
  }
  for (const std::size_t size : sizes) {
    const std::vector<unsigned char> bytes(full.begin(),
                                           full.begin() + static_cast<std::ptrdiff_t>(size));
    const RecordingContents contents = read_recording(write_file("cut.rec", bytes));
    EXPECT_TRUE(contents.truncated) << size;
    const std::size_t whole = std::min<std::size_t>(4, (size - records_start) / info.record_bytes);
    expect_ticks(contents, whole);
    EXPECT_NE(contents.truncation_message().find(std::to_string(whole) + " whole records"),
              std::string::npos);
  }
}

TEST(RecordingFile, ATrailerThatMiscountsIsRefused) {
  const RecordingInfo info = two_blade_info();
  std::vector<unsigned char> bytes = complete_file(info, 5, 0);
  // A record lost from the middle: the trailer still counts five.
  bytes.erase(
      bytes.end() - static_cast<std::ptrdiff_t>(sizeof(RecordingTrailer) + info.record_bytes),
      bytes.end() - static_cast<std::ptrdiff_t>(sizeof(RecordingTrailer)));
  const std::string path = write_file("miscount.rec", bytes);
  EXPECT_EQ(error_of(path),
            "recording '" + path + "': damaged: its trailer counts 5 records, the file holds 4");
}

TEST(RecordingFile, AnOlderVersionIsRefusedNamingBothVersions) {
  const RecordingInfo info = two_blade_info();
  std::vector<unsigned char> bytes = complete_file(info, 2, 0);
  const std::string current = "\"version\":" + std::to_string(kRecordVersion);
  const std::string older = "\"version\":" + std::to_string(kRecordVersion - 1);
  std::string text(bytes.begin(), bytes.end());
  const std::size_t at = text.find(current);
  ASSERT_NE(at, std::string::npos);
  text.replace(at, current.size(), older);
  const std::string path =
      write_file("old.rec", std::vector<unsigned char>(text.begin(), text.end()));
  EXPECT_EQ(error_of(path), "recording '" + path + "': record version " +
                                std::to_string(kRecordVersion - 1) + ", this servo reads version " +
                                std::to_string(kRecordVersion) +
                                " only (record it again with this servo)");
}

TEST(RecordingFile, WhatIsNotARegularFileIsRefusedWithoutWaiting) {
  const std::string fifo = ::testing::TempDir() + "recording.fifo";
  ::unlink(fifo.c_str());
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // No writer ever opens it: a blocking open would never return.
  EXPECT_EQ(error_of(fifo), "recording '" + fifo + "': not a regular file (a FIFO)");
  ::unlink(fifo.c_str());
  EXPECT_EQ(error_of("/dev/zero"),
            "recording '/dev/zero': not a regular file (a character device)");
  EXPECT_EQ(error_of(::testing::TempDir()),
            "recording '" + ::testing::TempDir() + "': not a regular file (a directory)");
  const std::string missing = ::testing::TempDir() + "no-such.rec";
  EXPECT_EQ(error_of(missing), "recording '" + missing + "': No such file or directory");
}

TEST(RecordingFile, NotARecordingIsNamed) {
  const std::string path = write_file("not.rec", {'H', 'C', 'R', 'E', 'C'});
  EXPECT_EQ(error_of(path),
            "recording '" + path + "': not a hapticut recording (no HCREC001 magic)");
}

}  // namespace
}  // namespace hapticut::servo
