#include "session.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "devices/viewport_device.h"
#include "hapticut/parameter_range.h"
#include "hapticut/scene_io.h"
#include "hapticut/tet_mesh.h"
#include "passivity.h"

namespace hapticut::servo {

namespace {

Scene read_scene_source(const SessionConfig& config, const std::function<void()>& between_stages) {
  if (config.scene) return *config.scene;
  if (!config.scene_json.empty()) {
    const std::vector<std::uint8_t> bytes(config.scene_json.begin(), config.scene_json.end());
    return parse_scene(bytes, SceneEncoding::Json);
  }
  if (config.scene_path.empty()) throw SceneError("(file)", "no scene given");
  std::vector<std::uint8_t> bytes;
  try {
    bytes = read_regular_file(config.scene_path, config.max_scene_bytes, "--max-scene-bytes");
  } catch (const FileRefused& e) {
    throw SceneError("(file)", e.what());
  }
  between_stages();
  return parse_scene(bytes, encoding_for_path(config.scene_path));
}

void bounds(const Scene& scene, Vec3& lo, Vec3& hi) {
  const double inf = std::numeric_limits<double>::infinity();
  lo = {inf, inf, inf};
  hi = {-inf, -inf, -inf};
  for (const Vec3& v : scene.vertices_mm) {
    lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
    hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
  }
}

}  // namespace

Session::Session(const SessionConfig& config, const std::function<void()>& between_stages) {
  scene_ = read_scene_source(config, between_stages);
  between_stages();
  scene_label_ = config.scene                ? std::string("(in memory)")
                 : config.scene_json.empty() ? config.scene_path
                                             : std::string("(inline)");
  if (scene_.blades.empty()) throw SceneError("/blades", "the scene has no blade to drive");
  rate_Hz_ = config.rate_Hz > 0.0 ? config.rate_Hz : scene_.servo_rate_Hz;
  if (!(rate_Hz_ >= 1.0 && rate_Hz_ <= kMaxRate_Hz)) {
    const std::string reason = format_value(rate_Hz_) + " Hz is outside the servo's 1 to 10000 Hz";
    if (config.rate_Hz > 0.0) throw DeviceError("rate " + reason);
    throw SceneError("/coupling/servo_rate_Hz", reason);
  }
  as_fast_as_possible_ = config.as_fast_as_possible;
  // The engine's own checks of what the scene reader passed (a mesh whose
  // tets repeat, a blade beyond the engine's points) name the scene's field too.
  try {
    space_ = Space::from_scene(scene_);
  } catch (const MeshError& e) {
    throw SceneError("/mesh/tets", e.what());
  }
  between_stages();
  shading_ = std::make_shared<const ForceShading>(*space_);
  cuts_ = std::make_shared<CutState>(space_);
  cut_feed_ = std::make_unique<CutFeed>(static_cast<std::size_t>(space_->mesh().tet_count()));
  between_stages();

  std::vector<DeviceSpec> specs;
  for (const std::string& text : config.devices) specs.push_back(parse_device_spec(text));
  std::string blade_names;
  for (const BladeSpec& b : scene_.blades)
    blade_names += (blade_names.empty() ? "" : ", ") + b.name;
  for (DeviceSpec& spec : specs) {
    if (spec.blade.empty()) {
      if (scene_.blades.size() != 1) {
        throw DeviceError(spec.describe() + ": the scene has " +
                          std::to_string(scene_.blades.size()) + " blades (" + blade_names +
                          "); name one: NAME=" + spec.kind + ":...");
      }
      spec.blade = scene_.blades[0].name;
    }
    const bool known = std::any_of(scene_.blades.begin(), scene_.blades.end(),
                                   [&](const BladeSpec& b) { return b.name == spec.blade; });
    if (!known) {
      throw DeviceError(spec.describe() + ": the scene has no blade '" + spec.blade +
                        "' (it has: " + blade_names + ")");
    }
  }

  DeviceContext context;
  context.scene = &scene_;
  context.rate_Hz = rate_Hz_;
  context.as_fast_as_possible = as_fast_as_possible_;
  context.watchdog_s = config.watchdog_ms / 1000.0;
  context.remote_bridge_allowed = config.remote_bridge_allowed;
  bounds(scene_, context.scene_min_mm, context.scene_max_mm);

  SafetySettings request = config.safety_request;
  if (config.lower_to_scene_limits) {
    request.max_force_N = std::min(request.max_force_N, scene_.safety.max_force_N);
    request.max_torque_N_mm = std::min(request.max_torque_N_mm, scene_.safety.max_torque_N_mm);
    if (request.ramp_time_s < 0.0) request.ramp_time_s = scene_.safety.ramp_time_s;
  }
  if (request.ramp_time_s < 0.0) request.ramp_time_s = setting_range::kRampTime.default_value;
  request.watchdog_ticks =
      std::max(1, static_cast<int>(std::lround(config.watchdog_ms / 1000.0 * rate_Hz_)));
  request.late_tick_s = config.watchdog_ms / 1000.0;

  bindings_.reserve(scene_.blades.size());
  for (const BladeSpec& blade_spec : scene_.blades) {
    const DeviceSpec* spec = nullptr;
    for (const DeviceSpec& s : specs) {
      if (s.blade == blade_spec.name) {
        if (spec != nullptr) {
          throw DeviceError("blade '" + blade_spec.name + "' has two devices ('" + spec->text +
                            "' and '" + s.text + "')");
        }
        spec = &s;
      }
    }
    if (spec == nullptr) {
      throw DeviceError("blade '" + blade_spec.name + "' has no device (add --device " +
                        blade_spec.name + "=KIND:ARGS, e.g. " + blade_spec.name + "=sim)");
    }
    context.blade = blade_spec.name;
    Binding binding;
    binding.blade_name = blade_spec.name;
    binding.device_text = spec->text;
    binding.device = make_device(*spec, context);
    binding.viewport = dynamic_cast<ViewportDevice*>(binding.device.get());
    try {
      binding.blade = std::make_unique<Blade>(space_, blade_spec, shading_, cuts_);
    } catch (const std::invalid_argument& e) {
      throw SceneError("/blades/" + std::to_string(bindings_.size()), e.what());
    }
    binding.requested = request;
    binding.safety = std::make_unique<SafetyChannel>(request, binding.device->limits());
    binding.device_max_stiffness_N_per_mm = stiffness_limit(binding.device->limits(), rate_Hz_);
    binding.springs = rendered_springs(binding.blade->coupling(), binding.blade->point_count());
    binding.max_stiffness_N_per_mm =
        point_stiffness_limit(binding.device_max_stiffness_N_per_mm, binding.springs);
    // Passivity for every device that renders force (docs/stability.md).
    if (config.passivity && binding.device->limits().has_force_output) {
      binding.safety->set_passivity(
          make_passivity_controller(config.passivity_link_delay_s, rate_Hz_));
      binding.passivity = true;
    }
    binding.snapshot = BladeTickSnapshot(blade_spec.points);
    bindings_.push_back(std::move(binding));
    between_stages();
  }
  // A replay starts from the cuts its recording started with.
  for (const Binding& b : bindings_) {
    const std::span<const std::int32_t> initial = b.device->initial_cuts();
    if (initial.empty()) continue;
    try {
      cuts_->set_cuts(initial);
    } catch (const std::invalid_argument& e) {
      throw DeviceError("blade '" + b.blade_name + "': device '" + b.device_text +
                        "': the recording's cuts do not fit this scene (" + e.what() + ")");
    }
    break;
  }
  cut_feed_->follow(*cuts_);
  if (frame_bytes() > kMaxFrameBytes) {
    throw SceneError("/blades", "a stream frame of this scene's blades would be " +
                                    std::to_string(frame_bytes()) + " bytes, over the " +
                                    std::to_string(kMaxFrameBytes) +
                                    "-byte datagram limit (fewer points)");
  }
  recording_info_.rate_Hz = rate_Hz_;
  recording_info_.as_fast_as_possible = as_fast_as_possible_;
  recording_info_.scene = scene_label_;
  recording_info_.tet_count = static_cast<std::uint32_t>(space_->mesh().tet_count());
  for (const Binding& b : bindings_) {
    recording_info_.blades.push_back({b.blade_name, b.device_text,
                                      static_cast<std::uint32_t>(b.snapshot.point_count()), 0,
                                      coupling_name(b.blade->coupling())});
  }
  lay_out_record(recording_info_);
}

Binding* Session::find(const std::string& blade_name) {
  for (Binding& b : bindings_) {
    if (b.blade_name == blade_name) return &b;
  }
  return nullptr;
}

const Binding* Session::stiffness_exceeded(double stiffness_N_per_mm) const {
  for (const Binding& b : bindings_) {
    if (stiffness_in_force(stiffness_N_per_mm, b.max_stiffness_N_per_mm) != stiffness_N_per_mm) {
      return &b;
    }
  }
  return nullptr;
}

std::size_t Session::frame_bytes() const {
  std::size_t bytes = sizeof(FrameHeader);
  for (const Binding& b : bindings_)
    bytes += sizeof(BladeBlock) + points_block_bytes(b.snapshot.point_count());
  return bytes + sizeof(CutBlock);
}

}  // namespace hapticut::servo
