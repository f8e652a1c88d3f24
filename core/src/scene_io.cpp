// Scene files, format version 1 (docs/scene-format.md). Both encodings decode
// to one tree (nlohmann::ordered_json), which is checked field by field in
// document order; the first problem throws SceneError naming its JSON pointer.
// hapticut/scene/tree_reader.py applies the same checks in the same order with
// the same wording, so both languages report the same first error.
#include "hapticut/scene_io.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <string_view>
#include <unordered_map>
#include <utility>

#include "hapticut/material_table.h"
#include "hapticut/parameter_range.h"
#include "hapticut/scene_tree.h"

#if defined(__unix__) || defined(__APPLE__)
#include <unistd.h>
#endif

namespace hapticut {

namespace {

using Json = nlohmann::ordered_json;

constexpr std::string_view kFormatName = "hapticut.scene";
constexpr std::int64_t kMaxInt32 = std::numeric_limits<std::int32_t>::max();
// Same test as TetMesh: a tet with |6 V| below this fraction of (longest edge)^3 has no volume.
constexpr double kZeroVolumeRatio = 1e-12;
constexpr std::array<std::array<int, 2>, 6> kTetEdges{
    {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};

// ---------------------------------------------------------------------------
// Field paths: a chain of stack frames, turned into a JSON pointer only when
// an error is thrown, so the per-vertex and per-tet checks never allocate.

class Path {
 public:
  Path() = default;  // The root.
  Path(const Path& parent, std::string_view key) : parent_(&parent), key_(key) {}
  Path(const Path& parent, std::size_t index) : parent_(&parent), index_(index), is_index_(true) {}

  // RFC 6901 pointer ("" for the root).
  std::string pointer() const {
    if (parent_ == nullptr) return "";
    std::string out = parent_->pointer() + '/';
    if (is_index_) return out + std::to_string(index_);
    for (char c : key_) {
      if (c == '~') {
        out += "~0";
      } else if (c == '/') {
        out += "~1";
      } else {
        out += c;
      }
    }
    return out;
  }

 private:
  const Path* parent_ = nullptr;
  std::string_view key_;
  std::size_t index_ = 0;
  bool is_index_ = false;
};

[[noreturn]] void fail(const Path& path, const std::string& reason) {
  std::string pointer = path.pointer();
  throw SceneError(pointer.empty() ? "(root)" : std::move(pointer), reason);
}

// "free, drag, rigid, viscous, membrane", from the material table.
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

// ---------------------------------------------------------------------------
// Single values.

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

// A number in the engine's range for it (parameter_range.h, material_table.h).
double read_in_range(const Json& value, const Path& path, const ParameterRange& range) {
  const double number = read_finite(value, path);
  const std::string reason = range_reason(range, number, value.dump());
  if (!reason.empty()) fail(path, reason);
  return number;
}

// Integers as JSON Schema sees them: 3 and 3.0 both count. Values beyond int64
// saturate; every caller range-checks and prints the original with dump().
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

// Checked after an object's known fields, so a misspelt optional field is
// reported rather than silently replaced by its default.
void reject_unknown_fields(const Json& object, const Path& path,
                           std::initializer_list<std::string_view> known) {
  for (auto it = object.begin(); it != object.end(); ++it) {
    if (std::find(known.begin(), known.end(), it.key()) == known.end()) {
      fail(Path(path, it.key()), "unknown field");
    }
  }
}

// Unique, non-empty names ("/materials/3/name: duplicate name 'bone' (first at /materials/1)").
class NameRegistry {
 public:
  void add(const std::string& name, const Path& name_path, const Path& item_path) {
    auto [it, inserted] = first_.emplace(name, item_path.pointer());
    if (!inserted)
      fail(name_path, "duplicate name " + in_quotes(name) + " (first at " + it->second + ")");
  }

 private:
  std::unordered_map<std::string, std::string> first_;
};

// ---------------------------------------------------------------------------
// Sections, in document order.

void read_header(const Json& root, const Path& root_path) {
  expect_exact_string(required(root, root_path, "format"), Path(root_path, "format"), kFormatName);
  const Json& version = required(root, root_path, "version");
  if (read_integer(version, Path(root_path, "version")) != kSceneFormatVersion) {
    fail(Path(root_path, "version"), "unsupported format version " + version.dump() +
                                         " (this build reads " +
                                         std::to_string(kSceneFormatVersion) + ")");
  }
}

void read_units(const Json& root, const Path& root_path) {
  const Path path(root_path, "units");
  const Json& units = required(root, root_path, "units");
  expect_object(units, path);
  expect_exact_string(required(units, path, "length"), Path(path, "length"), "mm");
  expect_exact_string(required(units, path, "force"), Path(path, "force"), "N");
  expect_exact_string(required(units, path, "time"), Path(path, "time"), "s");
  reject_unknown_fields(units, path, {"length", "force", "time"});
}

void read_coupling(const Json& root, const Path& root_path, Scene& scene) {
  const Json* coupling = find(root, "coupling");
  if (coupling == nullptr) return;
  const Path path(root_path, "coupling");
  expect_object(*coupling, path);
  if (const Json* value = find(*coupling, "stiffness_N_per_mm")) {
    scene.stiffness_N_per_mm =
        read_in_range(*value, Path(path, "stiffness_N_per_mm"), setting_range::kStiffness);
  }
  if (const Json* value = find(*coupling, "servo_rate_Hz")) {
    scene.servo_rate_Hz =
        read_in_range(*value, Path(path, "servo_rate_Hz"), setting_range::kServoRate);
  }
  reject_unknown_fields(*coupling, path, {"stiffness_N_per_mm", "servo_rate_Hz"});
}

void read_tolerance(const Json& root, const Path& root_path, Scene& scene) {
  if (const Json* value = find(root, "tolerance_mm")) {
    scene.tolerance_mm =
        read_in_range(*value, Path(root_path, "tolerance_mm"), setting_range::kTolerance);
  }
}

void read_safety(const Json& root, const Path& root_path, SafetyLimits& safety) {
  const Json* object = find(root, "safety");
  if (object == nullptr) return;
  const Path path(root_path, "safety");
  expect_object(*object, path);
  if (const Json* value = find(*object, "max_force_N")) {
    safety.max_force_N = read_in_range(*value, Path(path, "max_force_N"), setting_range::kMaxForce);
  }
  if (const Json* value = find(*object, "max_torque_N_mm")) {
    safety.max_torque_N_mm =
        read_in_range(*value, Path(path, "max_torque_N_mm"), setting_range::kMaxTorque);
  }
  if (const Json* value = find(*object, "ramp_time_s")) {
    safety.ramp_time_s = read_in_range(*value, Path(path, "ramp_time_s"), setting_range::kRampTime);
  }
  if (const Json* value = find(*object, "max_transitions_per_tick")) {
    safety.max_transitions_per_tick = read_int_in_range(
        *value, Path(path, "max_transitions_per_tick"), setting_range::kMaxTransitions);
  }
  if (const Json* value = find(*object, "capped_tick_force_N")) {
    safety.capped_tick_force_N =
        read_in_range(*value, Path(path, "capped_tick_force_N"), setting_range::kCappedTickForce);
  }
  reject_unknown_fields(*object, path,
                        {"max_force_N", "max_torque_N_mm", "ramp_time_s",
                         "max_transitions_per_tick", "capped_tick_force_N"});
}

Material read_material(const Json& object, const Path& path, NameRegistry& names) {
  expect_object(object, path);
  Material material;
  const Path name_path(path, "name");
  material.name = read_name(required(object, path, "name"), name_path);
  names.add(material.name, name_path, path);
  const Path model_path(path, "model");
  const std::string& model = read_string(required(object, path, "model"), model_path);
  const auto parsed = material_model_from_name(model);
  if (!parsed) {
    fail(model_path, "unknown model " + in_quotes(model) + " (expected " + model_list() + ")");
  }
  material.model = *parsed;
  // Every parameter of every model in file order, so the first error does not
  // depend on the language (tree_reader.py walks the same table).
  for (const MaterialParameterSpec& any_model : material_parameters()) {
    const std::string_view key = any_model.range.name;
    const MaterialParameterSpec* parameter = find_material_parameter(material.model, key);
    const Json* value = find(object, key);
    const Path parameter_path(path, key);
    if (parameter == nullptr) {
      if (value != nullptr) fail(parameter_path, "not a parameter of model " + in_quotes(model));
      continue;
    }
    if (value == nullptr) {
      if (parameter->required) fail(parameter_path, "required field missing");
      continue;
    }
    material.*(parameter->field) = read_in_range(*value, parameter_path, parameter->range);
  }
  for (auto it = object.begin(); it != object.end(); ++it) {
    const bool known =
        it.key() == "name" || it.key() == "model" ||
        std::any_of(material_parameters().begin(), material_parameters().end(),
                    [&](const MaterialParameterSpec& p) { return p.range.name == it.key(); });
    if (!known) fail(Path(path, it.key()), "unknown field");
  }
  return material;
}

void read_materials(const Json& root, const Path& root_path, Scene& scene) {
  const Path path(root_path, "materials");
  const Json& materials = required(root, root_path, "materials");
  expect_array(materials, path);
  if (materials.empty()) fail(path, "empty (a scene needs at least one material)");
  NameRegistry names;
  scene.materials.reserve(materials.size());
  for (std::size_t i = 0; i < materials.size(); ++i) {
    scene.materials.push_back(read_material(materials[i], Path(path, i), names));
  }
}

void read_vertices(const Json& mesh, const Path& mesh_path, Scene& scene) {
  const Path path(mesh_path, "vertices");
  const Json& vertices = required(mesh, mesh_path, "vertices");
  expect_array(vertices, path);
  scene.vertices_mm.reserve(vertices.size());
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    scene.vertices_mm.push_back(read_point(vertices[i], Path(path, i)));
  }
}

// Structure and range of every index; distinctness and volume come after, in
// their own passes, so that the first error does not depend on the language.
void read_tet_indices(const Json& mesh, const Path& mesh_path, Scene& scene) {
  const Path path(mesh_path, "tets");
  const Json& tets = required(mesh, mesh_path, "tets");
  expect_array(tets, path);
  if (tets.empty()) fail(path, "no tets (a scene needs at least one)");
  const auto vertex_count = static_cast<std::int64_t>(scene.vertices_mm.size());
  scene.tets.resize(tets.size());
  for (std::size_t t = 0; t < tets.size(); ++t) {
    const Path tet_path(path, t);
    const Json& row = tets[t];
    expect_array(row, tet_path);
    if (row.size() != 4) {
      fail(tet_path, "expected 4 vertex indices, got " + std::to_string(row.size()));
    }
    for (std::size_t k = 0; k < 4; ++k) {
      const Path index_path(tet_path, k);
      const std::int64_t index = read_integer(row[k], index_path);
      if (index < 0 || index >= vertex_count) {
        fail(index_path, "vertex index " + row[k].dump() + " out of range (" +
                             std::to_string(vertex_count) + " vertices)");
      }
      scene.tets[t][k] = static_cast<std::int32_t>(index);
    }
  }
}

void check_distinct_vertices(const Path& tets_path, const Scene& scene) {
  for (std::size_t t = 0; t < scene.tets.size(); ++t) {
    const auto& tet = scene.tets[t];
    for (int k = 1; k < 4; ++k) {
      for (int j = 0; j < k; ++j) {
        if (tet[j] == tet[k]) {
          fail(Path(tets_path, t), "repeated vertex index " + std::to_string(tet[k]));
        }
      }
    }
  }
}

// The arithmetic matches TetMesh::validate_and_orient and mesh_checks.py
// operation for operation, so all three agree on which tets have no volume.
std::int64_t check_volumes(const Path& tets_path, Scene& scene, const ReadOptions& options) {
  std::int64_t reoriented = 0;
  for (std::size_t t = 0; t < scene.tets.size(); ++t) {
    auto& tet = scene.tets[t];
    const auto& v = scene.vertices_mm;
    double longest = 0.0;
    for (const auto& edge : kTetEdges) {
      longest = std::max(longest, norm(v[tet[edge[0]]] - v[tet[edge[1]]]));
    }
    const Vec3& a = v[tet[0]];
    const double volume6 = 6.0 * (dot(v[tet[1]] - a, cross(v[tet[2]] - a, v[tet[3]] - a)) / 6.0);
    if (!(std::abs(volume6) > kZeroVolumeRatio * longest * longest * longest)) {
      fail(Path(tets_path, t), "zero volume");
    }
    if (volume6 < 0.0) {
      if (options.strict) fail(Path(tets_path, t), "inverted (negative volume)");
      std::swap(tet[2], tet[3]);
      ++reoriented;
    }
  }
  return reoriented;
}

void read_tet_materials(const Json& mesh, const Path& mesh_path, Scene& scene) {
  const Path path(mesh_path, "tet_materials");
  const Json& tet_materials = required(mesh, mesh_path, "tet_materials");
  expect_array(tet_materials, path);
  if (tet_materials.size() != scene.tets.size()) {
    fail(path, std::to_string(tet_materials.size()) + " entries for " +
                   std::to_string(scene.tets.size()) + " tets");
  }
  const auto material_count = static_cast<std::int64_t>(scene.materials.size());
  scene.tet_materials.resize(tet_materials.size());
  for (std::size_t t = 0; t < tet_materials.size(); ++t) {
    const Path entry_path(path, t);
    const std::int64_t index = read_integer(tet_materials[t], entry_path);
    if (index < 0 || index >= material_count) {
      fail(entry_path, "unknown material " + tet_materials[t].dump() + " (" +
                           std::to_string(material_count) + " materials)");
    }
    scene.tet_materials[t] = static_cast<std::int32_t>(index);
  }
}

void read_mesh(const Json& root, const Path& root_path, SceneDocument& document,
               const ReadOptions& options) {
  const Path path(root_path, "mesh");
  const Json& mesh = required(root, root_path, "mesh");
  expect_object(mesh, path);
  read_vertices(mesh, path, document.scene);
  read_tet_indices(mesh, path, document.scene);
  const Path tets_path(path, "tets");
  check_distinct_vertices(tets_path, document.scene);
  document.reoriented_tets = check_volumes(tets_path, document.scene, options);
  read_tet_materials(mesh, path, document.scene);
  reject_unknown_fields(mesh, path, {"vertices", "tets", "tet_materials"});
}

BladeSpec read_blade(const Json& object, const Path& path, NameRegistry& names) {
  expect_object(object, path);
  BladeSpec blade;
  const Path name_path(path, "name");
  blade.name = read_name(required(object, path, "name"), name_path);
  names.add(blade.name, name_path, path);
  blade.start_mm = read_point(required(object, path, "start_mm"), Path(path, "start_mm"));
  blade.end_mm = read_point(required(object, path, "end_mm"), Path(path, "end_mm"));
  if (const Json* points = find(object, "points")) {
    blade.points = read_int_between(*points, Path(path, "points"), 1, kMaxInt32);
  }
  reject_unknown_fields(object, path, {"name", "start_mm", "end_mm", "points"});
  return blade;
}

void read_blades(const Json& root, const Path& root_path, Scene& scene) {
  const Json* blades = find(root, "blades");
  if (blades == nullptr) return;
  const Path path(root_path, "blades");
  expect_array(*blades, path);
  NameRegistry names;
  for (std::size_t i = 0; i < blades->size(); ++i) {
    scene.blades.push_back(read_blade((*blades)[i], Path(path, i), names));
  }
}

void read_metadata(const Json& root, const Path& root_path, SceneDocument& document) {
  const Json* metadata = find(root, "metadata");
  if (metadata == nullptr) return;
  const Path path(root_path, "metadata");
  expect_object(*metadata, path);
  try {
    document.metadata_json = metadata->dump();
  } catch (const Json::exception& error) {
    fail(path, std::string("not representable as JSON: ") + error.what());
  }
}

SceneDocument read_tree(const Json& root, const ReadOptions& options) {
  const Path root_path;
  expect_object(root, root_path);
  SceneDocument document;
  Scene& scene = document.scene;
  read_header(root, root_path);
  read_units(root, root_path);
  read_coupling(root, root_path, scene);
  read_tolerance(root, root_path, scene);
  read_safety(root, root_path, scene.safety);
  read_materials(root, root_path, scene);
  read_mesh(root, root_path, document, options);
  read_blades(root, root_path, scene);
  read_metadata(root, root_path, document);
  reject_unknown_fields(root, root_path,
                        {"format", "version", "units", "coupling", "tolerance_mm", "safety",
                         "materials", "mesh", "blades", "metadata"});
  return document;
}

// ---------------------------------------------------------------------------
// Decoding and encoding.

// "[json.exception.parse_error.101] parse error at ..." -> "parse error at ...".
std::string without_exception_id(const char* what) {
  std::string_view text(what);
  const auto end_of_id = text.find("] ");
  if (!text.empty() && text.front() == '[' && end_of_id != std::string_view::npos) {
    text.remove_prefix(end_of_id + 2);
  }
  return std::string(text);
}

Json point_tree(const Vec3& point) { return Json::array({point.x, point.y, point.z}); }

Json material_tree(const Material& material) {
  Json tree = Json::object();
  tree["name"] = material.name;
  tree["model"] = material_model_name(material.model);
  for (const MaterialParameterSpec& parameter : material_model_spec(material.model).parameters) {
    tree[std::string(parameter.range.name)] = material.*(parameter.field);
  }
  return tree;
}

Json mesh_tree(const Scene& scene) {
  Json vertices = Json::array();
  vertices.get_ref<Json::array_t&>().reserve(scene.vertices_mm.size());
  for (const Vec3& vertex : scene.vertices_mm) vertices.push_back(point_tree(vertex));
  Json tets = Json::array();
  tets.get_ref<Json::array_t&>().reserve(scene.tets.size());
  for (const auto& tet : scene.tets) tets.push_back(Json::array({tet[0], tet[1], tet[2], tet[3]}));
  Json tree = Json::object();
  tree["vertices"] = std::move(vertices);
  tree["tets"] = std::move(tets);
  tree["tet_materials"] = scene.tet_materials;
  return tree;
}

Json metadata_tree(const std::string& metadata_json) {
  try {
    return Json::parse(metadata_json);
  } catch (const Json::exception& error) {
    fail(Path(Path(), "metadata"),
         "metadata_json is not valid JSON: " + without_exception_id(error.what()));
  }
}

// Every section is written out, defaults included, so a file says everything.
Json document_tree(const Scene& scene, const std::string& metadata_json) {
  Json tree = Json::object();
  tree["format"] = kFormatName;
  tree["version"] = kSceneFormatVersion;
  tree["units"] = Json{{"length", "mm"}, {"force", "N"}, {"time", "s"}};
  tree["coupling"] = Json{{"stiffness_N_per_mm", scene.stiffness_N_per_mm},
                          {"servo_rate_Hz", scene.servo_rate_Hz}};
  tree["tolerance_mm"] = scene.tolerance_mm;
  const SafetyLimits& safety = scene.safety;
  tree["safety"] = Json{{"max_force_N", safety.max_force_N},
                        {"max_torque_N_mm", safety.max_torque_N_mm},
                        {"ramp_time_s", safety.ramp_time_s},
                        {"max_transitions_per_tick", safety.max_transitions_per_tick},
                        {"capped_tick_force_N", safety.capped_tick_force_N}};
  Json materials = Json::array();
  for (const Material& material : scene.materials) materials.push_back(material_tree(material));
  tree["materials"] = std::move(materials);
  tree["mesh"] = mesh_tree(scene);
  Json blades = Json::array();
  for (const BladeSpec& blade : scene.blades) {
    blades.push_back(Json{{"name", blade.name},
                          {"start_mm", point_tree(blade.start_mm)},
                          {"end_mm", point_tree(blade.end_mm)},
                          {"points", blade.points}});
  }
  tree["blades"] = std::move(blades);
  tree["metadata"] = metadata_tree(metadata_json);
  return tree;
}

// Indented like json.dump(indent=2), except that an array holding no arrays or
// objects stays on one line: one vertex or tet per line keeps big meshes
// readable and small. tree_writer.py lays out text the same way.
void append_layout(std::string& out, const Json& value, int depth) {
  const auto is_container = [](const Json& item) { return item.is_object() || item.is_array(); };
  const bool expand =
      value.is_object() ? !value.empty()
                        : value.is_array() && std::any_of(value.begin(), value.end(), is_container);
  if (!expand) {
    out += value.dump();
    return;
  }
  out += value.is_object() ? "{\n" : "[\n";
  bool first = true;
  for (auto it = value.begin(); it != value.end(); ++it) {
    if (!first) out += ",\n";
    first = false;
    out.append(2 * (depth + 1), ' ');
    if (value.is_object()) out += Json(it.key()).dump() + ": ";
    append_layout(out, it.value(), depth + 1);
  }
  out += '\n';
  out.append(2 * depth, ' ');
  out += value.is_object() ? '}' : ']';
}

std::vector<std::uint8_t> encode(const Json& tree, SceneEncoding encoding) {
  try {
    if (encoding == SceneEncoding::MessagePack) return Json::to_msgpack(tree);
    std::string text;
    append_layout(text, tree, 0);
    text += '\n';
    return {text.begin(), text.end()};
  } catch (const Json::exception& error) {
    fail(Path(), std::string("cannot encode: ") + without_exception_id(error.what()));
  }
}

// ---------------------------------------------------------------------------
// Files.

[[noreturn]] void fail_file(const std::string& action, const std::string& path, int error) {
  throw SceneError("(file)",
                   "cannot " + action + " " + in_quotes(path) + ": " + std::strerror(error));
}

std::vector<std::uint8_t> read_file(const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) fail_file("open", path, errno);
  std::vector<std::uint8_t> bytes;
  std::uint8_t buffer[1 << 16];
  std::size_t count = 0;
  while ((count = std::fread(buffer, 1, sizeof buffer, file)) > 0) {
    bytes.insert(bytes.end(), buffer, buffer + count);
  }
  const bool failed = std::ferror(file) != 0;
  const int error = errno;
  std::fclose(file);
  if (failed) fail_file("read", path, error);
  return bytes;
}

std::string temporary_path_beside(const std::string& path) {
  std::random_device random;
  char suffix[32];
  std::snprintf(suffix, sizeof suffix, ".tmp-%08x%08x", random(), random());
  return path + suffix;
}

// Write, flush to disk, then rename over the target: readers see the old file
// or the new one, never a prefix of the new one.
void write_file_atomically(const std::vector<std::uint8_t>& bytes, const std::string& path) {
  const std::string temporary = temporary_path_beside(path);
  std::FILE* file = std::fopen(temporary.c_str(), "wbx");
  if (file == nullptr) fail_file("create", temporary, errno);
  bool ok = std::fwrite(bytes.data(), 1, bytes.size(), file) == bytes.size();
  ok = ok && std::fflush(file) == 0;
#if defined(__unix__) || defined(__APPLE__)
  ok = ok && ::fsync(::fileno(file)) == 0;
#endif
  int error = errno;
  ok = (std::fclose(file) == 0) && ok;
  if (!ok) {
    error = error != 0 ? error : errno;
    std::remove(temporary.c_str());
    fail_file("write", temporary, error);
  }
  std::error_code rename_error;
  std::filesystem::rename(temporary, path, rename_error);
  if (rename_error) {
    std::remove(temporary.c_str());
    fail_file("rename " + in_quotes(temporary) + " to", path, rename_error.value());
  }
}

}  // namespace

std::optional<MaterialModel> material_model_from_name(std::string_view name) {
  for (const MaterialModelSpec& spec : material_models()) {
    if (name == spec.name) return spec.model;
  }
  return std::nullopt;
}

SceneEncoding encoding_for_path(const std::string& path) {
  constexpr std::string_view kSuffix = ".msgpack";
  const bool msgpack = path.size() >= kSuffix.size() &&
                       path.compare(path.size() - kSuffix.size(), kSuffix.size(), kSuffix) == 0;
  return msgpack ? SceneEncoding::MessagePack : SceneEncoding::Json;
}

SceneDocument parse_scene_document(const std::vector<std::uint8_t>& bytes, SceneEncoding encoding,
                                   const ReadOptions& options) {
  return read_tree(decode_scene_tree(bytes, encoding), options);
}

Scene parse_scene(const std::vector<std::uint8_t>& bytes, SceneEncoding encoding,
                  const ReadOptions& options) {
  return parse_scene_document(bytes, encoding, options).scene;
}

Scene parse_scene(const std::vector<std::uint8_t>& bytes, SceneEncoding encoding) {
  return parse_scene(bytes, encoding, ReadOptions{});
}

std::vector<std::uint8_t> serialize_scene_document(const SceneDocument& document,
                                                   SceneEncoding encoding) {
  const Json tree = document_tree(document.scene, document.metadata_json);
  read_tree(tree, ReadOptions{});  // Never write what the reader would reject.
  return encode(tree, encoding);
}

std::vector<std::uint8_t> serialize_scene(const Scene& scene, SceneEncoding encoding) {
  const Json tree = document_tree(scene, "{}");
  read_tree(tree, ReadOptions{});
  return encode(tree, encoding);
}

SceneDocument load_scene_document(const std::string& path, const ReadOptions& options) {
  return parse_scene_document(read_file(path), encoding_for_path(path), options);
}

Scene load_scene(const std::string& path, const ReadOptions& options) {
  return load_scene_document(path, options).scene;
}

Scene load_scene(const std::string& path) { return load_scene(path, ReadOptions{}); }

void save_scene_document(const SceneDocument& document, const std::string& path) {
  write_file_atomically(serialize_scene_document(document, encoding_for_path(path)), path);
}

void save_scene(const Scene& scene, const std::string& path) {
  write_file_atomically(serialize_scene(scene, encoding_for_path(path)), path);
}

}  // namespace hapticut
