#include "control_message.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "hapticut/scene_io.h"
#include "hapticut/scene_tree.h"

namespace hapticut::servo {

namespace {

[[noreturn]] void refuse(const char* key, const std::string& reason) {
  throw CommandError(std::string(key) + ": " + reason);
}

const ControlJson& field(const ControlJson& message, const char* key) {
  const auto it = message.find(key);
  if (it == message.end()) refuse(key, "missing");
  return *it;
}

// Whether a key or a string anywhere in `value` holds a NUL (JSON's \u0000),
// which the decoder lets through and which would cut a C string short.
bool holds_nul(const ControlJson& value) {
  if (value.is_string()) return value.get_ref<const std::string&>().find('\0') != std::string::npos;
  if (value.is_object()) {
    for (const auto& [key, item] : value.items()) {
      if (key.find('\0') != std::string::npos || holds_nul(item)) return true;
    }
  }
  if (value.is_array()) {
    for (const ControlJson& item : value) {
      if (holds_nul(item)) return true;
    }
  }
  return false;
}

}  // namespace

void refuse_unknown_fields(const ControlJson& message, std::initializer_list<const char*> known) {
  for (const auto& [key, value] : message.items()) {
    if (key == "type" || key == "id") continue;
    const bool found = std::any_of(known.begin(), known.end(),
                                   [&key = key](const char* name) { return key == name; });
    if (found) continue;
    std::string names;
    for (const char* name : known) names += (names.empty() ? "" : ", ") + std::string(name);
    throw CommandError("unknown field " + quoted_excerpt(key) + " (\"" +
                       message.at("type").get<std::string>() + "\" takes " +
                       (names.empty() ? std::string("none") : names) + ")");
  }
}

std::string quoted_excerpt(std::string_view text) {
  const bool cut = text.size() > kMaxEchoBytes;
  if (cut) text = text.substr(0, kMaxEchoBytes);
  return "'" + printable(text) + (cut ? "'..." : "'");
}

ControlMessage parse_control_message(std::string_view text) {
  // JSON text exchanged between systems must not begin with a byte order mark (RFC 8259, 8.1).
  if (text.substr(0, 3) == "\xEF\xBB\xBF") {
    throw MalformedMessage("malformed JSON: a byte order mark before the object");
  }
  ControlMessage message;
  try {
    message.body = decode_scene_tree(text, SceneEncoding::Json);
  } catch (const SceneError& e) {
    throw MalformedMessage(std::string("malformed JSON: ") + e.what());
  }
  const ControlJson& body = message.body;
  if (!body.is_object()) throw MalformedMessage("malformed message: expected an object");
  if (holds_nul(body)) {
    throw MalformedMessage("malformed message: a key or string holds \\u0000 (NUL)");
  }
  const auto type = body.find("type");
  if (type == body.end() || !type->is_string()) {
    throw MalformedMessage("malformed message: expected an object with a string \"type\"");
  }
  message.type = type->get<std::string>();
  if (message.type.empty() || message.type.size() > kMaxTypeBytes) {
    throw MalformedMessage("type: expected 1 to " + std::to_string(kMaxTypeBytes) + " bytes");
  }
  const auto id = body.find("id");
  if (id != body.end()) {
    const bool fits = id->is_number_integer() ||
                      (id->is_string() && id->get_ref<const std::string&>().size() <= kMaxIdBytes);
    if (!fits) {
      throw MalformedMessage("id: expected an integer or a string of at most " +
                             std::to_string(kMaxIdBytes) + " bytes");
    }
    message.id = *id;
  }
  return message;
}

bool has_field(const ControlJson& message, const char* key) { return message.contains(key); }

std::int64_t integer_field(const ControlJson& message, const char* key, std::int64_t minimum,
                           std::int64_t maximum) {
  const ControlJson& value = field(message, key);
  const std::string range = std::to_string(minimum) + " to " + std::to_string(maximum);
  if (!value.is_number_integer()) refuse(key, "expected an integer, " + range);
  if (value.is_number_unsigned()) {
    const auto v = value.get<std::uint64_t>();
    const bool below = minimum > 0 && v < static_cast<std::uint64_t>(minimum);
    if (below || v > static_cast<std::uint64_t>(maximum)) {
      refuse(key, "out of range (" + range + ")");
    }
    return static_cast<std::int64_t>(v);
  }
  const auto v = value.get<std::int64_t>();
  if (v < minimum || v > maximum) refuse(key, "out of range (" + range + ")");
  return v;
}

double number_field(const ControlJson& message, const char* key, const ParameterRange& range) {
  const ControlJson& value = field(message, key);
  if (!value.is_number()) refuse(key, "expected a number");
  const double v = value.get<double>();
  const std::string reason = range_reason(range, v);
  if (!reason.empty()) refuse(key, reason);
  return v;
}

double number_field(const ControlJson& message, const char* key, double minimum, double maximum) {
  const ControlJson& value = field(message, key);
  if (!value.is_number()) refuse(key, "expected a number");
  const double v = value.get<double>();
  if (!std::isfinite(v) || v < minimum || v > maximum) {
    refuse(key, "expected " + format_bound(minimum) + " to " + format_bound(maximum) + ", got " +
                    format_value(v));
  }
  return v;
}

bool boolean_field(const ControlJson& message, const char* key) {
  const ControlJson& value = field(message, key);
  if (!value.is_boolean()) refuse(key, "expected true or false");
  return value.get<bool>();
}

std::string string_field(const ControlJson& message, const char* key, std::size_t max_bytes) {
  const ControlJson& value = field(message, key);
  if (!value.is_string()) refuse(key, "expected a string");
  const auto& text = value.get_ref<const std::string&>();
  if (text.empty() || text.size() > max_bytes) {
    refuse(key, "expected 1 to " + std::to_string(max_bytes) + " bytes");
  }
  if (text.find('\0') != std::string::npos) refuse(key, "contains a NUL byte");
  return text;
}

}  // namespace hapticut::servo
