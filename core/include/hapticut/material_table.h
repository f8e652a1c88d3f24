// The one table of material models: which parameters each model takes, with
// unit, range, default and a one-line summary, and the named presets the
// Blender add-on offers. The scene readers, the bindings, the CLI (`hapticut
// materials`, `hapticut mesh --material`), `hapticut info` and the test of the
// JSON Schema all read this table instead of listing parameters themselves.
#pragma once

#include <span>
#include <string_view>

#include "hapticut/parameter_range.h"
#include "hapticut/scene.h"

namespace hapticut {

// Bumped when a model, parameter or preset changes meaning.
inline constexpr int kMaterialTableVersion = 1;

struct MaterialParameterSpec {
  ParameterRange range;
  double Material::*field = nullptr;  // Where the value lives in a Material.
  bool required = true;               // false: default_value when the file omits it.
};

struct MaterialModelSpec {
  MaterialModel model = MaterialModel::Free;
  std::string_view name;  // As in the scene file's "model".
  std::string_view summary;
  std::span<const MaterialParameterSpec> parameters;
};

struct PresetValue {
  std::string_view parameter;
  double value = 0.0;
};

struct MaterialPreset {
  std::string_view name;   // Identifier ("soft_tissue").
  std::string_view label;  // For people ("Soft tissue").
  MaterialModel model = MaterialModel::Free;
  std::span<const PresetValue> values;  // One per parameter of the model.
};

// The five models, in the order of MaterialModel.
std::span<const MaterialModelSpec> material_models();
const MaterialModelSpec& material_model_spec(MaterialModel model);
// Every parameter of every model once, in the order a scene file lists them.
std::span<const MaterialParameterSpec> material_parameters();
// The parameter `name` of `model`, or nullptr when the model does not take it.
const MaterialParameterSpec* find_material_parameter(MaterialModel model, std::string_view name);
std::span<const MaterialPreset> material_presets();
// The preset as a Material named after it.
Material preset_material(const MaterialPreset& preset);

}  // namespace hapticut
