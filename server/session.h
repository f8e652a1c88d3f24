// Session: a loaded scene ready to run: the engine's Space, one Blade per
// scene blade, each bound to its device (by blade name) with its own safety
// channel. Everything the tick touches is allocated here, before the run.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "blade_tick_snapshot.h"
#include "client_files.h"
#include "cut_feed.h"
#include "devices/device.h"
#include "devices/device_factory.h"
#include "hapticut/blade.h"
#include "hapticut/cut_state.h"
#include "hapticut/scene.h"
#include "hapticut/space.h"
#include "recording/recording_file.h"
#include "safety.h"
#include "stream_frame.h"

namespace hapticut::servo {

class ViewportDevice;

struct SessionConfig {
  std::string scene_path;              // Either a path ...
  std::string scene_json;              // ... or the scene itself (JSON text),
  std::shared_ptr<const Scene> scene;  // ... or one already read (built in code).
  std::uint64_t max_scene_bytes = kDefaultMaxSceneBytes;  // A larger file is refused.
  std::vector<std::string> devices;                       // --device texts.
  double rate_Hz = 0.0;                                   // 0: the scene's servo_rate_Hz.
  bool as_fast_as_possible = false;
  double watchdog_ms = 100.0;
  SafetySettings safety_request;      // Lowered to each device's limits.
  bool lower_to_scene_limits = true;  // The scene may lower the limits too.
  // A Hannaford-Ryu passivity controller on every device with force output.
  bool passivity = true;
  double passivity_link_delay_s = 0.0;  // The device link's delay beyond one tick.
  // `devices` are the operator's and the servo has a token (DeviceContext).
  bool remote_bridge_allowed = false;
};

struct Binding {
  std::string blade_name;
  std::string device_text;
  std::unique_ptr<Device> device;
  ViewportDevice* viewport = nullptr;  // The device, when it is a viewport.
  std::unique_ptr<Blade> blade;
  std::unique_ptr<SafetyChannel> safety;
  SafetySettings requested;  // Before the device's limits.
  // The device's stiffness limit at the session's rate (stiffness_limit, devices/device.h;
  // 0: none known), on what the blade renders at its tool: springs x k.
  double device_max_stiffness_N_per_mm = 0.0;
  int springs = 1;  // rendered_springs: the blade's point count when rigid, else 1.
  // The limit on k for this blade (point_stiffness_limit: the device's over
  // springs; 0: none): the blade steps with the settings' stiffness lowered to it.
  double max_stiffness_N_per_mm = 0.0;
  BladeTickSnapshot snapshot;
  // The blade stepped since `snapshot` was last filled: the snapshot is taken
  // only when a record or a stream frame needs it, after the device write.
  bool snapshot_stale = false;
  BladeTickResult result;
  bool has_reset = false;
  bool engage_bit = false;  // kEngageRequestBit of the last admitted sample.
  bool passivity = false;   // A passivity controller is plugged in.
};

class Session {
 public:
  // Throws SceneError for the scene, DeviceError for the bindings.
  // `between_stages` is called after reading, parsing, building the Space and
  // the force shading, and after each blade's device: a load on a worker
  // thread stops there when asked (it throws).
  explicit Session(
      const SessionConfig& config, const std::function<void()>& between_stages = [] {});

  const Scene& scene() const { return scene_; }
  const std::string& scene_label() const { return scene_label_; }
  double rate_Hz() const { return rate_Hz_; }
  // The scene's settings per tick (what a run starts with).
  const RuntimeSettings& runtime_settings() const { return space_->runtime_settings(); }
  bool as_fast_as_possible() const { return as_fast_as_possible_; }
  std::vector<Binding>& bindings() { return bindings_; }
  const std::vector<Binding>& bindings() const { return bindings_; }
  Binding* find(const std::string& blade_name);
  // The first binding whose stiffness limit `stiffness_N_per_mm` exceeds
  // (nullptr: none does).
  const Binding* stiffness_exceeded(double stiffness_N_per_mm) const;
  // Bytes of a stream frame and of a recording record.
  std::size_t frame_bytes() const;
  const RecordingInfo& recording_info() const { return recording_info_; }
  // The tets the blades have cut since the load (cut_state.h); every blade
  // reads and marks this one, on the servo thread.
  const CutState& cuts() const { return *cuts_; }
  // Changed only on the loop's thread while a run is on, by the control
  // thread while none is (reset_cuts, load_cuts).
  CutState& cut_state() { return *cuts_; }
  // The cut order for the other threads (cut_feed.h): the writer follows
  // cut_state() after every change.
  CutFeed& cut_feed() { return *cut_feed_; }
  const CutFeed& cut_feed() const { return *cut_feed_; }

 private:
  Scene scene_;
  std::string scene_label_;
  std::shared_ptr<const Space> space_;
  // Built at load, shared by every blade: the settings per tick switch it on.
  std::shared_ptr<const ForceShading> shading_;
  // The loaded scene's cut memory, shared by every blade (docs/decisions.md, "Cut memory").
  std::shared_ptr<CutState> cuts_;
  std::unique_ptr<CutFeed> cut_feed_;
  double rate_Hz_ = 1000.0;
  bool as_fast_as_possible_ = false;
  std::vector<Binding> bindings_;
  RecordingInfo recording_info_;
};

inline constexpr double kMaxRate_Hz = 10000.0;

// As the protocol and the recording's header name a blade's coupling.
inline const char* coupling_name(BladeCoupling coupling) {
  return coupling == BladeCoupling::Rigid ? "rigid" : "independent";
}

}  // namespace hapticut::servo
