// The lock-free handoffs between the servo's threads (LatestValue, TripleBuffer,
// SpscRing), each with its writer and its reader on two threads: every value the
// reader gets is whole (no field from another write) and in order. Under
// ThreadSanitizer (tests/scripts/tsan.sh) a missing ordering is also a report.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <memory>
#include <thread>

#include "rt/latest_value.h"
#include "rt/spsc_ring.h"
#include "rt/triple_buffer.h"

namespace hapticut::servo {
namespace {

// 68 bytes: the last of its words is only half used.
struct Sample {
  std::array<std::uint32_t, 17> fields;
};

TEST(HandoffThreads, LatestValueReadsAreWholeAndInOrder) {
  constexpr std::uint32_t kWrites = 20000;
  LatestValue<Sample> value;
  std::thread writer([&] {
    for (std::uint32_t k = 1; k <= kWrites; ++k) {
      Sample s;
      s.fields.fill(k);
      value.publish(s);
    }
  });
  std::uint32_t last = 0;
  int torn = 0;
  int backwards = 0;
  int miscounted = 0;
  while (last < kWrites) {
    Sample s{};
    const std::uint64_t count = value.read(s);
    if (count == 0) continue;
    for (std::uint32_t f : s.fields) torn += f != s.fields[0] ? 1 : 0;
    backwards += s.fields[0] < last ? 1 : 0;
    miscounted += count != s.fields[0] ? 1 : 0;
    last = s.fields[0];
    std::this_thread::yield();
  }
  writer.join();
  EXPECT_EQ(torn, 0);
  EXPECT_EQ(backwards, 0);
  EXPECT_EQ(miscounted, 0);
}

struct Frame {
  std::uint64_t sequence;
  std::array<std::uint64_t, 1024> payload;
};

TEST(HandoffThreads, TripleBufferFramesAreWholeAndNewer) {
  constexpr std::uint64_t kFrames = 3000;
  auto buffer = std::make_unique<TripleBuffer<Frame>>();
  std::thread writer([&] {
    for (std::uint64_t k = 1; k <= kFrames; ++k) {
      Frame& f = buffer->back();
      f.payload.fill(k);
      f.sequence = k;
      buffer->publish();
    }
  });
  std::uint64_t last = 0;
  int torn = 0;
  int not_newer = 0;
  while (last < kFrames) {
    if (!buffer->fetch()) {
      std::this_thread::yield();
      continue;
    }
    const Frame& f = buffer->front();
    for (std::uint64_t word : f.payload) torn += word != f.sequence ? 1 : 0;
    not_newer += f.sequence <= last ? 1 : 0;
    last = f.sequence;
  }
  writer.join();
  EXPECT_EQ(torn, 0);
  EXPECT_EQ(not_newer, 0);
}

TEST(HandoffThreads, SpscRingDeliversEveryRecordInOrder) {
  constexpr std::uint64_t kRecords = 50000;
  constexpr std::size_t kSlotBytes = 40;  // Five words, all the record's number.
  SpscRing ring(kSlotBytes, 16);
  std::thread producer([&] {
    for (std::uint64_t k = 1; k <= kRecords;) {
      unsigned char* slot = ring.begin_push();
      if (slot == nullptr) {  // Full: the recorder is behind; try again.
        std::this_thread::yield();
        continue;
      }
      for (std::size_t w = 0; w < kSlotBytes / 8; ++w) std::memcpy(slot + w * 8, &k, 8);
      ring.end_push();
      ++k;
    }
  });
  std::uint64_t expected = 1;
  int wrong = 0;
  while (expected <= kRecords) {
    const unsigned char* slot = ring.front();
    if (slot == nullptr) {
      std::this_thread::yield();
      continue;
    }
    for (std::size_t w = 0; w < kSlotBytes / 8; ++w) {
      std::uint64_t word = 0;
      std::memcpy(&word, slot + w * 8, 8);
      wrong += word != expected ? 1 : 0;
    }
    ring.pop();
    ++expected;
  }
  producer.join();
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(ring.front(), nullptr);
}

}  // namespace
}  // namespace hapticut::servo
