// Servo: the process's state: the loaded session, the loop thread, the
// recorder, the housekeeping thread (device maintenance at 2 Hz, fault
// messages), and the commands of the control channel. Control methods are
// serialised by a mutex the loop never touches.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "control_message.h"
#include "options.h"
#include "recording/recorder.h"
#include "servo_loop.h"
#include "session.h"
#include "session_load.h"

namespace hapticut::servo {

class Servo {
 public:
  explicit Servo(const Options& options);
  ~Servo();
  Servo(const Servo&) = delete;
  Servo& operator=(const Servo&) = delete;

  // Throws SceneError (scene) or DeviceError (bindings); the old session stays
  // when the new one fails. Reads and builds on the calling thread (the
  // command line's scene); a client's `load` goes through the three steps below.
  void load(const SessionConfig& config);
  SessionConfig config_from_options() const;

  // A client's load, built off the control thread (session_load.h):
  // begin_load refuses while running or while another load is on its way
  // (CommandError) and from then on `start` is refused; then either install
  // (the prepared session replaces the old one, as load does) or end_load
  // (it failed, or nobody waits for it: the old session stays).
  void begin_load();
  void install(PreparedLoad prepared);
  void end_load();
  // The reply to a `load` that succeeded: the blades, rate and sizes.
  nlohmann::json loaded_reply();
  // Throws CommandError (nothing loaded, already running), DeviceError
  // (a device cannot start) or std::runtime_error (recording file).
  void start();
  // Ramps the forces to zero, ends the run, closes the recording. Returns the
  // run's statistics (null when nothing ran).
  nlohmann::json stop();

  // The servo's control commands, each given its message (already parsed)
  // and returning the reply without "id"; the control server's table
  // (ControlServer::dispatch) names which message type calls which. Each
  // throws CommandError with the reason when it cannot be done.
  nlohmann::json start_command();
  nlohmann::json stop_command();
  nlohmann::json engage_command(const ControlJson& message);
  nlohmann::json set_parameters(const ControlJson& message);
  nlohmann::json record_command(const ControlJson& message);
  nlohmann::json pose_command(const ControlJson& message);
  // The scene's cut tets (docs/protocol.md, "Cut tets").
  nlohmann::json cuts_command(const ControlJson& message);
  nlohmann::json reset_cuts_command();
  nlohmann::json save_cuts_command(const ControlJson& message);
  nlohmann::json load_cuts_command(const ControlJson& message);

  LoopShared& shared() { return *shared_; }
  nlohmann::json status();
  bool shutdown_requested() const { return shutdown_.load(); }
  void request_shutdown() { shutdown_.store(true); }
  // The run ended by itself (stroke done, duration) and was wound up.
  bool run_ended() const { return run_ended_.load(); }

 private:
  nlohmann::json finish_run_locked();
  nlohmann::json stats_locked() const;
  void housekeeping();
  void report_events_locked();

  Options options_;
  std::mutex mutex_;
  std::unique_ptr<LoopShared> shared_;
  std::unique_ptr<Session> session_;
  std::unique_ptr<Recorder> recorder_;
  std::thread loop_thread_;
  std::thread housekeeping_thread_;
  std::atomic<bool> shutdown_{false};
  std::atomic<bool> quit_housekeeping_{false};
  std::atomic<bool> run_ended_{false};
  bool loading_ = false;  // Between begin_load and install or end_load (under mutex_).
  std::string realtime_message_;
  std::array<std::array<std::uint64_t, kSafetyFlagCount>, kMaxBlades> reported_{};
  int runs_ = 0;
};

}  // namespace hapticut::servo
