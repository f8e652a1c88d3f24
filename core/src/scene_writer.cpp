// Scene files, format version 1 (docs/scene-format.md): the writer. A scene
// becomes the tree the reader reads, checked by the reader before it is
// encoded, so nothing is written that would not read back the same.
#include <algorithm>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <utility>

#include "hapticut/material_table.h"
#include "hapticut/scene_io.h"
#include "scene_reader.h"
#include "scene_values.h"

namespace hapticut {

namespace {

using Json = SceneTree;
using scene_values::fail;
using scene_values::Path;

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
  if (!material.cut_to.empty()) tree["cut_to"] = material.cut_to;
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
  tree["format"] = kSceneFormatName;
  tree["version"] = kSceneFormatVersion;
  tree["units"] = Json{{"length", "mm"}, {"force", "N"}, {"time", "s"}};
  tree["coupling"] = Json{{"stiffness_N_per_mm", scene.stiffness_N_per_mm},
                          {"servo_rate_Hz", scene.servo_rate_Hz}};
  tree["tolerance_mm"] = scene.tolerance_mm;
  const SafetyLimits& safety = scene.safety;
  tree["safety"] = Json{{"max_force_N", safety.max_force_N},
                        {"max_torque_N_mm", safety.max_torque_N_mm},
                        {"ramp_time_s", safety.ramp_time_s},
                        // The engine's budget, kept in the file's "safety" object.
                        {"max_transitions_per_tick", scene.max_transitions_per_tick},
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
                          {"points", blade.points},
                          {"coupling", blade_coupling_name(blade.coupling)},
                          {"orientation", blade_orientation_name(blade.orientation)}});
  }
  tree["blades"] = std::move(blades);
  tree["metadata"] = metadata_tree(metadata_json);
  return tree;
}

// Indented like json.dump(indent=2), except that an array holding no arrays or
// objects stays on one line: one vertex or tet per line keeps big meshes
// readable and small.
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

}  // namespace

std::vector<std::uint8_t> serialize_scene_document(const SceneDocument& document,
                                                   SceneEncoding encoding) {
  const Json tree = document_tree(document.scene, document.metadata_json);
  read_scene_tree(tree, ReadOptions{});  // Never write what the reader would reject.
  return encode(tree, encoding);
}

std::vector<std::uint8_t> serialize_scene(const Scene& scene, SceneEncoding encoding) {
  const Json tree = document_tree(scene, "{}");
  read_scene_tree(tree, ReadOptions{});
  return encode(tree, encoding);
}

}  // namespace hapticut
