// One control message (docs/protocol.md) and its fields, read without trusting
// the client: the text goes through the scene reader's decoder (bounded
// nesting, linear time, duplicate keys, a NUL byte, invalid UTF-8 and trailing
// bytes refused), and every field is read by a function that checks its type
// and range and names the field when it refuses. No error echoes more than
// kMaxEchoBytes of what the client sent.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <string_view>

#include "hapticut/parameter_range.h"

namespace hapticut::servo {

// The decoded message: members keep their order (the scene reader's tree).
using ControlJson = nlohmann::ordered_json;

// A command that cannot be done; the reply's "error" is its message.
class CommandError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A message that is not a well-formed request (counted as malformed).
class MalformedMessage : public CommandError {
 public:
  using CommandError::CommandError;
};

inline constexpr std::size_t kMaxTypeBytes = 32;
inline constexpr std::size_t kMaxIdBytes = 64;      // A string "id"; an integer one is any.
inline constexpr std::size_t kMaxEchoBytes = 64;    // Of client text quoted in an error.
inline constexpr std::size_t kMaxPathBytes = 4096;  // PATH_MAX.
inline constexpr std::size_t kMaxNameBytes = 256;   // A blade's name, a --device text.
inline constexpr std::size_t kMaxTokenBytes = 4096;

struct ControlMessage {
  ControlJson body;
  std::string type;
  ControlJson id;  // Null when the request has none; echoed in the reply.
};

// Throws MalformedMessage: not JSON (the decoder's reason, never the bytes),
// not an object, no string "type" of 1 to kMaxTypeBytes bytes, an "id" that is
// neither an integer nor a string of at most kMaxIdBytes bytes.
ControlMessage parse_control_message(std::string_view text);

// Throws CommandError naming the first field of `message` that is neither
// "type", "id" nor one of `known`, and the fields the message type takes.
void refuse_unknown_fields(const ControlJson& message, std::initializer_list<const char*> known);

// The field readers: each throws CommandError "<key>: <reason>".
bool has_field(const ControlJson& message, const char* key);
// An integer (not 1.0, not true) within [minimum, maximum].
std::int64_t integer_field(const ControlJson& message, const char* key, std::int64_t minimum,
                           std::int64_t maximum);
// A finite number within the engine's range for it (the scene file's table).
double number_field(const ControlJson& message, const char* key, const ParameterRange& range);
// A finite number within [minimum, maximum].
double number_field(const ControlJson& message, const char* key, double minimum, double maximum);
bool boolean_field(const ControlJson& message, const char* key);
// A string of 1 to max_bytes bytes without a NUL.
std::string string_field(const ControlJson& message, const char* key, std::size_t max_bytes);

// Client text for an error: at most kMaxEchoBytes, in quotes, anything outside
// printable ASCII as \xNN (printable(), hapticut/scene_tree.h), "..." when cut.
std::string quoted_excerpt(std::string_view text);

}  // namespace hapticut::servo
