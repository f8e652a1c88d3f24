// The checks of single values in a decoded scene tree (scene_tree.h), shared by
// the reader (scene_reader.cpp) and the writer's error paths: each failure
// throws SceneError naming the field's JSON pointer, worded as in
// docs/scene-format.md and tests/data/scene_error_cases.json. Internal to core/.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <string_view>
#include <unordered_map>

#include "hapticut/parameter_range.h"
#include "hapticut/scene_tree.h"
#include "hapticut/vec3.h"

namespace hapticut::scene_values {

using Json = SceneTree;

// Field paths: a chain of stack frames, turned into a JSON pointer only when an
// error is thrown, so the per-vertex and per-tet checks never allocate.
class Path {
 public:
  Path() = default;  // The root.
  Path(const Path& parent, std::string_view key) : parent_(&parent), key_(key) {}
  Path(const Path& parent, std::size_t index) : parent_(&parent), index_(index), is_index_(true) {}

  // RFC 6901 pointer ("" for the root).
  std::string pointer() const;

 private:
  const Path* parent_ = nullptr;
  std::string_view key_;
  std::size_t index_ = 0;
  bool is_index_ = false;
};

// Throws SceneError(pointer, reason); the root is named "(root)".
[[noreturn]] void fail(const Path& path, const std::string& reason);

// "free, drag, rigid, viscous, membrane", from the material table.
std::string model_list();
std::string in_quotes(std::string_view text);
// "object", "array", "string", "number", ... as the error messages name them.
const char* kind_of(const Json& value);

const Json* find(const Json& object, std::string_view key);
const Json& required(const Json& object, const Path& path, std::string_view key);
void expect_object(const Json& value, const Path& path);
void expect_array(const Json& value, const Path& path);
const std::string& read_string(const Json& value, const Path& path);
// A non-empty string.
const std::string& read_name(const Json& value, const Path& path);
void expect_exact_string(const Json& value, const Path& path, std::string_view expected);
double read_finite(const Json& value, const Path& path);
// A number in the engine's range for it (parameter_range.h, material_table.h).
double read_in_range(const Json& value, const Path& path, const ParameterRange& range);
// Integers as JSON Schema sees them: 3 and 3.0 both count. Values beyond int64
// saturate; every caller range-checks and prints the original with dump().
std::int64_t read_integer(const Json& value, const Path& path);
int read_int_between(const Json& value, const Path& path, std::int64_t low, std::int64_t high);
int read_int_in_range(const Json& value, const Path& path, const ParameterRange& range);
Vec3 read_point(const Json& value, const Path& path);

// Checked after an object's known fields, so a misspelt optional field is
// reported rather than silently replaced by its default.
void reject_unknown_fields(const Json& object, const Path& path,
                           std::initializer_list<std::string_view> known);

// Unique, non-empty names ("/materials/3/name: duplicate name 'bone' (first at /materials/1)").
class NameRegistry {
 public:
  void add(const std::string& name, const Path& name_path, const Path& item_path);

 private:
  std::unordered_map<std::string, std::string> first_;
};

}  // namespace hapticut::scene_values
