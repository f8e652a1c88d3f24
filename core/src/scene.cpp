#include "hapticut/scene.h"

namespace hapticut {

const char* material_model_name(MaterialModel model) {
  switch (model) {
    case MaterialModel::Free:
      return "free";
    case MaterialModel::Drag:
      return "drag";
    case MaterialModel::Rigid:
      return "rigid";
    case MaterialModel::Viscous:
      return "viscous";
    case MaterialModel::Membrane:
      return "membrane";
  }
  return "unknown";
}

const char* blade_coupling_name(BladeCoupling coupling) {
  return coupling == BladeCoupling::Rigid ? "rigid" : "independent";
}

const char* blade_orientation_name(BladeOrientation orientation) {
  return orientation == BladeOrientation::Locked ? "locked" : "free";
}

std::optional<BladeCoupling> blade_coupling_from_name(std::string_view name) {
  for (const BladeCoupling coupling : {BladeCoupling::Rigid, BladeCoupling::Independent}) {
    if (name == blade_coupling_name(coupling)) return coupling;
  }
  return std::nullopt;
}

std::optional<BladeOrientation> blade_orientation_from_name(std::string_view name) {
  for (const BladeOrientation orientation : {BladeOrientation::Free, BladeOrientation::Locked}) {
    if (name == blade_orientation_name(orientation)) return orientation;
  }
  return std::nullopt;
}

}  // namespace hapticut
