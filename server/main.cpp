// hapticut-servo: the real-time process (docs/servo.md). Parses the command
// line, loads the scene, opens the control channel, runs, and on SIGINT or
// SIGTERM ramps the forces to zero, closes the recording and prints the
// statistics.
#include <pthread.h>
#include <signal.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <nlohmann/json.hpp>
#include <thread>

#include "control_server.h"
#include "rt/clock.h"
#ifdef HAPTICUT_WITH_DEVICES
#include "devices/bridge_device.h"
#include "devices/device_limits_json.h"
#include "devices/dhd_device.h"
#include "devices/hd_device.h"
#include "devices/hid_device.h"
#endif
#include "devices/sim_device.h"
#include "devices/viewport_device.h"
#include "hapticut/scene_io.h"
#include "layout.h"
#include "options.h"
#include "rt/histogram.h"
#include "rt/realtime.h"
#include "servo.h"

namespace hapticut::servo {
namespace {

// A bare absolute-time clock_nanosleep loop with the servo's real-time
// settings: the anchor the servo's wake latency is compared with.
int run_bare_loop(const Options& options) {
  const double rate = options.rate_Hz > 0.0 ? options.rate_Hz : 1000.0;
  const double duration = options.duration_s > 0.0 ? options.duration_s : 2.0;
  auto histogram = std::make_unique<LatencyHistogram>();
  std::uint64_t late = 0;
  std::uint64_t ticks = 0;
  std::string realtime;
  std::thread thread([&] {
    realtime = options.realtime ? enter_realtime_priority(options.priority)
                                : std::string("real-time: not asked for (--no-realtime)");
    if (options.cpu >= 0) realtime += "; " + pin_to_cpu(options.cpu);
    const double period = 1.0 / rate;
    const double start = monotonic_now_s();
    double deadline = start + period;
    while (deadline - start < duration) {
      sleep_until(deadline);
      const double now = monotonic_now_s();
      histogram->add((now - deadline) * 1e6);
      ++ticks;
      deadline += period;
      if (now > deadline) {
        ++late;
        deadline += std::ceil((now - deadline) / period) * period;
      }
    }
  });
  thread.join();
  const nlohmann::json out = {{"rate_Hz", rate},
                              {"ticks", ticks},
                              {"late_ticks", late},
                              {"realtime", realtime},
                              {"wake_latency_us",
                               {{"p50", histogram->percentile_us(0.5)},
                                {"p99", histogram->percentile_us(0.99)},
                                {"max", histogram->max_us()},
                                {"count", histogram->count()}}}};
  std::printf("%s\n", out.dump().c_str());
  return kExitOk;
}

#ifdef HAPTICUT_WITH_DEVICES
// The kinds besides hid that --list-devices --json offers, with their default limits.
std::vector<DeviceKindInfo> other_device_kinds() {
  const BridgeDeviceOptions bridge;
  return {{"sim", "sim", sim_device_limits(SimOptions{})},
          {"viewport", "viewport", viewport_device_limits()},
          {"bridge", "bridge:port=" + std::to_string(bridge.port), bridge.limits}};
}
#endif

// A vendor library's object in the listing: whether it loaded (its path, or
// why not), its enumeration error if any, and the devices it sees.
nlohmann::json vendor_listing(bool found, const std::string& library, const std::string& error,
                              nlohmann::json devices) {
  return {{"library_found", found},
          {"library", found ? nlohmann::json(library) : nlohmann::json(nullptr)},
          {"error", found ? (error.empty() ? nlohmann::json(nullptr) : nlohmann::json(error))
                          : nlohmann::json(library)},
          {"devices", std::move(devices)}};
}

// A device row's limits, or its error.
nlohmann::json device_row(nlohmann::json row, const std::string& error, const DeviceLimits& limits,
                          double rate_Hz) {
  if (error.empty()) {
    row["limits"] = device_limits_json(limits, rate_Hz);
    row["error"] = nullptr;
  } else {
    row["error"] = error;
  }
  return row;
}

// The listing's "forcedimension" and "openhaptics" objects: each vendor
// library, and the devices it sees with their bindings and limits.
std::string with_vendor_listings(const std::string& listing_json, const DhdListing& dhd,
                                 const HdListing& hd, double rate_Hz) {
  nlohmann::json listing = nlohmann::json::parse(listing_json);
  nlohmann::json arms = nlohmann::json::array();
  for (const DhdDeviceRow& row : dhd.devices) {
    nlohmann::json device = {{"id", row.index}, {"binding", row.binding}};
    if (row.error.empty()) {
      device["system_type"] = row.system_type;
      device["model"] = row.model;
      // false: a stalled loop leaves the arm its last force (the warning says so).
      device["firmware_watchdog"] = row.firmware_watchdog;
      if (!row.firmware_watchdog)
        device["firmware_watchdog_warning"] = row.firmware_watchdog_warning;
    }
    arms.push_back(device_row(device, row.error, row.limits, rate_Hz));
  }
  listing["forcedimension"] = vendor_listing(dhd.library_found, dhd.library, dhd.error, arms);
  nlohmann::json touches = nlohmann::json::array();
  for (const HdDeviceRow& row : hd.devices) {
    nlohmann::json device = {{"name", row.name}, {"binding", row.binding}};
    touches.push_back(device_row(device, row.error, row.limits, rate_Hz));
  }
  listing["openhaptics"] = vendor_listing(hd.library_found, hd.library, "", touches);
  return listing.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

// --list-devices: the HID devices hidapi finds, and the profile each matches
// (--json: with the shipped profiles and the other kinds, and their limits,
// the stiffness limit at --rate among them).
int list_devices(const Options& options) {
#ifdef HAPTICUT_WITH_DEVICES
  try {
    // The stiffness limits at --rate, else at a scene's default rate.
    const double rate_Hz = options.rate_Hz > 0.0 ? options.rate_Hz : Scene{}.servo_rate_Hz;
    const DhdListing dhd = list_dhd_devices();
    const HdListing hd = list_hd_devices();
    const std::string text =
        options.json ? with_vendor_listings(
                           list_devices_json(options.profiles_dir, other_device_kinds(), rate_Hz),
                           dhd, hd, rate_Hz)
                     : list_hid_devices_text(options.profiles_dir) + "\n" +
                           format_dhd_listing(dhd) + format_hd_listing(hd);
    std::printf("%s", text.c_str());
    return kExitOk;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hapticut-servo: --list-devices: %s\n", e.what());
    return kExitDevice;
  }
#else
  (void)options;
  std::fprintf(stderr, "hapticut-servo: built without HID devices (HAPTICUT_BUILD_DEVICES=OFF)\n");
  return kExitDevice;
#endif
}

// The process's exit code once everything is wound up. A load left inside a
// stage at shutdown (ControlServer::stop) still runs on its own thread, which
// static destructors would pull the ground from under: exit without them.
int exit_code(ControlServer* control, int code) {
  if (control == nullptr || !control->load_left_running()) return code;
  std::fflush(stdout);
  std::fflush(stderr);
  std::_Exit(code);
}

// After a signal, the loop gets its --stop-ramp and this much more to end (a
// few ticks late at most); the rest of the process then this much to wind up.
constexpr double kSignalLoopGrace_s = 0.2;
constexpr double kSignalExitGrace_s = 0.8;

// After SIGINT or SIGTERM: the loop ramps the force to zero on its own; the
// rest (recording, devices, threads) is wound up on a thread of its own, and
// if that is stuck (a thread blocked in the kernel) the process exits without
// it once the loop has ended, so a signal always ends the servo.
int wind_down_after_signal(Servo& servo, ControlServer* control, double stop_ramp_s) {
  auto done = std::make_shared<std::atomic<bool>>(false);
  std::thread wind_down([&servo, control, done] {
    servo.stop();
    if (control != nullptr) control->stop();
    done->store(true);
  });
  const double loop_deadline_s = monotonic_now_s() + stop_ramp_s + kSignalLoopGrace_s;
  while (servo.shared().running.load() && monotonic_now_s() < loop_deadline_s) {
    sleep_until(monotonic_now_s() + 0.001);
  }
  const double exit_deadline_s = monotonic_now_s() + kSignalExitGrace_s;
  while (!done->load() && monotonic_now_s() < exit_deadline_s)
    sleep_until(monotonic_now_s() + 0.001);
  if (done->load()) {
    wind_down.join();
    return exit_code(control, kExitOk);
  }
  std::fprintf(stderr,
               "hapticut-servo: a thread did not finish within %g s of the signal (%s); exiting "
               "without it\n",
               kSignalExitGrace_s,
               servo.shared().running.load() ? "the loop is still running" : "the force is zero");
  std::fflush(stderr);
  std::fflush(stdout);
  std::_Exit(servo.shared().running.load() ? kExitInternal : kExitStuck);
}

int run(const Options& options) {
  // SIGINT and SIGTERM are taken by sigtimedwait below, in no other thread.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  signal(SIGPIPE, SIG_IGN);
  // Before any thread starts: every thread but the loop inherits this affinity.
  if (options.cpu >= 0) {
    const std::string line = keep_threads_off_cpu(options.cpu);
    if (!options.quiet) std::printf("hapticut-servo: %s\n", line.c_str());
  }

  Servo servo_state(options);
  if (!options.scene_path.empty()) {
    try {
      servo_state.load(servo_state.config_from_options());
    } catch (const SceneError& e) {
      std::fprintf(stderr, "hapticut-servo: scene '%s': %s\n", options.scene_path.c_str(),
                   e.what());
      return kExitScene;
    } catch (const MeshError& e) {
      std::fprintf(stderr, "hapticut-servo: scene '%s': %s\n", options.scene_path.c_str(),
                   e.what());
      return kExitScene;
    } catch (const DeviceError& e) {
      std::fprintf(stderr, "hapticut-servo: %s\n", e.what());
      return kExitDevice;
    }
  } else if (options.control_port < 0) {
    std::fprintf(stderr,
                 "hapticut-servo: nothing to do: give a SCENE, or --control PORT to wait for "
                 "a \"load\" message (see --help)\n");
    return kExitUsage;
  }

  std::unique_ptr<ControlServer> control;
  if (options.control_port >= 0) {
    try {
      control = std::make_unique<ControlServer>(servo_state, options);
    } catch (const NetworkError& e) {
      std::fprintf(stderr, "hapticut-servo: %s\n", e.what());
      return kExitNetwork;
    }
  }

  // The run starts before the control channel answers (its port is bound, not
  // yet served): a client's first "status" sees it running.
  if (!options.scene_path.empty() && !options.wait_for_start) {
    try {
      servo_state.start();
    } catch (const DeviceError& e) {
      std::fprintf(stderr, "hapticut-servo: %s\n", e.what());
      return kExitDevice;
    } catch (const std::runtime_error& e) {
      std::fprintf(stderr, "hapticut-servo: %s\n", e.what());
      return kExitRecording;
    }
  }
  if (control) {
    std::printf("control: %s:%d\n", options.listen_address.c_str(), control->port());
    std::fflush(stdout);
    control->start();
  }

  // Wait: a signal, a shutdown message, or (without a control channel) the
  // run ending by itself.
  const timespec poll_interval = to_timespec(0.05);
  bool signalled = false;
  for (;;) {
    const int signal_number = sigtimedwait(&signals, nullptr, &poll_interval);
    if (signal_number == SIGINT || signal_number == SIGTERM) {
      // Straight to the loop's flag, which it reads every tick: the ramp to
      // zero must not wait for a lock another thread (a stuck file open, a
      // flooding client) may hold.
      servo_state.shared().stop_requested.store(true);
      signalled = true;
      if (!options.quiet) {
        std::fprintf(stderr, "hapticut-servo: %s: ramping the force to zero and stopping\n",
                     signal_number == SIGINT ? "SIGINT" : "SIGTERM");
      }
      break;
    }
    if (servo_state.shutdown_requested()) break;
    if (!control && servo_state.run_ended()) break;
  }
  if (signalled) return wind_down_after_signal(servo_state, control.get(), options.stop_ramp_s);
  servo_state.stop();
  if (control) control->stop();
  return exit_code(control.get(), kExitOk);
}

int run_main(int argc, char** argv) {
  Options options;
  try {
    options = parse_options(argc, argv);
  } catch (const UsageError& e) {
    std::fprintf(stderr, "hapticut-servo: %s\n", e.what());
    return kExitUsage;
  }
  if (options.help) {
    std::printf("%s", usage_text().c_str());
    return kExitOk;
  }
  if (options.version) {
    std::printf("hapticut-servo " HAPTICUT_VERSION " (protocol %d, frame %d, record %d)\n",
                kProtocolVersion, kFrameVersion, kRecordVersion);
    return kExitOk;
  }
  if (options.list_devices) return list_devices(options);
  if (options.print_layout) {
    std::printf("%s\n", layout_json().c_str());
    return kExitOk;
  }
  try {
    if (options.bare_loop) return run_bare_loop(options);
    return run(options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hapticut-servo: internal error: %s\n", e.what());
    return kExitInternal;
  }
}

}  // namespace
}  // namespace hapticut::servo

int main(int argc, char** argv) { return hapticut::servo::run_main(argc, argv); }
