// The scene, as read from and written to a scene file (format version 1).
// Units: lengths in mm, forces in N, time in s. The JSON Schema lives in
// core/hapticut/schema/scene-v1.schema.json; docs/scene-format.md explains it.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hapticut/material.h"  // Material, MaterialModel: scene users keep compiling.
#include "hapticut/parameter_range.h"
#include "hapticut/vec3.h"

namespace hapticut {

inline constexpr int kSceneFormatVersion = 1;
inline constexpr std::string_view kSceneFormatName = "hapticut.scene";

// How a blade's points move together (docs/decisions.md, "The rigid blade"):
// the paper's independent proxies, or one rigid edge whose pose the point
// proxies detect contacts for. Rigid is the default: a knife is one body.
enum class BladeCoupling : std::uint8_t { Independent, Rigid };
// A rigid blade's orientation: its own (a bone under one end tilts it), or
// the device's (for devices that render no torque). Free is the default
// (docs/decisions.md, "The rigid blade").
enum class BladeOrientation : std::uint8_t { Free, Locked };

struct BladeSpec {
  std::string name;
  Vec3 start_mm;    // In the tool frame.
  Vec3 end_mm;      // In the tool frame.
  int points = 50;  // Sample points along the edge, ends included (>= 1).
  BladeCoupling coupling = BladeCoupling::Rigid;
  BladeOrientation orientation = BladeOrientation::Free;
};

// The file's "safety" object, less the engine's transition budget the file
// also keeps there (Scene::max_transitions_per_tick). Defaults:
// parameter_range.h (setting_range).
struct SafetyLimits {
  // Clamp on the summed blade force.
  double max_force_N = setting_range::kMaxForce.default_value;
  // Clamp on the torque about the tool origin.
  double max_torque_N_mm = setting_range::kMaxTorque.default_value;
  // Force ramp after start or after a fault.
  double ramp_time_s = setting_range::kRampTime.default_value;
  // Per-point force limit on a capped tick.
  double capped_tick_force_N = setting_range::kCappedTickForce.default_value;
};

// Throws std::invalid_argument naming the first limit outside its range
// (parameter_range.h); the servo's safety layer takes only checked limits
// (Space::from_scene calls it).
void check_safety_limits(const SafetyLimits& limits);

struct Scene {
  int version = kSceneFormatVersion;
  // Coupling k in f = k (q - p), eq. (15).
  double stiffness_N_per_mm = setting_range::kStiffness.default_value;
  double servo_rate_Hz = setting_range::kServoRate.default_value;
  // 0: derived from the mesh's size (see docs/decisions.md).
  double tolerance_mm = setting_range::kTolerance.default_value;
  // Cap on one proxy's transitions per tick (docs/method.md): an engine budget,
  // not a safety limit. The file keeps it in its "safety" object.
  int max_transitions_per_tick = default_count(setting_range::kMaxTransitions);
  std::vector<Material> materials;
  std::vector<Vec3> vertices_mm;
  std::vector<std::array<std::int32_t, 4>> tets;
  std::vector<std::int32_t> tet_materials;  // Index into materials, one per tet.
  std::vector<BladeSpec> blades;
  SafetyLimits safety;
};

const char* material_model_name(MaterialModel model);
// The names scene files and Python use ("rigid", "independent"; "free",
// "locked"), and back; nullopt for a name that is none of them.
const char* blade_coupling_name(BladeCoupling coupling);
const char* blade_orientation_name(BladeOrientation orientation);
std::optional<BladeCoupling> blade_coupling_from_name(std::string_view name);
std::optional<BladeOrientation> blade_orientation_from_name(std::string_view name);

}  // namespace hapticut
