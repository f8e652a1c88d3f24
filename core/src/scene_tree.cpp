#include "hapticut/scene_tree.h"

#include <cstddef>
#include <cstring>
#include <string>
#include <string_view>
#include <unordered_set>
#include <utility>

namespace hapticut {

namespace {

using Json = SceneTree;

// Whether `text` is well-formed UTF-8 (RFC 3629: no overlongs, no surrogates,
// nothing above U+10FFFF).
bool is_utf8(std::string_view text) {
  const auto* s = reinterpret_cast<const unsigned char*>(text.data());
  const std::size_t n = text.size();
  std::size_t i = 0;
  while (i < n) {
    const unsigned char c = s[i];
    if (c < 0x80) {
      ++i;
      continue;
    }
    std::size_t length = 0;
    unsigned char low = 0x80;
    unsigned char high = 0xBF;
    if (c >= 0xC2 && c <= 0xDF) {
      length = 2;
    } else if (c >= 0xE0 && c <= 0xEF) {
      length = 3;
      if (c == 0xE0) low = 0xA0;
      if (c == 0xED) high = 0x9F;
    } else if (c >= 0xF0 && c <= 0xF4) {
      length = 4;
      if (c == 0xF0) low = 0x90;
      if (c == 0xF4) high = 0x8F;
    } else {
      return false;
    }
    if (i + length > n) return false;
    if (s[i + 1] < low || s[i + 1] > high) return false;
    for (std::size_t k = 2; k < length; ++k) {
      if (s[i + k] < 0x80 || s[i + k] > 0xBF) return false;
    }
    i += length;
  }
  return true;
}

// "[json.exception.parse_error.101] parse error at line 1, column 3: syntax
// error while parsing value - invalid literal; last read: 'tru'" -> "parse
// error at line 1, column 3: syntax error while parsing value - invalid
// literal": neither the library's exception id nor the input's bytes.
std::string without_exception_id(const char* what) {
  std::string_view text(what);
  const auto end_of_id = text.find("] ");
  if (!text.empty() && text.front() == '[' && end_of_id != std::string_view::npos) {
    text.remove_prefix(end_of_id + 2);
  }
  const auto last_read = text.find("; last read: ");
  if (last_read != std::string_view::npos) {
    std::string out(text.substr(0, last_read));
    // What the decoder expected instead is the library's text, not the input's.
    const auto expected = text.rfind("'; expected ");
    if (expected != std::string_view::npos && expected > last_read) {
      out += "; ";
      out += text.substr(expected + 3);
    }
    return printable(out);
  }
  return printable(text);
}

// Builds the tree like nlohmann's own DOM parser, but appends object members
// without ordered_map's linear search (a duplicate is found in a hash set
// instead), refuses to nest deeper than kMaxSceneNesting, and checks UTF-8.
// Returning false stops the parse; the first problem is kept in error_.
class TreeBuilder {
 public:
  explicit TreeBuilder(std::string_view encoding_name) : encoding_name_(encoding_name) {}

  bool null() { return add(Json(nullptr)); }
  bool boolean(bool value) { return add(Json(value)); }
  bool number_integer(Json::number_integer_t value) { return add(Json(value)); }
  bool number_unsigned(Json::number_unsigned_t value) { return add(Json(value)); }
  bool number_float(Json::number_float_t value, const Json::string_t& /*text*/) {
    return add(Json(value));
  }
  bool string(Json::string_t& value) {
    if (!is_utf8(value)) return fail(pointer(), "invalid UTF-8 in a string");
    return add(Json(std::move(value)));
  }
  bool binary(Json::binary_t& value) { return add(Json(std::move(value))); }

  bool start_object(std::size_t /*size*/) {
    if (!open(Json::object())) return false;
    keys_.emplace_back();
    return true;
  }
  bool key(Json::string_t& name) {
    if (!is_utf8(name)) return fail(pointer(false), "invalid UTF-8 in a key");
    frames_.back().key = name;
    if (!keys_.back().insert(name).second) return fail(pointer(), "duplicate key");
    return true;
  }
  bool end_object() {
    keys_.pop_back();
    return close();
  }
  bool start_array(std::size_t /*size*/) { return open(Json::array()); }
  bool end_array() { return close(); }

  bool parse_error(std::size_t /*position*/, const std::string& /*last_token*/,
                   const nlohmann::detail::exception& error) {
    return fail("(root)", "truncated or not valid " + std::string(encoding_name_) + ": " +
                              without_exception_id(error.what()));
  }

  bool failed() const { return !error_field_.empty(); }
  [[noreturn]] void rethrow() const { throw SceneError(error_field_, error_reason_); }
  Json take_root() { return std::move(root_); }

 private:
  struct Frame {
    Json* container = nullptr;
    std::string key;  // The member being read, when the container is an object.
  };

  bool fail(std::string field, std::string reason) {
    if (!failed()) {
      error_field_ = std::move(field);
      error_reason_ = std::move(reason);
    }
    return false;
  }

  // The JSON pointer of the value being read; without its last step (the
  // object whose key is being read) when include_last is false.
  std::string pointer(bool include_last = true) const {
    std::string out;
    for (std::size_t i = 0; i < frames_.size(); ++i) {
      const Frame& frame = frames_[i];
      const bool last = i + 1 == frames_.size();
      if (last && !include_last) break;
      out += '/';
      if (frame.container->is_array()) {
        // An open child is already the array's last element; a new value is next.
        const std::size_t size = frame.container->size();
        out += std::to_string(last ? size : size - 1);
        continue;
      }
      append_pointer_token(out, frame.key);
    }
    return out.empty() ? "(root)" : out;
  }

  Json* insert(Json&& value) {
    if (frames_.empty()) {
      root_ = std::move(value);
      return &root_;
    }
    Frame& top = frames_.back();
    if (top.container->is_array()) {
      auto& array = top.container->get_ref<Json::array_t&>();
      array.push_back(std::move(value));
      return &array.back();
    }
    // ordered_map is a std::vector of pairs; appending skips its key search.
    auto& members = static_cast<std::vector<std::pair<const std::string, Json>>&>(
        top.container->get_ref<Json::object_t&>());
    members.emplace_back(top.key, std::move(value));  // The key stays in the frame's pointer.
    return &members.back().second;
  }

  bool add(Json&& value) {
    insert(std::move(value));
    return true;
  }

  bool open(Json&& container) {
    if (static_cast<int>(frames_.size()) >= kMaxSceneNesting) {
      return fail("(root)",
                  "nested deeper than " + std::to_string(kMaxSceneNesting) + " arrays and objects");
    }
    // Parents do not grow while a child is open, so these pointers stay valid.
    frames_.push_back({insert(std::move(container)), {}});
    return true;
  }

  bool close() {
    frames_.pop_back();
    return true;
  }

  std::string_view encoding_name_;
  Json root_;
  std::vector<Frame> frames_;
  std::vector<std::unordered_set<std::string>> keys_;
  std::string error_field_;
  std::string error_reason_;
};

}  // namespace

std::string printable(std::string_view text) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte < 0x7F) {
      out += c;
    } else {
      out += "\\x";
      out += kHex[byte >> 4];
      out += kHex[byte & 0xF];
    }
  }
  return out;
}

void append_pointer_token(std::string& out, std::string_view key) {
  for (const char c : key) {
    if (c == '~') {
      out += "~0";
    } else if (c == '/') {
      out += "~1";
    } else {
      out += c;
    }
  }
}

SceneTree decode_scene_tree(std::string_view bytes, SceneEncoding encoding) {
  const bool json = encoding == SceneEncoding::Json;
  const std::string_view name = json ? "JSON" : "MessagePack";
  if (json) {
    // nlohmann's lexer takes a NUL byte for the end of the input, so text
    // after one would be ignored; JSON text never holds a raw NUL.
    const auto nul = bytes.find('\0');
    if (nul != std::string_view::npos) {
      throw SceneError("(root)",
                       "truncated or not valid JSON: NUL byte at offset " + std::to_string(nul));
    }
  }
  TreeBuilder builder(name);
  const auto format =
      json ? nlohmann::json::input_format_t::json : nlohmann::json::input_format_t::msgpack;
  bool ok = false;
  try {
    ok = Json::sax_parse(bytes.begin(), bytes.end(), &builder, format, /*strict=*/true);
  } catch (const Json::exception& error) {
    throw SceneError("(root)", "truncated or not valid " + std::string(name) + ": " +
                                   without_exception_id(error.what()));
  }
  if (builder.failed()) builder.rethrow();
  if (!ok) throw SceneError("(root)", "truncated or not valid " + std::string(name));
  return builder.take_root();
}

SceneTree decode_scene_tree(const std::vector<std::uint8_t>& bytes, SceneEncoding encoding) {
  return decode_scene_tree(
      std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), encoding);
}

}  // namespace hapticut
