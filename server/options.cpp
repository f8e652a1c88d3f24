#include "options.h"

#include <sched.h>

#include <cmath>
#include <cstdlib>

#include "client_admission.h"
#include "devices/device_factory.h"
#include "session.h"

namespace hapticut::servo {

namespace {

constexpr const char* kUsage =
    "usage: hapticut-servo [SCENE] [options]\n"
    "\n"
    "The Hapticut servo: runs the blades of a scene file against their devices at a\n"
    "fixed rate (1 kHz by default), with safety (clamp, ramp, watchdog, NaN guard,\n"
    "engage), streams the proxies over UDP and records every tick.\n"
    "\n"
    "  SCENE                   scene file (.hapticut.json or .hapticut.msgpack); without\n"
    "                          it, wait for a \"load\" message on the control channel\n"
    "  --device [NAME=]KIND[:ARGS]  bind blade NAME to a device (repeat per blade;\n"
    "                          NAME may be left out when the scene has one blade)\n"
    "  --rate HZ               loop rate, 1 to 10000 (default: the scene's, 1000)\n"
    "  --as-fast-as-possible   no sleeping: time advances by the period each tick\n"
    "                          (bake a sim stroke; never real-time priority)\n"
    "  --duration S            end the run after S seconds (servo time)\n"
    "  --exit-when-done        end the run when every device has finished its path\n"
    "  --wait                  load SCENE but start only on a \"start\" message\n"
    "  --record FILE           record every tick of every run to FILE\n"
    "  --record-buffer-s S     records held in memory for the writer (2 s)\n"
    "  --record-dir DIR        where \"record\" messages may create recordings, new\n"
    "                          files only (default $XDG_STATE_HOME/hapticut/recordings,\n"
    "                          else ~/.local/state/hapticut/recordings)\n"
    "  --max-scene-bytes N     the largest scene file a \"load\" reads (256 MiB)\n"
    "  --control PORT          open the control channel (TCP) on PORT (0: any free\n"
    "                          port); prints \"control: ADDRESS:PORT\"\n"
    "  --listen ADDRESS        address of the control channel (127.0.0.1); any other\n"
    "                          needs --token\n"
    "  --token-file FILE       clients must present the token FILE holds (its first\n"
    "                          line) in \"hello\"; or $HAPTICUT_SERVO_TOKEN; --token\n"
    "                          TOKEN works too but shows in the process list; at\n"
    "                          least 16 bytes\n"
    "  --stream-rate HZ        default frame rate of a subscription (120)\n"
    "  --engage                engaged from the start (else: an \"engage\" message or\n"
    "                          a button of --engage-buttons)\n"
    "  --engage-buttons MASK   device buttons that engage while held (0: none)\n"
    "  --max-force N           force clamp, N (lowers the scene's and the device's)\n"
    "  --max-torque NMM        torque clamp, N mm\n"
    "  --ramp S                force ramp at start, engage and after a fault (scene's)\n"
    "  --stop-ramp S           ramp down on stop, SIGINT and SIGTERM (0.1)\n"
    "  --watchdog-ms MS        no new device sample for MS: zero force (100)\n"
    "  --no-passivity          no passivity controller (on by default for every\n"
    "                          device with force output: docs/stability.md)\n"
    "  --passivity-delay-ms MS the device link's delay the controller allows for (0)\n"
    "  --list-devices          list the HID devices hidapi finds, marking those a\n"
    "                          shipped profile matches (\"no HID devices found\" when\n"
    "                          none), then whether Force Dimension's DHD library\n"
    "                          and OpenHaptics's HD library loaded (where, or why\n"
    "                          not) and the devices they see, and exit\n"
    "  --json                  with --list-devices: print the devices, the shipped\n"
    "                          profiles and the other kinds with their limits as JSON\n"
    "                          (Force Dimension's under \"forcedimension\",\n"
    "                          OpenHaptics's under \"openhaptics\");\n"
    "                          with --rate HZ each stiffness limit is also given at\n"
    "                          that loop rate (max_stiffness_N_per_mm_at_rate; rate_Hz:\n"
    "                          1000 without --rate)\n"
    "  --profiles DIR          device profiles for --list-devices (default: next to\n"
    "                          the binary in the package, or $HAPTICUT_PROFILE_DIR)\n"
    "  --no-realtime           do not ask for SCHED_FIFO\n"
    "  --priority P            SCHED_FIFO priority, 1 to 99 (80)\n"
    "  --cpu N                 pin the loop thread to CPU N and keep the servo's\n"
    "                          other threads off it, where permitted (default: not\n"
    "                          pinned); also for --bare-loop\n"
    "  --bare-loop             measure a bare clock_nanosleep loop at --rate for\n"
    "                          --duration (2 s) and print its wake latency as JSON\n"
    "  --print-layout          print the frame and record layouts as JSON and exit\n"
    "  --quiet                 only errors and the final statistics\n"
    "  --version, --help\n"
    "\n"
    "Device kinds:\n";

constexpr const char* kExitCodes =
    "\n"
    "Exit codes: 0 the run ended (stroke done, duration, stop, shutdown, SIGINT,\n"
    "SIGTERM: the force is ramped to zero and the recording closed first), 1 internal\n"
    "error, 2 bad command line, 3 scene file missing or invalid, 4 device binding or\n"
    "device failure, 5 control port unavailable or non-loopback without --token,\n"
    "6 recording file not writable, 7 after SIGINT or SIGTERM the force reached zero but a\n"
    "thread stayed stuck (the process exits without it).\n";

// The first line of a token file, without its line end.
std::string read_token_file(const std::string& path) {
  std::vector<std::uint8_t> bytes;
  try {
    bytes = read_regular_file(path, 64 * 1024);
  } catch (const FileRefused& e) {
    throw UsageError(std::string("--token-file: ") + e.what());
  }
  std::string token(bytes.begin(), bytes.end());
  token = token.substr(0, token.find_first_of("\r\n"));
  if (token.empty())
    throw UsageError("--token-file: '" + path + "' holds no token on its first line");
  return token;
}

double number(const std::string& option, const char* text) {
  char* end = nullptr;
  const double value = std::strtod(text, &end);
  if (end == text || *end != '\0' || !std::isfinite(value)) {
    throw UsageError(option + ": '" + text + "' is not a number");
  }
  return value;
}

}  // namespace

std::string usage_text() { return std::string(kUsage) + device_usage() + kExitCodes; }

Options parse_options(int argc, const char* const* argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> const char* {
      if (i + 1 >= argc) throw UsageError(arg + ": needs a value");
      return argv[++i];
    };
    auto positive = [&](double v) {
      if (!(v > 0.0)) throw UsageError(arg + ": must be positive");
      return v;
    };
    if (arg == "--help" || arg == "-h") {
      o.help = true;
    } else if (arg == "--version") {
      o.version = true;
    } else if (arg == "--device") {
      o.devices.emplace_back(value());
    } else if (arg == "--rate") {
      o.rate_Hz = number(arg, value());
      if (!(o.rate_Hz >= 1.0 && o.rate_Hz <= kMaxRate_Hz)) {
        throw UsageError("--rate: 1 to " + std::to_string(static_cast<int>(kMaxRate_Hz)) + " Hz");
      }
    } else if (arg == "--as-fast-as-possible") {
      o.as_fast_as_possible = true;
    } else if (arg == "--duration") {
      o.duration_s = positive(number(arg, value()));
    } else if (arg == "--exit-when-done") {
      o.exit_when_done = true;
    } else if (arg == "--wait") {
      o.wait_for_start = true;
    } else if (arg == "--record") {
      o.record_path = value();
    } else if (arg == "--record-buffer-s") {
      o.record_buffer_s = positive(number(arg, value()));
    } else if (arg == "--control") {
      const double port = number(arg, value());
      if (port < 0 || port > 65535 || port != std::floor(port)) {
        throw UsageError("--control: a port 0 to 65535");
      }
      o.control_port = static_cast<int>(port);
    } else if (arg == "--listen") {
      o.listen_address = value();
    } else if (arg == "--token") {
      o.token = value();
    } else if (arg == "--token-file") {
      o.token = read_token_file(value());
    } else if (arg == "--record-dir") {
      o.record_dir = value();
      if (o.record_dir.empty()) throw UsageError("--record-dir: needs a directory");
    } else if (arg == "--max-scene-bytes") {
      const double bytes = number(arg, value());
      if (!(bytes >= 1.0 && bytes <= 1e12) || bytes != std::floor(bytes)) {
        throw UsageError("--max-scene-bytes: a whole number of bytes, 1 to 1e12");
      }
      o.max_scene_bytes = static_cast<std::uint64_t>(bytes);
    } else if (arg == "--stream-rate") {
      o.stream_rate_Hz = positive(number(arg, value()));
    } else if (arg == "--engage") {
      o.engage = true;
    } else if (arg == "--engage-buttons") {
      o.engage_buttons = static_cast<unsigned>(number(arg, value()));
    } else if (arg == "--max-force") {
      o.max_force_N = positive(number(arg, value()));
    } else if (arg == "--max-torque") {
      o.max_torque_N_mm = positive(number(arg, value()));
    } else if (arg == "--ramp") {
      o.ramp_s = number(arg, value());
      if (o.ramp_s < 0) throw UsageError("--ramp: must not be negative");
    } else if (arg == "--stop-ramp") {
      o.stop_ramp_s = number(arg, value());
      if (o.stop_ramp_s < 0) throw UsageError("--stop-ramp: must not be negative");
    } else if (arg == "--watchdog-ms") {
      o.watchdog_ms = positive(number(arg, value()));
    } else if (arg == "--no-passivity") {
      o.passivity = false;
    } else if (arg == "--passivity-delay-ms") {
      o.passivity_delay_ms = number(arg, value());
      if (o.passivity_delay_ms < 0 || o.passivity_delay_ms > 1000) {
        throw UsageError("--passivity-delay-ms: 0 to 1000");
      }
    } else if (arg == "--list-devices") {
      o.list_devices = true;
    } else if (arg == "--json") {
      o.json = true;
    } else if (arg == "--profiles") {
      o.profiles_dir = value();
    } else if (arg == "--no-realtime") {
      o.realtime = false;
    } else if (arg == "--priority") {
      const double p = number(arg, value());
      if (p < 1 || p > 99) throw UsageError("--priority: 1 to 99");
      o.priority = static_cast<int>(p);
    } else if (arg == "--cpu") {
      const double cpu = number(arg, value());
      // CPU_SETSIZE: the CPUs a cpu_set_t can name (rt/realtime.cpp pins with one).
      if (cpu < 0 || cpu >= CPU_SETSIZE || cpu != std::floor(cpu)) {
        throw UsageError("--cpu: a CPU number 0 to " + std::to_string(CPU_SETSIZE - 1));
      }
      o.cpu = static_cast<int>(cpu);
    } else if (arg == "--bare-loop") {
      o.bare_loop = true;
    } else if (arg == "--print-layout") {
      o.print_layout = true;
    } else if (arg == "--quiet") {
      o.quiet = true;
    } else if (!arg.empty() && arg[0] == '-') {
      throw UsageError("unknown option " + arg + " (see --help)");
    } else if (o.scene_path.empty()) {
      o.scene_path = arg;
    } else {
      throw UsageError("more than one scene given ('" + o.scene_path + "', '" + arg + "')");
    }
  }
  if (o.token.empty()) {
    const char* token = std::getenv("HAPTICUT_SERVO_TOKEN");
    if (token != nullptr) o.token = token;
  }
  // Wrong tokens are slowed, never locked out (client_admission.h), so the
  // token's length is what keeps a guesser out.
  if (!o.token.empty() && o.token.size() < kMinTokenBytes) {
    throw UsageError("the token (--token-file, $HAPTICUT_SERVO_TOKEN or --token) has " +
                     std::to_string(o.token.size()) + " bytes; at least " +
                     std::to_string(kMinTokenBytes) +
                     " are needed (make one with: python3 -c \"import secrets; "
                     "print(secrets.token_urlsafe(32))\")");
  }
  if (o.record_dir.empty()) o.record_dir = default_recording_directory();
  if (o.json && !o.list_devices) throw UsageError("--json goes with --list-devices");
  if (o.list_devices && !o.json && o.rate_Hz > 0.0) {
    throw UsageError("--rate with --list-devices goes with --json (the limits at that rate)");
  }
  return o;
}

}  // namespace hapticut::servo
