// The Force Dimension models the forcedimension kind knows, by the type
// dhdGetSystemType returns: a name, whether it has a wrist (a rotation
// through dhdGetOrientationFrame), and the servo's default limits for it in
// the device's own frame. The forces and stiffnesses are conservative
// defaults below what the models' datasheets state, not measurements: a
// binding's max_force= and max_stiffness= change them, a limit set in the
// device (dhdGetMaxForce) lowers the force, and a scene lowers either.
// The workspace is a box about the device's origin a little larger than the
// model's reach, so that only a sample no arm can give is a fault.
#pragma once

#include <string>

#include "devices/device.h"

namespace hapticut::servo {

struct DhdModel {
  int system_type = 0;  // DHD_DEVICE_*; 0 for a type not in the table.
  const char* name = "unknown Force Dimension device";
  bool has_wrist = false;
  double max_force_N = 2.0;
  double max_stiffness_N_per_mm = 1.0;
  double workspace_half_mm = 300.0;  // Half-width of the workspace box.
};

// The table's row for `system_type`; an unknown type gets the most cautious
// limits (DhdModel's defaults) and its number in the name.
DhdModel dhd_model(int system_type);
// The model's limits in the device frame (mm about its origin). No torque:
// this kind renders forces only.
DeviceLimits dhd_model_limits(const DhdModel& model);

}  // namespace hapticut::servo
