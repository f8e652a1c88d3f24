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

namespace hapticut::servo {

class Servo {
 public:
  explicit Servo(const Options& options);
  ~Servo();
  Servo(const Servo&) = delete;
  Servo& operator=(const Servo&) = delete;

  // Throws SceneError (scene) or DeviceError (bindings); the old session stays
  // when the new one fails.
  void load(const SessionConfig& config);
  SessionConfig config_from_options() const;
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
  nlohmann::json load_command(const ControlJson& message);
  nlohmann::json start_command();
  nlohmann::json stop_command();
  nlohmann::json engage_command(const ControlJson& message);
  nlohmann::json set_parameters(const ControlJson& message);
  nlohmann::json record_command(const ControlJson& message);
  nlohmann::json pose_command(const ControlJson& message);

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
  std::string realtime_message_;
  std::array<std::array<std::uint64_t, kSafetyFlagCount>, kMaxBlades> reported_{};
  int runs_ = 0;
};

}  // namespace hapticut::servo
