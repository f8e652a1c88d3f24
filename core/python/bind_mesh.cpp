// Bindings: materials, Space (a TetMesh with its materials) and the
// reference meshes of the paper's set-ups.
#include <nanobind/stl/shared_ptr.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include <stdexcept>
#include <string>

#include "arrays.h"
#include "hapticut/material_table.h"
#include "hapticut/parameter_range.h"
#include "hapticut/reference_meshes.h"
#include "hapticut/space.h"

namespace hapticut::python {

namespace {

MaterialModel model_from_name(const std::string& name) {
  std::string names;
  for (const MaterialModelSpec& spec : material_models()) {
    if (name == spec.name) return spec.model;
    names += (names.empty() ? "" : ", ") + std::string(spec.name);
  }
  throw std::invalid_argument("unknown material model '" + name + "' (expected " + names + ")");
}

bool is_parameter_name(std::string_view key) {
  for (const MaterialParameterSpec& parameter : material_parameters()) {
    if (parameter.range.name == key) return true;
  }
  return false;
}

// A material from a dict of the scene file's fields ({"name", "model", ...}).
// Parameters of other models are ignored (dataclasses.asdict lists them all);
// unknown keys, missing required parameters and values out of the table's
// range raise ValueError (Space's own check).
Material material_from_dict(const nb::dict& d) {
  Material m;
  m.name = d.contains("name") ? nb::cast<std::string>(d["name"]) : "";
  if (!d.contains("model")) throw std::invalid_argument("material '" + m.name + "': no model");
  m.model = model_from_name(nb::cast<std::string>(d["model"]));
  for (auto [key, value] : d) {
    const auto text = nb::cast<std::string>(nb::str(key));
    if (text != "name" && text != "model" && text != "cut_to" && !is_parameter_name(text)) {
      throw std::invalid_argument("material '" + m.name + "': unknown field '" + text + "'");
    }
  }
  // The Space checks it against the other materials (cut_to_problem).
  if (d.contains("cut_to") && !d["cut_to"].is_none()) m.cut_to = nb::cast<std::string>(d["cut_to"]);
  for (const MaterialParameterSpec& parameter : material_model_spec(m.model).parameters) {
    const char* key = parameter.range.name.data();  // The table's names are literals.
    if (d.contains(key)) {
      m.*(parameter.field) = nb::cast<double>(d[key]);
    } else if (parameter.required) {
      throw std::invalid_argument("material '" + m.name + "' (" +
                                  std::string(material_model_spec(m.model).name) + "): " + key +
                                  " required");
    } else {
      m.*(parameter.field) = parameter.range.default_value;
    }
  }
  return m;
}

nb::dict range_dict(const ParameterRange& range) {
  nb::dict out;
  out["name"] = std::string(range.name);
  out["unit"] = std::string(range.unit);
  out["minimum"] = range.minimum;
  out["minimum_exclusive"] = range.minimum_exclusive;
  out["maximum"] = range.maximum;
  out["default"] = range.default_value;
  out["summary"] = std::string(range.summary);
  return out;
}

// The material table as plain values (the shape `hapticut materials --json` prints).
nb::dict material_table_dict() {
  nb::list models;
  for (const MaterialModelSpec& spec : material_models()) {
    nb::list parameters;
    for (const MaterialParameterSpec& parameter : spec.parameters) {
      nb::dict item = range_dict(parameter.range);
      item["required"] = parameter.required;
      parameters.append(item);
    }
    nb::dict model;
    model["name"] = std::string(spec.name);
    model["summary"] = std::string(spec.summary);
    model["parameters"] = parameters;
    models.append(model);
  }
  nb::list presets;
  for (const MaterialPreset& preset : material_presets()) {
    const Material material = preset_material(preset);
    nb::dict values;
    for (const MaterialParameterSpec& parameter : material_model_spec(preset.model).parameters) {
      values[nb::str(parameter.range.name.data(), parameter.range.name.size())] =
          material.*(parameter.field);
    }
    nb::dict item;
    item["name"] = std::string(preset.name);
    item["label"] = std::string(preset.label);
    item["model"] = std::string(material_model_spec(preset.model).name);
    item["parameters"] = values;
    presets.append(item);
  }
  nb::dict out;
  out["version"] = kMaterialTableVersion;
  out["models"] = models;
  out["presets"] = presets;
  return out;
}

// The engine settings' ranges, keyed by their scene-file names.
nb::dict setting_ranges_dict() {
  nb::dict out;
  for (const ParameterRange* range :
       {&setting_range::kStiffness, &setting_range::kServoRate, &setting_range::kTolerance,
        &setting_range::kMaxForce, &setting_range::kMaxTorque, &setting_range::kRampTime,
        &setting_range::kMaxTransitions, &setting_range::kCappedTickForce}) {
    out[nb::str(range->name.data(), range->name.size())] = range_dict(*range);
  }
  return out;
}

MeshData to_mesh_data(const PointsIn& vertices, const TetsIn& tets) {
  MeshData data;
  data.vertices_mm = to_points(vertices);
  data.tets.resize(tets.shape(0));
  for (std::size_t t = 0; t < data.tets.size(); ++t) {
    for (int k = 0; k < 4; ++k) data.tets[t][k] = tets(t, k);
  }
  return data;
}

nb::tuple mesh_to_arrays(const MeshData& data) {
  auto tets = new_array<std::int32_t>({data.tets.size(), 4});
  for (std::size_t t = 0; t < data.tets.size(); ++t) {
    for (int k = 0; k < 4; ++k) tets.data()[4 * t + k] = data.tets[t][k];
  }
  return nb::make_tuple(from_points(data.vertices_mm), tets);
}

std::shared_ptr<Space> make_space(const PointsIn& vertices, const TetsIn& tets,
                                  const IndicesIn& tet_materials, const nb::list& materials,
                                  double stiffness_N_per_mm, double servo_rate_Hz,
                                  int max_transitions_per_tick, double capped_tick_force_N,
                                  double tolerance_mm) {
  const MeshData data = to_mesh_data(vertices, tets);
  std::vector<std::int32_t> labels(tet_materials.data(),
                                   tet_materials.data() + tet_materials.shape(0));
  std::vector<Material> table;
  for (nb::handle h : materials) table.push_back(material_from_dict(nb::cast<nb::dict>(h)));
  EngineSettings settings{stiffness_N_per_mm, servo_rate_Hz, max_transitions_per_tick,
                          capped_tick_force_N};
  // Building the mesh's fans and trees can take a while: other Python threads
  // (Blender's UI) run meanwhile.
  nb::gil_scoped_release released;
  return std::const_pointer_cast<Space>(
      Space::create(TetMesh(data.vertices_mm, data.tets, std::move(labels), tolerance_mm),
                    std::move(table), settings));
}

}  // namespace

void bind_mesh(nb::module_& m) {
  nb::exception<MeshError>(m, "MeshError", PyExc_ValueError);

  nb::class_<Space>(m, "Space",
                    "A tet mesh with a material per tet and the engine's settings (immutable).")
      .def(nb::new_([](const PointsIn& vertices, const TetsIn& tets, const IndicesIn& tet_materials,
                       const nb::list& materials, double stiffness_N_per_mm, double servo_rate_Hz,
                       int max_transitions_per_tick, double capped_tick_force_N,
                       double tolerance_mm) {
             return make_space(vertices, tets, tet_materials, materials, stiffness_N_per_mm,
                               servo_rate_Hz, max_transitions_per_tick, capped_tick_force_N,
                               tolerance_mm);
           }),
           nb::arg("vertices"), nb::arg("tets"), nb::arg("tet_materials"), nb::arg("materials"),
           nb::arg("stiffness_N_per_mm") = 0.1, nb::arg("servo_rate_Hz") = 1000.0,
           nb::arg("max_transitions_per_tick") = 64, nb::arg("capped_tick_force_N") = 1.0,
           nb::arg("tolerance_mm") = 0.0,
           "Validates the mesh (raises MeshError naming the offending index) and precomputes "
           "planes, fans and the boundary tree. materials: list of dicts with the scene file's "
           "fields.")
      .def_prop_ro(
          "tet_count", [](const Space& s) { return s.mesh().tet_count(); }, nb::rv_policy::move)
      .def_prop_ro(
          "vertex_count", [](const Space& s) { return s.mesh().vertex_count(); },
          nb::rv_policy::move)
      .def_prop_ro(
          "edge_count", [](const Space& s) { return s.mesh().edge_count(); }, nb::rv_policy::move)
      .def_prop_ro(
          "boundary_face_count", [](const Space& s) { return s.mesh().boundary_faces().size(); },
          nb::rv_policy::move)
      .def_prop_ro("tolerance_mm", &Space::tolerance, nb::rv_policy::move)
      .def_prop_ro(
          "stiffness_N_per_mm", [](const Space& s) { return s.settings().stiffness_N_per_mm; },
          nb::rv_policy::move)
      .def_prop_ro(
          "memory_bytes", [](const Space& s) { return s.mesh().memory_bytes(); },
          nb::rv_policy::move)
      .def_prop_ro(
          "vertices", [](const Space& s) { return from_points(s.mesh().vertices()); },
          nb::rv_policy::move)
      .def_prop_ro(
          "tets",
          [](const Space& s) {
            const auto& tets = s.mesh().tets();
            auto out = new_array<std::int32_t>({tets.size(), 4});
            for (std::size_t t = 0; t < tets.size(); ++t) {
              std::copy(tets[t].begin(), tets[t].end(), out.data() + 4 * t);
            }
            return out;
          },
          nb::rv_policy::move,
          "The tets as stored: positively oriented (an inverted input tet has its last two "
          "vertices swapped). ProxySet.local indexes these.")
      .def_prop_ro(
          "tet_materials",
          [](const Space& s) {
            const auto& labels = s.mesh().materials();
            auto out = new_array<std::int32_t>({labels.size()});
            std::copy(labels.begin(), labels.end(), out.data());
            return out;
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "material_names",
          [](const Space& s) {
            std::vector<std::string> names;
            for (const Material& mat : s.materials()) names.push_back(mat.name);
            return names;
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "stats",
          [](const Space& s) {
            const MeshStats& st = s.mesh().stats();
            nb::dict d;
            d["reoriented_tets"] = st.reoriented_tets;
            d["max_tets_per_edge"] = st.max_tets_per_edge;
            d["mean_tets_per_edge"] = st.mean_tets_per_edge;
            d["max_tets_per_vertex"] = st.max_tets_per_vertex;
            d["mean_tets_per_vertex"] = st.mean_tets_per_vertex;
            d["min_dihedral_deg"] = st.min_dihedral_deg;
            d["boundary_faces"] = st.boundary_faces;
            return d;
          },
          nb::rv_policy::move)
      .def(
          "locate",
          [](const Space& s, const PointsIn& points) {
            auto out = new_array<std::int32_t>({points.shape(0)});
            for (std::size_t i = 0; i < points.shape(0); ++i) {
              out.data()[i] = s.mesh().locate({points(i, 0), points(i, 1), points(i, 2)});
            }
            return out;
          },
          nb::arg("points"), "The tet containing each point, or -1 outside the mesh.");

  m.def("material_table", &material_table_dict,
        "The material models (parameters with unit, range, default, summary) and the named "
        "presets, as plain dicts and lists (the C++ table, material_table.h).");
  m.def("setting_ranges", &setting_ranges_dict,
        "The range of each engine setting, keyed by its scene-file name (parameter_range.h).");
  m.def(
      "two_tets_mesh", [](double size) { return mesh_to_arrays(two_tets_mesh(size)); },
      nb::arg("size_mm") = 10.0, "Two tets sharing a face (Table 2's TET/FACE set-up).");
  m.def(
      "edge_fan_mesh",
      [](int n, double r, double h) { return mesh_to_arrays(edge_fan_mesh(n, r, h)); },
      nb::arg("fan_size") = 12, nb::arg("radius_mm") = 10.0, nb::arg("half_height_mm") = 10.0,
      "One edge (vertices 0-1) shared by fan_size tets (Table 2's EDGE set-up).");
  m.def(
      "icosahedron_mesh", [](double r) { return mesh_to_arrays(icosahedron_mesh(r)); },
      nb::arg("radius_mm") = 10.0, "The icosahedron's centre (vertex 0) in 20 tets.");
  m.def(
      "vertex_fan_mesh", [](int k, double r) { return mesh_to_arrays(vertex_fan_mesh(k, r)); },
      nb::arg("subdivisions") = 1, nb::arg("radius_mm") = 10.0,
      "The centre (vertex 0) of a geodesic ball in 20 x 4^subdivisions tets (0: the "
      "icosahedron).");
  m.def(
      "double_cone_mesh",
      [](int n, double r, double h) { return mesh_to_arrays(double_cone_mesh(n, r, h)); },
      nb::arg("ring_size") = 10, nb::arg("radius_mm") = 10.0, nb::arg("half_height_mm") = 10.0,
      "The centre (vertex 0) of a double cone over a ring of ring_size vertices: 2 x ring_size "
      "tets.");
  m.def(
      "cube_mesh", [](double s) { return mesh_to_arrays(cube_mesh(s)); }, nb::arg("size_mm") = 10.0,
      "A cube of 6 tets, 12 boundary triangles.");
  m.def(
      "grid_mesh",
      [](const std::vector<double>& xs, const std::vector<double>& ys,
         const std::vector<double>& zs, double jitter,
         std::uint64_t seed) { return mesh_to_arrays(grid_mesh(xs, ys, zs, jitter, seed)); },
      nb::arg("xs"), nb::arg("ys"), nb::arg("zs"), nb::arg("jitter") = 0.0, nb::arg("seed") = 1,
      "A box of cells on the given plane coordinates, 6 Kuhn tets per cell.");
}

}  // namespace hapticut::python
