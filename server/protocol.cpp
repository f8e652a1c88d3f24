#include "protocol.h"

namespace hapticut::servo {

MessageReader::Result MessageReader::next(std::string& message, std::uint32_t& length) {
  if (buffer_.size() < 4) return Result::NeedMore;
  const auto* b = reinterpret_cast<const unsigned char*>(buffer_.data());
  length = (std::uint32_t(b[0]) << 24) | (std::uint32_t(b[1]) << 16) | (std::uint32_t(b[2]) << 8) |
           std::uint32_t(b[3]);
  if (length > limit_) return Result::TooLarge;
  if (buffer_.size() < 4 + std::size_t(length)) return Result::NeedMore;
  if (buffer_.size() == 4 + std::size_t(length)) {
    // The whole buffer is this message (a large one always is): hand it over
    // rather than copy it, so that it is held once.
    message = std::move(buffer_);
    buffer_ = std::string();
    message.erase(0, 4);
    return Result::Message;
  }
  message.assign(buffer_, 4, length);
  buffer_.erase(0, 4 + std::size_t(length));
  return Result::Message;
}

bool MessageReader::next_length(std::uint32_t& length) const {
  if (buffer_.size() < 4) return false;
  const auto* b = reinterpret_cast<const unsigned char*>(buffer_.data());
  length = (std::uint32_t(b[0]) << 24) | (std::uint32_t(b[1]) << 16) | (std::uint32_t(b[2]) << 8) |
           std::uint32_t(b[3]);
  return true;
}

bool MessageReader::has_message() const {
  std::uint32_t length = 0;
  if (!next_length(length)) return false;
  return length > limit_ || buffer_.size() >= 4 + std::size_t(length);
}

void MessageReader::release_spare_capacity() {
  if (buffer_.capacity() > 2 * buffer_.size() + 65536) std::string(buffer_).swap(buffer_);
}

std::string frame_message(const std::string& json_text) {
  const auto n = static_cast<std::uint32_t>(json_text.size());
  std::string out;
  out.reserve(4 + json_text.size());
  out.push_back(static_cast<char>((n >> 24) & 0xFF));
  out.push_back(static_cast<char>((n >> 16) & 0xFF));
  out.push_back(static_cast<char>((n >> 8) & 0xFF));
  out.push_back(static_cast<char>(n & 0xFF));
  out += json_text;
  return out;
}

}  // namespace hapticut::servo
