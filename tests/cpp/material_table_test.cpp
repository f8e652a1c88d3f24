// The material table and the engine's own range checks: every public
// constructor refuses NaN, infinite, negative or absurd
// values with an error naming the value.
#include "hapticut/material_table.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "hapticut/material.h"
#include "hapticut/parameter_range.h"
#include "test_support.h"

namespace hapticut {
namespace {

using testing::drag_material;
using testing::make_space;
using testing::paper_materials;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// The message of the std::invalid_argument that `action` throws ("" if none).
template <typename Action>
std::string invalid_argument_of(Action action) {
  try {
    action();
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "";
}

TEST(MaterialTable, HasEveryModelInEnumOrderWithItsParameters) {
  const auto models = material_models();
  ASSERT_EQ(models.size(), 5U);
  for (std::size_t i = 0; i < models.size(); ++i) {
    EXPECT_EQ(static_cast<std::size_t>(models[i].model), i);
    EXPECT_EQ(models[i].name, material_model_name(models[i].model));
    EXPECT_FALSE(models[i].summary.empty());
  }
  EXPECT_TRUE(material_model_spec(MaterialModel::Free).parameters.empty());
  // Rigid takes its friction, optional and frictionless when omitted.
  for (const char* name : {"static_friction", "dynamic_friction"}) {
    const MaterialParameterSpec* friction = find_material_parameter(MaterialModel::Rigid, name);
    ASSERT_NE(friction, nullptr) << name;
    EXPECT_FALSE(friction->required) << name;
    EXPECT_EQ(friction->range.default_value, 0.0) << name;
  }
  EXPECT_EQ(material_model_spec(MaterialModel::Rigid).parameters.size(), 2U);
  ASSERT_NE(find_material_parameter(MaterialModel::Drag, "drag_distance_mm"), nullptr);
  EXPECT_EQ(find_material_parameter(MaterialModel::Drag, "break_force_N"), nullptr);
  const MaterialParameterSpec* max_lag =
      find_material_parameter(MaterialModel::Viscous, "max_lag_mm");
  ASSERT_NE(max_lag, nullptr);
  EXPECT_FALSE(max_lag->required);
  EXPECT_EQ(max_lag->range.default_value, Material{}.max_lag_mm);
}

TEST(MaterialTable, EveryRangeIsFiniteBoundedAndHoldsItsDefault) {
  for (const MaterialParameterSpec& parameter : material_parameters()) {
    const ParameterRange& range = parameter.range;
    EXPECT_TRUE(std::isfinite(range.minimum) && std::isfinite(range.maximum)) << range.name;
    EXPECT_GE(range.minimum, 0.0) << range.name;
    EXPECT_LT(range.minimum, range.maximum) << range.name;
    EXPECT_EQ(range_violation(range, range.default_value), RangeViolation::None) << range.name;
    EXPECT_FALSE(range.unit.empty() || range.summary.empty()) << range.name;
  }
}

TEST(MaterialTable, PresetsAreValidMaterialsOfTheirModel) {
  const auto presets = material_presets();
  ASSERT_EQ(presets.size(), 5U);
  for (const MaterialPreset& preset : presets) {
    const Material material = preset_material(preset);
    EXPECT_NO_THROW(validate_material(material)) << preset.name;
    EXPECT_EQ(preset.values.size(), material_model_spec(preset.model).parameters.size())
        << preset.name;
    for (const PresetValue& value : preset.values) {
      EXPECT_NE(find_material_parameter(preset.model, value.parameter), nullptr) << preset.name;
    }
  }
  EXPECT_EQ(preset_material(presets[1]).drag_distance_mm, 2.0);  // soft_tissue
}

TEST(MaterialValidation, RejectsNanInfiniteNegativeAndHugeParameters) {
  for (double bad : {kNan, kInf, -kInf, -1.0, 0.0, 1e308}) {
    const std::string message = invalid_argument_of([&] { validate_material(drag_material(bad)); });
    EXPECT_NE(message.find("material 'flesh' (drag) drag_distance_mm"), std::string::npos)
        << bad << ": " << message;
  }
  EXPECT_EQ(invalid_argument_of([] { validate_material(drag_material(kNan)); }),
            "material 'flesh' (drag) drag_distance_mm: not a finite number");
  EXPECT_EQ(invalid_argument_of([] { validate_material(drag_material(-0.5)); }),
            "material 'flesh' (drag) drag_distance_mm: must be > 0, got -0.5");
  EXPECT_EQ(invalid_argument_of([] { validate_material(drag_material(5000.0)); }),
            "material 'flesh' (drag) drag_distance_mm: must be <= 1000, got 5000");
  Material membrane{"skin", MaterialModel::Membrane};
  membrane.break_force_N = kNan;
  EXPECT_NE(invalid_argument_of([&] { validate_material(membrane); }), "");
  Material viscous{"fat", MaterialModel::Viscous};
  viscous.viscosity_N_s_per_mm = 0.001;
  viscous.max_lag_mm = -kInf;
  EXPECT_EQ(invalid_argument_of([&] { validate_material(viscous); }),
            "material 'fat' (viscous) max_lag_mm: not a finite number");
  // Parameters of other models are not read.
  Material rigid{"bone", MaterialModel::Rigid};
  rigid.drag_distance_mm = kNan;
  EXPECT_NO_THROW(validate_material(rigid));
}

TEST(SpaceValidation, RejectsAMaterialThatWouldTurnTheProxyIntoNan) {
  const MeshData mesh = two_tets_mesh(10.0);
  std::vector<Material> materials = paper_materials();
  materials[1].drag_distance_mm = kNan;
  EXPECT_NE(invalid_argument_of([&] {
              make_space(mesh, {1, 1}, materials);
            }).find("not a finite"),
            std::string::npos);
}

TEST(SpaceValidation, RejectsSettingsOutsideTheirRange) {
  const MeshData mesh = two_tets_mesh(10.0);
  const auto space_with = [&](EngineSettings settings) {
    return invalid_argument_of([&] { make_space(mesh, {0, 2}, paper_materials(), settings); });
  };
  EXPECT_EQ(space_with({}), "");
  EngineSettings settings;
  for (double bad : {0.0, -0.1, kNan, kInf, 1e308}) {
    settings = {};
    settings.stiffness_N_per_mm = bad;
    EXPECT_NE(space_with(settings).find("stiffness_N_per_mm: "), std::string::npos) << bad;
    settings = {};
    settings.servo_rate_Hz = bad;
    EXPECT_NE(space_with(settings).find("servo_rate_Hz: "), std::string::npos) << bad;
    settings = {};
    settings.capped_tick_force_N = bad;
    EXPECT_NE(space_with(settings).find("capped_tick_force_N: "), std::string::npos) << bad;
  }
  settings = {};
  settings.stiffness_N_per_mm = 1e308;
  EXPECT_EQ(space_with(settings), "stiffness_N_per_mm: must be <= 100, got 1e+308");
  for (int bad : {0, -1, 1'000'000'000}) {
    settings = {};
    settings.max_transitions_per_tick = bad;
    EXPECT_NE(space_with(settings).find("max_transitions_per_tick: "), std::string::npos) << bad;
  }
  settings = {};
  settings.max_transitions_per_tick = 1'000'000'000;
  EXPECT_EQ(space_with(settings), "max_transitions_per_tick: must be <= 10000, got 1e+09");
}

TEST(SpaceValidation, FromSceneChecksTheSafetyLimits) {
  Scene scene;
  const MeshData mesh = two_tets_mesh(10.0);
  scene.vertices_mm = mesh.vertices_mm;
  scene.tets = mesh.tets;
  scene.tet_materials = {0, 0};
  scene.materials = {testing::free_material()};
  EXPECT_EQ(invalid_argument_of([&] { Space::from_scene(scene); }), "");
  scene.safety.max_force_N = kInf;
  EXPECT_EQ(invalid_argument_of([&] { Space::from_scene(scene); }),
            "max_force_N: not a finite number");
  scene.safety.max_force_N = 5.0;
  scene.safety.ramp_time_s = -1.0;
  EXPECT_EQ(invalid_argument_of([&] { Space::from_scene(scene); }),
            "ramp_time_s: must be >= 0, got -1");
}

TEST(TetMeshValidation, RejectsAToleranceThatIsNotAToleranceAnyMore) {
  const MeshData mesh = two_tets_mesh(10.0);
  const auto mesh_with = [&](double tolerance_mm) {
    return invalid_argument_of([&] { TetMesh(mesh.vertices_mm, mesh.tets, {0, 0}, tolerance_mm); });
  };
  EXPECT_EQ(mesh_with(0.0), "");
  EXPECT_EQ(mesh_with(1e-6), "");
  EXPECT_EQ(mesh_with(1e-4), "");
  EXPECT_EQ(mesh_with(1e6), "tolerance_mm: must be <= 0.0001, got 1e+06");
  EXPECT_EQ(mesh_with(-1e-9), "tolerance_mm: must be >= 0, got -1e-09");
  EXPECT_EQ(mesh_with(kNan), "tolerance_mm: not a finite number");
}

}  // namespace
}  // namespace hapticut

namespace hapticut {
namespace {

std::string mesh_error_of(const std::vector<Vec3>& vertices,
                          const std::vector<std::array<std::int32_t, 4>>& tets) {
  try {
    TetMesh(vertices, tets, std::vector<std::int32_t>(tets.size(), 0));
  } catch (const MeshError& error) {
    return error.what();
  }
  return "";
}

const std::vector<Vec3> kTwoTetVertices{
    {0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {0, 0, 10}, {10, 10, 10}};

TEST(TetMeshValidation, RejectsATetListedTwice) {
  EXPECT_EQ(mesh_error_of(kTwoTetVertices, {{0, 1, 2, 3}, {1, 2, 3, 4}, {3, 2, 1, 0}}),
            "tets 0 and 2 are the same tet (vertices 0, 1, 2, 3)");
  EXPECT_EQ(mesh_error_of(kTwoTetVertices, {{0, 1, 2, 3}, {0, 1, 2, 3}}),
            "tets 0 and 1 are the same tet (vertices 0, 1, 2, 3)");
}

TEST(TetMeshValidation, RejectsTwoTetsOnTheSameSideOfTheirSharedFace) {
  std::vector<Vec3> vertices = kTwoTetVertices;
  vertices.push_back({1, 1, 1});  // On vertex 0's side of the face (1, 2, 3).
  EXPECT_EQ(mesh_error_of(vertices, {{0, 1, 2, 3}, {1, 2, 3, 5}}),
            "tets 0 and 1 lie on the same side of their shared face (vertices 1, 2, 3): the mesh "
            "is folded");
}

TEST(TetMeshValidation, RejectsOverlappingTetsWithTheirIndices) {
  std::vector<Vec3> vertices = kTwoTetVertices;
  for (int k = 0; k < 4; ++k) vertices.push_back(kTwoTetVertices[k] + Vec3{1, 1, 1});
  EXPECT_EQ(mesh_error_of(vertices, {{0, 1, 2, 3}, {1, 2, 3, 4}, {5, 6, 7, 8}}),
            "tets 0 and 2 overlap (a point well inside tet 0 is inside tet 2)");
  // Apart, the same tets are a valid mesh.
  for (int k = 5; k < 9; ++k) vertices[k] = vertices[k] + Vec3{50, 0, 0};
  EXPECT_EQ(mesh_error_of(vertices, {{0, 1, 2, 3}, {1, 2, 3, 4}, {5, 6, 7, 8}}), "");
}

TEST(TetMeshValidation, AcceptsEveryReferenceMesh) {
  for (const MeshData& mesh : {two_tets_mesh(10.0), edge_fan_mesh(12, 10.0, 10.0), cube_mesh(10.0),
                               vertex_fan_mesh(2, 10.0), double_cone_mesh(10, 10.0, 10.0),
                               grid_mesh({0, 5, 10}, {0, 5, 10}, {0, 5, 10}, 0.3, 21)}) {
    EXPECT_EQ(mesh_error_of(mesh.vertices_mm, mesh.tets), "");
  }
}

}  // namespace
}  // namespace hapticut
