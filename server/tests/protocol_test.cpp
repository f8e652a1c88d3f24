// Framing of the control channel, and the lock-free handoffs of the loop.
#include "protocol.h"

#include <gtest/gtest.h>

#include "rt/histogram.h"
#include "rt/spsc_ring.h"
#include "rt/triple_buffer.h"

namespace hapticut::servo {
namespace {

TEST(MessageReader, SplitsAStreamIntoMessages) {
  MessageReader reader;
  const std::string bytes = frame_message(R"({"type":"hello"})") + frame_message("{}");
  std::string message;
  std::uint32_t length = 0;
  reader.feed(bytes.data(), 3);  // Not even a full prefix yet.
  EXPECT_EQ(reader.next(message, length), MessageReader::Result::NeedMore);
  reader.feed(bytes.data() + 3, bytes.size() - 3);
  ASSERT_EQ(reader.next(message, length), MessageReader::Result::Message);
  EXPECT_EQ(message, R"({"type":"hello"})");
  ASSERT_EQ(reader.next(message, length), MessageReader::Result::Message);
  EXPECT_EQ(message, "{}");
  EXPECT_EQ(reader.next(message, length), MessageReader::Result::NeedMore);
  EXPECT_EQ(reader.buffered(), 0U);
}

TEST(MessageReader, RefusesAHugeLengthBeforeBuffering) {
  MessageReader reader;
  const unsigned char gigabyte[4] = {0x40, 0, 0, 0};
  reader.feed(reinterpret_cast<const char*>(gigabyte), 4);
  std::string message;
  std::uint32_t length = 0;
  EXPECT_EQ(reader.next(message, length), MessageReader::Result::TooLarge);
  EXPECT_EQ(length, 1U << 30);
}

TEST(MessageReader, ALoweredLimitRefusesWhatTheFullOneTakes) {
  MessageReader reader;
  reader.set_limit(8);
  const std::string bytes = frame_message(R"({"type":"hello"})");
  reader.feed(bytes.data(), bytes.size());
  std::string message;
  std::uint32_t length = 0;
  EXPECT_TRUE(reader.has_message());
  EXPECT_EQ(reader.next(message, length), MessageReader::Result::TooLarge);
  reader.set_limit(kMaxMessageBytes + 1);  // Never above the protocol's own limit.
  EXPECT_EQ(reader.limit(), kMaxMessageBytes);
  EXPECT_EQ(reader.next(message, length), MessageReader::Result::Message);
}

TEST(SpscRing, FullRingRefusesAndEmptiesInOrder) {
  SpscRing ring(8, 2);
  for (unsigned char v = 1; v <= 2; ++v) {
    unsigned char* slot = ring.begin_push();
    ASSERT_NE(slot, nullptr);
    slot[0] = v;
    ring.end_push();
  }
  EXPECT_EQ(ring.begin_push(), nullptr);  // Full: the producer counts a drop.
  ASSERT_NE(ring.front(), nullptr);
  EXPECT_EQ(ring.front()[0], 1);
  ring.pop();
  EXPECT_EQ(ring.front()[0], 2);
  ring.pop();
  EXPECT_EQ(ring.front(), nullptr);
}

TEST(TripleBuffer, ReaderGetsTheNewestOnly) {
  TripleBuffer<int> buffer;
  EXPECT_FALSE(buffer.fetch());
  buffer.back() = 1;
  buffer.publish();
  buffer.back() = 2;
  buffer.publish();
  ASSERT_TRUE(buffer.fetch());
  EXPECT_EQ(buffer.front(), 2);
  EXPECT_FALSE(buffer.fetch());
}

TEST(LatencyHistogram, PercentilesWithinABin) {
  auto h = std::make_unique<LatencyHistogram>();
  for (int i = 1; i <= 1000; ++i) h->add(double(i));
  EXPECT_NEAR(h->percentile_us(0.5), 500.0, 500.0 * 0.021);
  EXPECT_NEAR(h->percentile_us(0.99), 990.0, 990.0 * 0.021);
  EXPECT_EQ(h->max_us(), 1000.0);
  EXPECT_EQ(h->count(), 1000U);
  h->clear();
  EXPECT_EQ(h->percentile_us(0.5), 0.0);
}

}  // namespace
}  // namespace hapticut::servo
