// libFuzzer harness for the servo's control message parser
// (server/control_message.h): the bytes a client sends, after the length
// prefix. The only exception allowed out is CommandError (MalformedMessage
// or a field refused); a message it accepts has a type of bounded length, an
// id it may echo, and fields every reader takes or refuses by name. Anything
// else (a crash, a sanitizer report, another exception, a hang) is a
// finding. Built and run for a bounded time by tests/scripts/fuzz.sh.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "control_message.h"

namespace {

using hapticut::servo::CommandError;
using hapticut::servo::ControlMessage;

// Every field reader on every key the protocol has: each must take the value
// or refuse it with CommandError.
void read_fields(const ControlMessage& message) {
  namespace s = hapticut::servo;
  static const char* const kKeys[] = {"version", "port",    "rate_Hz",    "engaged", "path",
                                      "action",  "blade",   "buttons",    "token",   "ramp_time_s",
                                      "shading", "devices", "max_force_N"};
  for (const char* key : kKeys) {
    try {
      (void)s::integer_field(message.body, key, 0, 65535);
    } catch (const CommandError&) {
    }
    try {
      (void)s::number_field(message.body, key, hapticut::setting_range::kRampTime);
    } catch (const CommandError&) {
    }
    try {
      (void)s::boolean_field(message.body, key);
    } catch (const CommandError&) {
    }
    try {
      (void)s::string_field(message.body, key, s::kMaxPathBytes);
    } catch (const CommandError&) {
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  ControlMessage message;
  try {
    message = hapticut::servo::parse_control_message(text);
  } catch (const CommandError&) {
    return 0;
  }
  if (message.type.empty() || message.type.size() > hapticut::servo::kMaxTypeBytes) std::abort();
  if (!message.id.is_null() && !message.id.is_number_integer() &&
      message.id.get_ref<const std::string&>().size() > hapticut::servo::kMaxIdBytes) {
    std::abort();
  }
  (void)hapticut::servo::quoted_excerpt(message.type);
  try {
    hapticut::servo::refuse_unknown_fields(message.body, {"port", "rate_Hz"});
  } catch (const CommandError&) {
  }
  read_fields(message);
  return 0;
}
