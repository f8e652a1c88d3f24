#include "hapticut/material_table.h"

#include <array>
#include <string>

namespace hapticut {

namespace {

// The ranges are parameter_range.h's (material_range); this adds where each
// value lives and whether a file may omit it.
constexpr MaterialParameterSpec kDragDistance{material_range::kDragDistance,
                                              &Material::drag_distance_mm, true};
constexpr MaterialParameterSpec kViscosity{material_range::kViscosity,
                                           &Material::viscosity_N_s_per_mm, true};
constexpr MaterialParameterSpec kMaxLag{material_range::kMaxLag, &Material::max_lag_mm, false};
constexpr MaterialParameterSpec kBreakForce{material_range::kBreakForce, &Material::break_force_N,
                                            true};

constexpr MaterialParameterSpec kStaticFriction{material_range::kStaticFriction,
                                                &Material::static_friction, false};
constexpr MaterialParameterSpec kDynamicFriction{material_range::kDynamicFriction,
                                                 &Material::dynamic_friction, false};

constexpr std::array<MaterialParameterSpec, 6> kAllParameters{
    kDragDistance, kViscosity, kMaxLag, kBreakForce, kStaticFriction, kDynamicFriction};
constexpr std::array<MaterialParameterSpec, 1> kDragParameters{kDragDistance};
constexpr std::array<MaterialParameterSpec, 2> kViscousParameters{kViscosity, kMaxLag};
constexpr std::array<MaterialParameterSpec, 1> kMembraneParameters{kBreakForce};
constexpr std::array<MaterialParameterSpec, 2> kRigidParameters{kStaticFriction, kDynamicFriction};

constexpr std::array<MaterialModelSpec, 5> kModels{{
    {MaterialModel::Free, "free", "no resistance: the proxy follows the device point (air)", {}},
    {MaterialModel::Drag, "drag", "the proxy trails the device point at a fixed distance",
     kDragParameters},
    {MaterialModel::Rigid, "rigid", "impenetrable: the proxy stays on the surface (bone)",
     kRigidParameters},
    {MaterialModel::Viscous, "viscous", "drag whose lag grows with the stroke speed",
     kViscousParameters},
    {MaterialModel::Membrane, "membrane", "rigid until pushed hard enough, then free (skin)",
     kMembraneParameters},
}};

constexpr std::array<PresetValue, 1> kSoftTissueValues{{{"drag_distance_mm", 2.0}}};
constexpr std::array<PresetValue, 2> kFatValues{
    {{"viscosity_N_s_per_mm", 0.002}, {"max_lag_mm", 10.0}}};
// A point's own spring breaks the skin (eq. (15)): at the default stiffness, a push of a few
// mm, so a first stroke at the default settings cuts through.
constexpr std::array<PresetValue, 1> kSkinValues{{{"break_force_N", 0.3}}};

// Bone against a steel blade: a knife pressed onto a round bone stays where it
// landed until pulled along the bone at 0.4 times the push, then slides at 0.3.
constexpr std::array<PresetValue, 2> kBoneValues{
    {{"static_friction", 0.4}, {"dynamic_friction", 0.3}}};

constexpr std::array<MaterialPreset, 5> kPresets{{
    {"air", "Air", MaterialModel::Free, {}},
    {"soft_tissue", "Soft tissue", MaterialModel::Drag, kSoftTissueValues},
    {"fat", "Fat", MaterialModel::Viscous, kFatValues},
    {"skin", "Skin", MaterialModel::Membrane, kSkinValues},
    {"bone", "Bone", MaterialModel::Rigid, kBoneValues},
}};

}  // namespace

std::span<const MaterialModelSpec> material_models() { return kModels; }

const MaterialModelSpec& material_model_spec(MaterialModel model) {
  for (const MaterialModelSpec& spec : kModels) {
    if (spec.model == model) return spec;
  }
  return kModels[0];  // Unreachable: every enumerator has a row.
}

std::span<const MaterialParameterSpec> material_parameters() { return kAllParameters; }

const MaterialParameterSpec* find_material_parameter(MaterialModel model, std::string_view name) {
  for (const MaterialParameterSpec& parameter : material_model_spec(model).parameters) {
    if (parameter.range.name == name) return &parameter;
  }
  return nullptr;
}

std::span<const MaterialPreset> material_presets() { return kPresets; }

Material preset_material(const MaterialPreset& preset) {
  Material material;
  material.name = std::string(preset.name);
  material.model = preset.model;
  for (const MaterialParameterSpec& parameter : material_model_spec(preset.model).parameters) {
    material.*(parameter.field) = parameter.range.default_value;
  }
  for (const PresetValue& value : preset.values) {
    material.*(find_material_parameter(preset.model, value.parameter)->field) = value.value;
  }
  return material;
}

}  // namespace hapticut
