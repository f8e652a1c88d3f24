// The command line of hapticut-servo (--help prints kUsage and the device table).
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "client_files.h"

namespace hapticut::servo {

// Exit codes (docs/servo.md).
enum ExitCode : int {
  kExitOk = 0,         // The run ended (stroke done, duration, stop, shutdown, SIGINT, SIGTERM).
  kExitInternal = 1,   // An unexpected error (a bug): the message says what.
  kExitUsage = 2,      // A bad command line.
  kExitScene = 3,      // The scene file is missing or invalid.
  kExitDevice = 4,     // A --device binding is wrong or its device cannot start.
  kExitNetwork = 5,    // The control port cannot be opened, or non-loopback without a token.
  kExitRecording = 6,  // The --record file cannot be written.
  kExitStuck = 7,      // After SIGINT or SIGTERM the force reached zero but a thread stayed stuck.
};

class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Options {
  std::string scene_path;
  std::vector<std::string> devices;
  double rate_Hz = 0.0;   // 0: the scene's.
  int control_port = -1;  // -1: no control channel; 0: any free port.
  std::string listen_address = "127.0.0.1";
  std::string token;
  std::string record_path;
  std::string record_dir;  // Where "record" messages write; "": default_recording_directory().
  std::uint64_t max_scene_bytes = kDefaultMaxSceneBytes;
  double record_buffer_s = 2.0;
  double duration_s = 0.0;
  bool exit_when_done = false;
  bool as_fast_as_possible = false;
  bool wait_for_start = false;
  bool engage = false;
  bool realtime = true;
  int priority = 80;
  int cpu = -1;  // --cpu: the CPU the loop thread has to itself; -1: not pinned.
  double watchdog_ms = 100.0;
  double max_force_N = 1e300;
  double max_torque_N_mm = 1e300;
  double ramp_s = -1.0;  // < 0: the scene's.
  double stop_ramp_s = 0.1;
  unsigned engage_buttons = 0;
  double stream_rate_Hz = 120.0;
  bool print_layout = false;
  bool bare_loop = false;
  bool help = false;
  bool version = false;
  bool quiet = false;
  bool passivity = true;
  double passivity_delay_ms = 0.0;
  bool list_devices = false;
  bool json = false;         // --list-devices --json: the machine-readable listing.
  std::string profiles_dir;  // "": find_profile_directory()'s search.
};

// Throws UsageError naming the option that is wrong.
Options parse_options(int argc, const char* const* argv);
std::string usage_text();

}  // namespace hapticut::servo
