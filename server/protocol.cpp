#include "protocol.h"

namespace hapticut::servo {

MessageReader::Result MessageReader::next(std::string& message, std::uint32_t& length) {
  if (buffer_.size() < 4) return Result::NeedMore;
  const auto* b = reinterpret_cast<const unsigned char*>(buffer_.data());
  length = (std::uint32_t(b[0]) << 24) | (std::uint32_t(b[1]) << 16) | (std::uint32_t(b[2]) << 8) |
           std::uint32_t(b[3]);
  if (length > limit_) return Result::TooLarge;
  if (buffer_.size() < 4 + std::size_t(length)) return Result::NeedMore;
  message.assign(buffer_, 4, length);
  buffer_.erase(0, 4 + std::size_t(length));
  return Result::Message;
}

bool MessageReader::has_message() const {
  if (buffer_.size() < 4) return false;
  const auto* b = reinterpret_cast<const unsigned char*>(buffer_.data());
  const std::uint32_t length = (std::uint32_t(b[0]) << 24) | (std::uint32_t(b[1]) << 16) |
                               (std::uint32_t(b[2]) << 8) | std::uint32_t(b[3]);
  return length > limit_ || buffer_.size() >= 4 + std::size_t(length);
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
