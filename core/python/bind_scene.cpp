// Python access to the C++ scene reader and writer (hapticut._core): the only
// ones, hapticut.scenefile reads and writes through them. A scene crosses as a
// dict shaped like hapticut.scenefile.scene_to_dict(): plain values plus numpy
// arrays (vertices (n, 3) float64, tets (m, 4) int32, tet_materials (m,) int32).
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "hapticut/material_table.h"
#include "hapticut/parameter_range.h"
#include "hapticut/scene_io.h"
#include "hapticut/scene_tree.h"

namespace nb = nanobind;
using namespace nb::literals;

namespace {

using hapticut::SceneDocument;
using hapticut::SceneEncoding;
using hapticut::SceneError;

// ---------------------------------------------------------------------------
// SceneError -> hapticut._core.SceneError(ValueError), with .field and .reason.

PyObject* utf8(const std::string& text) {
  return PyUnicode_DecodeUTF8(text.data(), static_cast<Py_ssize_t>(text.size()), "replace");
}

void translate_scene_error(const std::exception_ptr& pending, void* python_type) {
  try {
    std::rethrow_exception(pending);
  } catch (const SceneError& error) {
    auto* type = static_cast<PyObject*>(python_type);
    const std::string message = error.what();
    PyObject* text = utf8(message);
    PyObject* instance = text ? PyObject_CallOneArg(type, text) : nullptr;
    Py_XDECREF(text);
    if (instance == nullptr) return;  // The failed call left its own Python error set.
    PyObject* field = utf8(error.field());
    PyObject* reason = utf8(message.substr(std::min(message.size(), error.field().size() + 2)));
    if (field) PyObject_SetAttrString(instance, "field", field);
    if (reason) PyObject_SetAttrString(instance, "reason", reason);
    Py_XDECREF(field);
    Py_XDECREF(reason);
    PyErr_SetObject(type, instance);
    Py_DECREF(instance);
  }
}

// ---------------------------------------------------------------------------
// C++ -> Python.

template <typename T>
nb::object numpy_array(std::vector<T>&& values, std::initializer_list<std::size_t> shape) {
  auto* owned = new std::vector<T>(std::move(values));
  nb::capsule owner(owned, [](void* data) noexcept { delete static_cast<std::vector<T>*>(data); });
  return nb::ndarray<nb::numpy, T>(owned->data(), shape, owner).cast();
}

nb::tuple point_tuple(const hapticut::Vec3& point) {
  return nb::make_tuple(point.x, point.y, point.z);
}

// The decoded tree as plain Python values (depth is bounded by the decoder).
nb::object tree_to_python(const hapticut::SceneTree& value) {
  using Type = hapticut::SceneTree::value_t;
  switch (value.type()) {
    case Type::null:
    case Type::discarded:
      return nb::none();
    case Type::boolean:
      return nb::bool_(value.get<bool>());
    case Type::number_integer:
      return nb::int_(value.get<std::int64_t>());
    case Type::number_unsigned:
      return nb::steal(PyLong_FromUnsignedLongLong(value.get<std::uint64_t>()));
    case Type::number_float:
      return nb::float_(value.get<double>());
    case Type::string: {
      const auto& text = value.get_ref<const std::string&>();
      return nb::str(text.data(), text.size());  // Valid UTF-8: the decoder checked.
    }
    case Type::binary: {
      const auto& bytes = value.get_binary();
      return nb::bytes(bytes.data(), bytes.size());
    }
    case Type::array: {
      nb::list out;
      for (const auto& item : value) out.append(tree_to_python(item));
      return out;
    }
    case Type::object: {
      nb::dict out;
      for (auto it = value.begin(); it != value.end(); ++it) {
        out[nb::str(it.key().data(), it.key().size())] = tree_to_python(it.value());
      }
      return out;
    }
  }
  return nb::none();
}

nb::dict document_to_dict(const SceneDocument& document) {
  const hapticut::Scene& scene = document.scene;
  nb::list materials;
  for (const hapticut::Material& material : scene.materials) {
    nb::dict item;
    item["name"] = material.name;
    item["model"] = hapticut::material_model_name(material.model);
    // Every parameter of every model (the table's order), as Material holds it.
    for (const hapticut::MaterialParameterSpec& parameter : hapticut::material_parameters()) {
      item[nb::str(parameter.range.name.data(), parameter.range.name.size())] =
          material.*(parameter.field);
    }
    item["cut_to"] = material.cut_to;
    materials.append(item);
  }
  std::vector<double> vertices;
  vertices.reserve(3 * scene.vertices_mm.size());
  for (const hapticut::Vec3& v : scene.vertices_mm)
    vertices.insert(vertices.end(), {v.x, v.y, v.z});
  std::vector<std::int32_t> tets;
  tets.reserve(4 * scene.tets.size());
  for (const auto& tet : scene.tets) tets.insert(tets.end(), tet.begin(), tet.end());
  nb::list blades;
  for (const hapticut::BladeSpec& blade : scene.blades) {
    nb::dict item;
    item["name"] = blade.name;
    item["start_mm"] = point_tuple(blade.start_mm);
    item["end_mm"] = point_tuple(blade.end_mm);
    item["points"] = blade.points;
    item["coupling"] = hapticut::blade_coupling_name(blade.coupling);
    item["orientation"] = hapticut::blade_orientation_name(blade.orientation);
    blades.append(item);
  }
  nb::dict safety;
  safety["max_force_N"] = scene.safety.max_force_N;
  safety["max_torque_N_mm"] = scene.safety.max_torque_N_mm;
  safety["ramp_time_s"] = scene.safety.ramp_time_s;
  safety["capped_tick_force_N"] = scene.safety.capped_tick_force_N;

  nb::dict out;
  out["materials"] = materials;
  out["vertices"] = numpy_array(std::move(vertices), {scene.vertices_mm.size(), 3});
  out["tets"] = numpy_array(std::move(tets), {scene.tets.size(), 4});
  out["tet_materials"] =
      numpy_array(std::vector<std::int32_t>(scene.tet_materials), {scene.tet_materials.size()});
  out["blades"] = blades;
  out["stiffness_N_per_mm"] = scene.stiffness_N_per_mm;
  out["servo_rate_Hz"] = scene.servo_rate_Hz;
  out["tolerance_mm"] = scene.tolerance_mm;
  out["max_transitions_per_tick"] = scene.max_transitions_per_tick;
  out["safety"] = safety;
  out["metadata"] = nb::module_::import_("json").attr("loads")(document.metadata_json);
  return out;
}

// ---------------------------------------------------------------------------
// Python -> C++. Shape and dtype problems of the arrays are reported with the
// field they would have in the file; the writer's own checks do the rest.

// A Python value of the wrong type is named by its field, as the reader names a
// wrong value in a file ("/materials/0/name: expected a string, got int").
template <typename T>
T cast_at(nb::handle value, const std::string& field) {
  try {
    return nb::cast<T>(value);
  } catch (const nb::cast_error&) {
    const char* expected = std::is_same_v<T, std::string> ? "a string"
                           : std::is_integral_v<T>        ? "an integer"
                           : std::is_floating_point_v<T>  ? "a number"
                                                          : "a mapping";
    const auto type = nb::cast<std::string>(nb::str(value.type().attr("__name__")));
    throw SceneError(field, std::string("expected ") + expected + ", got " + type);
  }
}

template <typename T>
T get_or(const nb::dict& mapping, const char* key, T fallback, const std::string& prefix) {
  return mapping.contains(key) ? cast_at<T>(mapping[key], prefix + "/" + key) : fallback;
}

// An (n, columns) or (n,) array of `dtype_name`, C-contiguous, from any array-like.
template <typename T>
std::vector<T> read_array(nb::handle value, const char* dtype_kinds, const char* dtype_name,
                          std::size_t columns, const std::string& field) {
  nb::module_ numpy = nb::module_::import_("numpy");
  nb::object array = numpy.attr("asarray")(value);
  const std::string kind = nb::cast<std::string>(array.attr("dtype").attr("kind"));
  const std::size_t size = nb::cast<std::size_t>(array.attr("size"));
  if (size > 0 && kind.find_first_of(dtype_kinds) == std::string::npos) {
    throw SceneError(field, "expected an array of " + std::string(dtype_name) + ", got dtype " +
                                nb::cast<std::string>(nb::str(array.attr("dtype"))));
  }
  const auto ndim = nb::cast<std::size_t>(array.attr("ndim"));
  const nb::tuple shape = nb::cast<nb::tuple>(array.attr("shape"));
  const bool shape_ok =
      size == 0 ||
      (columns == 0 ? ndim == 1 : ndim == 2 && nb::cast<std::size_t>(shape[1]) == columns);
  if (!shape_ok) {
    throw SceneError(
        field, "expected an array of shape " +
                   std::string(columns == 0 ? "(n,)" : "(n, " + std::to_string(columns) + ")") +
                   ", got shape " + nb::cast<std::string>(nb::str(shape)));
  }
  nb::object converted = numpy.attr("ascontiguousarray")(array, "dtype"_a = dtype_name);
  auto flat = nb::cast<nb::ndarray<const T, nb::c_contig, nb::device::cpu>>(converted);
  return std::vector<T>(flat.data(), flat.data() + flat.size());
}

std::int32_t to_index(std::int64_t value, const std::string& field) {
  if (value < std::numeric_limits<std::int32_t>::min() ||
      value > std::numeric_limits<std::int32_t>::max()) {
    throw SceneError(field, "index " + std::to_string(value) + " does not fit in 32 bits");
  }
  return static_cast<std::int32_t>(value);
}

hapticut::Vec3 read_point(nb::handle value, const std::string& field) {
  const auto xyz = nb::cast<std::vector<double>>(value);
  if (xyz.size() != 3) {
    throw SceneError(field, "expected 3 coordinates, got " + std::to_string(xyz.size()));
  }
  return {xyz[0], xyz[1], xyz[2]};
}

hapticut::Material read_material(const nb::dict& item, std::size_t index) {
  hapticut::Material material;
  const std::string field = "/materials/" + std::to_string(index);
  material.name = cast_at<std::string>(item["name"], field + "/name");
  const auto model_name = cast_at<std::string>(item["model"], field + "/model");
  const auto model = hapticut::material_model_from_name(model_name);
  if (!model) {
    std::string known;
    for (const hapticut::MaterialModelSpec& spec : hapticut::material_models()) {
      known += (known.empty() ? "" : ", ") + std::string(spec.name);
    }
    throw SceneError(field + "/model",
                     "unknown model '" + model_name + "' (expected " + known + ")");
  }
  material.model = *model;
  for (const hapticut::MaterialParameterSpec& parameter : hapticut::material_parameters()) {
    const char* key = parameter.range.name.data();  // The table's names are literals.
    material.*(parameter.field) = get_or(item, key, material.*(parameter.field), field);
  }
  // Empty or absent: a cut tet stays as it is (checked with the other materials).
  material.cut_to = get_or(item, "cut_to", material.cut_to, field);
  return material;
}

SceneDocument document_from_dict(const nb::dict& scene_dict) {
  SceneDocument document;
  hapticut::Scene& scene = document.scene;
  std::size_t index = 0;
  for (nb::handle item : scene_dict["materials"]) {
    const std::string field = "/materials/" + std::to_string(index);
    scene.materials.push_back(read_material(cast_at<nb::dict>(item, field), index++));
  }
  const auto vertices =
      read_array<double>(scene_dict["vertices"], "iuf", "float64", 3, "/mesh/vertices");
  for (std::size_t i = 0; i < vertices.size(); i += 3) {
    scene.vertices_mm.emplace_back(vertices[i], vertices[i + 1], vertices[i + 2]);
  }
  const auto tets = read_array<std::int64_t>(scene_dict["tets"], "iu", "int64", 4, "/mesh/tets");
  scene.tets.resize(tets.size() / 4);
  for (std::size_t i = 0; i < tets.size(); ++i) {
    scene.tets[i / 4][i % 4] =
        to_index(tets[i], "/mesh/tets/" + std::to_string(i / 4) + "/" + std::to_string(i % 4));
  }
  const auto tet_materials = read_array<std::int64_t>(scene_dict["tet_materials"], "iu", "int64", 0,
                                                      "/mesh/tet_materials");
  for (std::size_t i = 0; i < tet_materials.size(); ++i) {
    scene.tet_materials.push_back(
        to_index(tet_materials[i], "/mesh/tet_materials/" + std::to_string(i)));
  }
  if (scene_dict.contains("blades")) {
    index = 0;
    for (nb::handle value : scene_dict["blades"]) {
      const std::string field = "/blades/" + std::to_string(index++);
      const auto item = cast_at<nb::dict>(value, field);
      hapticut::BladeSpec blade;
      blade.name = cast_at<std::string>(item["name"], field + "/name");
      blade.start_mm = read_point(item["start_mm"], field + "/start_mm");
      blade.end_mm = read_point(item["end_mm"], field + "/end_mm");
      blade.points = get_or(item, "points", blade.points, field);
      if (item.contains("coupling")) {
        blade.coupling =
            hapticut::blade_coupling_at(cast_at<std::string>(item["coupling"], field + "/coupling"),
                                        blade.name, field + "/coupling");
      }
      if (item.contains("orientation")) {
        blade.orientation = hapticut::blade_orientation_at(
            cast_at<std::string>(item["orientation"], field + "/orientation"), blade.name,
            field + "/orientation");
      }
      scene.blades.push_back(blade);
    }
  }
  scene.stiffness_N_per_mm =
      get_or(scene_dict, "stiffness_N_per_mm", scene.stiffness_N_per_mm, "/coupling");
  scene.servo_rate_Hz = get_or(scene_dict, "servo_rate_Hz", scene.servo_rate_Hz, "/coupling");
  scene.tolerance_mm = get_or(scene_dict, "tolerance_mm", scene.tolerance_mm, "");
  // The file keeps the engine's transition budget in its "safety" object.
  scene.max_transitions_per_tick =
      get_or(scene_dict, "max_transitions_per_tick", scene.max_transitions_per_tick, "/safety");
  if (scene_dict.contains("safety")) {
    const auto safety = cast_at<nb::dict>(scene_dict["safety"], "/safety");
    // The file's place for it, not the dict's: refused, so a file-shaped dict loses no value.
    if (safety.contains("max_transitions_per_tick")) {
      throw SceneError("/safety/max_transitions_per_tick",
                       "a scene dict keeps it at its top level (Scene.max_transitions_per_tick)");
    }
    hapticut::SafetyLimits& limits = scene.safety;
    limits.max_force_N = get_or(safety, "max_force_N", limits.max_force_N, "/safety");
    limits.max_torque_N_mm = get_or(safety, "max_torque_N_mm", limits.max_torque_N_mm, "/safety");
    limits.ramp_time_s = get_or(safety, "ramp_time_s", limits.ramp_time_s, "/safety");
    limits.capped_tick_force_N =
        get_or(safety, "capped_tick_force_N", limits.capped_tick_force_N, "/safety");
  }
  if (scene_dict.contains("metadata")) {
    try {
      document.metadata_json = nb::cast<std::string>(nb::module_::import_("json").attr("dumps")(
          scene_dict["metadata"], "ensure_ascii"_a = false, "allow_nan"_a = false));
    } catch (const nb::python_error& error) {  // TypeError, ValueError: values JSON lacks.
      if (!error.matches(PyExc_TypeError) && !error.matches(PyExc_ValueError)) throw;
      const std::string reason = nb::cast<std::string>(nb::str(error.value()));
      throw SceneError("/metadata", "cannot encode: " + reason);
    }
  }
  return document;
}

SceneEncoding encoding_named(const std::string& name) {
  if (name == "json") return SceneEncoding::Json;
  if (name == "msgpack") return SceneEncoding::MessagePack;
  throw nb::value_error(("unknown encoding '" + name + "' (expected json or msgpack)").c_str());
}

std::vector<std::uint8_t> bytes_of(const nb::bytes& data) {
  const auto* begin = static_cast<const std::uint8_t*>(data.data());
  return {begin, begin + data.size()};
}

}  // namespace

void bind_scene(nb::module_& m) {
  PyObject* scene_error = PyErr_NewExceptionWithDoc(
      "hapticut._core.SceneError",
      "A scene the C++ reader or writer rejects; .field is the JSON pointer of the offending "
      "field, .reason the rest of the message.",
      PyExc_ValueError, nullptr);
  if (scene_error == nullptr) throw nb::python_error();
  m.attr("SceneError") = nb::steal(scene_error);
  nb::register_exception_translator(translate_scene_error, scene_error);

  m.def(
      "read_scene_file",
      [](const std::string& path, bool strict) {
        return document_to_dict(hapticut::load_scene_document(path, {.strict = strict}));
      },
      "path"_a, "strict"_a = false,
      "Read a scene file with the C++ reader (.msgpack: MessagePack, else JSON) into a dict.");
  m.def(
      "write_scene_file",
      [](const nb::dict& scene, const std::string& path) {
        hapticut::save_scene_document(document_from_dict(scene), path);
      },
      "scene"_a, "path"_a, "Write a scene dict with the C++ writer, atomically.");
  m.def(
      "parse_scene_document",
      [](const nb::bytes& data, const std::string& encoding, bool strict) {
        const SceneDocument document = hapticut::parse_scene_document(
            bytes_of(data), encoding_named(encoding), {.strict = strict});
        return nb::make_tuple(document_to_dict(document), document.reoriented_tets);
      },
      "data"_a, "encoding"_a = "json", "strict"_a = false,
      "Parse scene bytes with the C++ reader: (scene dict, number of inverted tets it "
      "re-oriented).");
  m.def(
      "range_problem",
      [](const std::string& name, double value) {
        for (const hapticut::MaterialParameterSpec& parameter : hapticut::material_parameters()) {
          if (parameter.range.name == name) {
            return hapticut::range_reason(parameter.range, value,
                                          hapticut::SceneTree(value).dump());
          }
        }
        throw nb::value_error(("unknown material parameter '" + name + "'").c_str());
      },
      "name"_a, "value"_a,
      "'' when value is in the range of the material parameter `name`, else the reason as the "
      "scene reader words it.");
  m.def(
      "parse_scene_bytes",
      [](const nb::bytes& data, const std::string& encoding, bool strict) {
        return document_to_dict(hapticut::parse_scene_document(
            bytes_of(data), encoding_named(encoding), {.strict = strict}));
      },
      "data"_a, "encoding"_a = "json", "strict"_a = false,
      "Parse scene bytes ('json' or 'msgpack') with the C++ reader into a dict.");
  m.def(
      "decode_scene_tree",
      [](const nb::bytes& data, const std::string& encoding) {
        return tree_to_python(
            hapticut::decode_scene_tree(bytes_of(data), encoding_named(encoding)));
      },
      "data"_a, "encoding"_a = "json",
      "Decode scene bytes into plain Python values with the C++ decoder both readers share "
      "(bounded nesting, no duplicate keys, valid UTF-8, nothing after the value).");
  m.def(
      "serialize_scene_bytes",
      [](const nb::dict& scene, const std::string& encoding) {
        const auto bytes =
            hapticut::serialize_scene_document(document_from_dict(scene), encoding_named(encoding));
        return nb::bytes(bytes.data(), bytes.size());
      },
      "scene"_a, "encoding"_a = "json", "Serialize a scene dict with the C++ writer.");
}
