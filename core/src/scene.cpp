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

}  // namespace hapticut
