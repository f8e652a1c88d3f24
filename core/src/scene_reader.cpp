// Scene files, format version 1 (docs/scene-format.md): the reader. Both
// encodings decode to one tree (scene_tree.h), which is checked field by field
// in document order; the first problem throws SceneError naming its JSON
// pointer. The one reader: the servo, the tests and Python (through
// core/python/bind_scene.cpp) all read with it.
#include "scene_reader.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string_view>
#include <utility>

#include "hapticut/material_table.h"
#include "hapticut/parameter_range.h"
#include "hapticut/tet_mesh.h"
#include "scene_values.h"

namespace hapticut {

using namespace scene_values;  // NOLINT(google-build-using-namespace): the reader's vocabulary.

namespace {

constexpr std::int64_t kMaxInt32 = std::numeric_limits<std::int32_t>::max();

void read_header(const Json& root, const Path& root_path) {
  expect_exact_string(required(root, root_path, "format"), Path(root_path, "format"),
                      kSceneFormatName);
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

// The optional number named after its range ("stiffness_N_per_mm"), kept in `value` when absent.
void read_setting(const Json& object, const Path& path, const ParameterRange& range,
                  double& value) {
  if (const Json* found = find(object, range.name)) {
    value = read_in_range(*found, Path(path, range.name), range);
  }
}

void read_coupling(const Json& root, const Path& root_path, Scene& scene) {
  const Json* coupling = find(root, "coupling");
  if (coupling == nullptr) return;
  const Path path(root_path, "coupling");
  expect_object(*coupling, path);
  read_setting(*coupling, path, setting_range::kStiffness, scene.stiffness_N_per_mm);
  read_setting(*coupling, path, setting_range::kServoRate, scene.servo_rate_Hz);
  reject_unknown_fields(*coupling, path, {"stiffness_N_per_mm", "servo_rate_Hz"});
}

// The file's "safety" object: the safety limits, and the engine's transition
// budget (Scene::max_transitions_per_tick), which the file keeps there.
void read_safety(const Json& root, const Path& root_path, Scene& scene) {
  SafetyLimits& safety = scene.safety;
  const Json* object = find(root, "safety");
  if (object == nullptr) return;
  const Path path(root_path, "safety");
  expect_object(*object, path);
  read_setting(*object, path, setting_range::kMaxForce, safety.max_force_N);
  read_setting(*object, path, setting_range::kMaxTorque, safety.max_torque_N_mm);
  read_setting(*object, path, setting_range::kRampTime, safety.ramp_time_s);
  if (const Json* value = find(*object, "max_transitions_per_tick")) {
    scene.max_transitions_per_tick = read_int_in_range(
        *value, Path(path, "max_transitions_per_tick"), setting_range::kMaxTransitions);
  }
  read_setting(*object, path, setting_range::kCappedTickForce, safety.capped_tick_force_N);
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
  // depend on where the material sits in the table.
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
  // Checked against the other materials once all are read (read_materials).
  if (const Json* cut_to = find(object, "cut_to")) {
    material.cut_to = read_name(*cut_to, Path(path, "cut_to"));
  }
  for (auto it = object.begin(); it != object.end(); ++it) {
    const bool known =
        it.key() == "name" || it.key() == "model" || it.key() == "cut_to" ||
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
  for (std::size_t i = 0; i < scene.materials.size(); ++i) {
    const std::string problem = cut_to_problem(scene.materials, i);
    if (!problem.empty()) fail(Path(Path(path, i), "cut_to"), problem);
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
// their own passes (the order docs/scene-format.md gives for the first error).
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

// The flatness test is TetMesh's own (tet_has_no_volume), so both agree on which tets have
// no volume.
std::int64_t check_volumes(const Path& tets_path, Scene& scene, const ReadOptions& options) {
  std::int64_t reoriented = 0;
  for (std::size_t t = 0; t < scene.tets.size(); ++t) {
    auto& tet = scene.tets[t];
    const auto& v = scene.vertices_mm;
    const double volume6 = 6.0 * signed_tet_volume(v[tet[0]], v[tet[1]], v[tet[2]], v[tet[3]]);
    if (tet_has_no_volume({v[tet[0]], v[tet[1]], v[tet[2]], v[tet[3]]}, volume6)) {
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
  if (const Json* coupling = find(object, "coupling")) {
    const Path coupling_path(path, "coupling");
    blade.coupling = blade_coupling_at(read_string(*coupling, coupling_path), blade.name,
                                       coupling_path.pointer());
  }
  if (const Json* orientation = find(object, "orientation")) {
    const Path orientation_path(path, "orientation");
    blade.orientation = blade_orientation_at(read_string(*orientation, orientation_path),
                                             blade.name, orientation_path.pointer());
  }
  reject_unknown_fields(object, path,
                        {"name", "start_mm", "end_mm", "points", "coupling", "orientation"});
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

}  // namespace

SceneDocument read_scene_tree(const SceneTree& root, const ReadOptions& options) {
  const Path root_path;
  expect_object(root, root_path);
  SceneDocument document;
  Scene& scene = document.scene;
  read_header(root, root_path);
  read_units(root, root_path);
  read_coupling(root, root_path, scene);
  read_setting(root, root_path, setting_range::kTolerance, scene.tolerance_mm);
  read_safety(root, root_path, scene);
  read_materials(root, root_path, scene);
  read_mesh(root, root_path, document, options);
  read_blades(root, root_path, scene);
  read_metadata(root, root_path, document);
  reject_unknown_fields(root, root_path,
                        {"format", "version", "units", "coupling", "tolerance_mm", "safety",
                         "materials", "mesh", "blades", "metadata"});
  return document;
}

BladeCoupling blade_coupling_at(std::string_view name, std::string_view blade,
                                const std::string& field) {
  const auto coupling = blade_coupling_from_name(name);
  if (!coupling) {
    throw SceneError(field, "unknown coupling " + in_quotes(name) + " of blade " +
                                in_quotes(blade) + " (expected rigid, independent)");
  }
  return *coupling;
}

BladeOrientation blade_orientation_at(std::string_view name, std::string_view blade,
                                      const std::string& field) {
  const auto orientation = blade_orientation_from_name(name);
  if (!orientation) {
    throw SceneError(field, "unknown orientation " + in_quotes(name) + " of blade " +
                                in_quotes(blade) + " (expected free, locked)");
  }
  return *orientation;
}

std::optional<MaterialModel> material_model_from_name(std::string_view name) {
  for (const MaterialModelSpec& spec : material_models()) {
    if (name == spec.name) return spec.model;
  }
  return std::nullopt;
}

SceneDocument parse_scene_document(const std::vector<std::uint8_t>& bytes, SceneEncoding encoding,
                                   const ReadOptions& options) {
  return read_scene_tree(decode_scene_tree(bytes, encoding), options);
}

Scene parse_scene(const std::vector<std::uint8_t>& bytes, SceneEncoding encoding,
                  const ReadOptions& options) {
  return parse_scene_document(bytes, encoding, options).scene;
}

Scene parse_scene(const std::vector<std::uint8_t>& bytes, SceneEncoding encoding) {
  return parse_scene(bytes, encoding, ReadOptions{});
}

}  // namespace hapticut
