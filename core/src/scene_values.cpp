// The value checks of the scene reader (scene_values.h).
#include "scene_values.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "hapticut/material_table.h"
#include "hapticut/scene_io.h"

namespace hapticut::scene_values {

std::string Path::pointer() const {
  if (parent_ == nullptr) return "";
  std::string out = parent_->pointer() + '/';
  if (is_index_) return out + std::to_string(index_);
  append_pointer_token(out, key_);
  return out;
}

[[noreturn]] void fail(const Path& path, const std::string& reason) {
  std::string pointer = path.pointer();
  throw SceneError(pointer.empty() ? "(root)" : std::move(pointer), reason);
}

std::string model_list() {
  std::string out;
  for (const MaterialModelSpec& spec : material_models()) {
    if (!out.empty()) out += ", ";
    out += spec.name;
  }
  return out;
}

std::string in_quotes(std::string_view text) {
  std::string out;
  out.reserve(text.size() + 2);
  out += '\'';
  out += text;
  out += '\'';
  return out;
}

const char* kind_of(const Json& value) {
  switch (value.type()) {
    case Json::value_t::object:
      return "object";
    case Json::value_t::array:
      return "array";
    case Json::value_t::string:
      return "string";
    case Json::value_t::boolean:
      return "boolean";
    case Json::value_t::null:
      return "null";
    case Json::value_t::binary:
      return "binary";
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned:
    case Json::value_t::number_float:
      return "number";
    case Json::value_t::discarded:
      break;
  }
  return "unknown";
}

const Json* find(const Json& object, std::string_view key) {
  auto it = object.find(std::string(key));
  return it == object.end() ? nullptr : &*it;
}

const Json& required(const Json& object, const Path& path, std::string_view key) {
  const Json* value = find(object, key);
  if (value == nullptr) fail(Path(path, key), "required field missing");
  return *value;
}

void expect_object(const Json& value, const Path& path) {
  if (!value.is_object()) fail(path, std::string("expected an object, got ") + kind_of(value));
}

void expect_array(const Json& value, const Path& path) {
  if (!value.is_array()) fail(path, std::string("expected an array, got ") + kind_of(value));
}

const std::string& read_string(const Json& value, const Path& path) {
  if (!value.is_string()) fail(path, std::string("expected a string, got ") + kind_of(value));
  return value.get_ref<const std::string&>();
}

const std::string& read_name(const Json& value, const Path& path) {
  const std::string& name = read_string(value, path);
  if (name.empty()) fail(path, "must not be empty");
  return name;
}

void expect_exact_string(const Json& value, const Path& path, std::string_view expected) {
  const std::string& text = read_string(value, path);
  if (text != expected) fail(path, "expected " + in_quotes(expected) + ", got " + in_quotes(text));
}

double read_finite(const Json& value, const Path& path) {
  if (!value.is_number()) fail(path, std::string("expected a number, got ") + kind_of(value));
  const double number = value.get<double>();
  if (!std::isfinite(number)) fail(path, "not a finite number");
  return number;
}

double read_in_range(const Json& value, const Path& path, const ParameterRange& range) {
  const double number = read_finite(value, path);
  const std::string reason = range_reason(range, number, value.dump());
  if (!reason.empty()) fail(path, reason);
  return number;
}

std::int64_t read_integer(const Json& value, const Path& path) {
  if (value.is_number_unsigned()) {
    const auto number = value.get<std::uint64_t>();
    return number > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())
               ? std::numeric_limits<std::int64_t>::max()
               : static_cast<std::int64_t>(number);
  }
  if (value.is_number_integer()) return value.get<std::int64_t>();
  if (!value.is_number()) fail(path, std::string("expected an integer, got ") + kind_of(value));
  const double number = value.get<double>();
  if (!std::isfinite(number) || std::floor(number) != number) {
    fail(path, "expected an integer, got a non-integer number");
  }
  constexpr double kLimit = 9.2e18;  // Inside int64, so the cast below is defined.
  if (number >= kLimit) return std::numeric_limits<std::int64_t>::max();
  if (number <= -kLimit) return std::numeric_limits<std::int64_t>::min();
  return static_cast<std::int64_t>(number);
}

int read_int_between(const Json& value, const Path& path, std::int64_t low, std::int64_t high) {
  const std::int64_t number = read_integer(value, path);
  if (number < low) fail(path, "must be >= " + std::to_string(low) + ", got " + value.dump());
  if (number > high) fail(path, "must be <= " + std::to_string(high) + ", got " + value.dump());
  return static_cast<int>(number);
}

int read_int_in_range(const Json& value, const Path& path, const ParameterRange& range) {
  return read_int_between(value, path, static_cast<std::int64_t>(range.minimum),
                          static_cast<std::int64_t>(range.maximum));
}

Vec3 read_point(const Json& value, const Path& path) {
  expect_array(value, path);
  if (value.size() != 3) {
    fail(path, "expected 3 coordinates, got " + std::to_string(value.size()));
  }
  return {read_finite(value[0], Path(path, std::size_t{0})),
          read_finite(value[1], Path(path, std::size_t{1})),
          read_finite(value[2], Path(path, std::size_t{2}))};
}

void reject_unknown_fields(const Json& object, const Path& path,
                           std::initializer_list<std::string_view> known) {
  for (auto it = object.begin(); it != object.end(); ++it) {
    if (std::find(known.begin(), known.end(), it.key()) == known.end()) {
      fail(Path(path, it.key()), "unknown field");
    }
  }
}

void NameRegistry::add(const std::string& name, const Path& name_path, const Path& item_path) {
  auto [it, inserted] = first_.emplace(name, item_path.pointer());
  if (!inserted) {
    fail(name_path, "duplicate name " + in_quotes(name) + " (first at " + it->second + ")");
  }
}

}  // namespace hapticut::scene_values
