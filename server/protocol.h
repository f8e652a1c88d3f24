// The control channel's framing (docs/protocol.md): every message is a
// 4-byte big-endian length, then that many bytes of UTF-8 JSON (an object).
// MessageReader cuts a byte stream into messages; a length over its limit
// (kMaxMessageBytes unless lowered) is refused before any of it is buffered.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace hapticut::servo {

// 2: every blade's ideal pose in the frames and the records (frame version 3,
// record version 4), and a rigid blade's stiffness limit on its points' sum.
inline constexpr int kProtocolVersion = 3;
inline constexpr std::uint32_t kMaxMessageBytes = 16U << 20;  // 16 MiB (an inline scene).

class MessageReader {
 public:
  enum class Result { NeedMore, Message, TooLarge };

  void feed(const char* data, std::size_t size) { buffer_.append(data, size); }
  // The longest message taken from now on (at most kMaxMessageBytes).
  void set_limit(std::uint32_t limit) {
    limit_ = limit < kMaxMessageBytes ? limit : kMaxMessageBytes;
  }
  std::uint32_t limit() const { return limit_; }
  // Message: `message` holds the next one. TooLarge: `length` is the refused
  // prefix; the stream cannot be resynchronised (close it).
  Result next(std::string& message, std::uint32_t& length);
  std::size_t buffered() const { return buffer_.size(); }
  // Whether next() would return a message (or refuse one) without more bytes.
  bool has_message() const;
  // The next message's length, once its prefix is buffered.
  bool next_length(std::uint32_t& length) const;
  // Makes room for `bytes` at once, so that a large message is never copied
  // while it grows.
  void reserve(std::size_t bytes) { buffer_.reserve(bytes); }
  // Gives memory back once a large message has gone: the buffer keeps what it
  // holds, not the capacity the large one needed.
  void release_spare_capacity();

 private:
  std::string buffer_;
  std::uint32_t limit_ = kMaxMessageBytes;
};

// The length prefix and the text.
std::string frame_message(const std::string& json_text);

}  // namespace hapticut::servo
