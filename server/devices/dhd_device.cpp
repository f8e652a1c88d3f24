#include "devices/dhd_device.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "rt/clock.h"

namespace hapticut::servo {
namespace {

// What an error of dhdOpenID or dhdGetDeviceCount asks the operator to do.
std::string open_hint(int code) {
  switch (code) {
    case dhd::kErrorDeviceInUse:
      return "; another program holds the device: close it (or the other servo)";
    case dhd::kErrorNoDriverFound:
    case dhd::kErrorNoDeviceFound:
      return "; check the USB cable and power, and the udev rule of docs/devices.md";
    default:
      return "; docs/devices.md, \"Force Dimension devices\", lists what each error means";
  }
}

bool finite(const Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// "" when the device is initialised, else why not and what to do. A device
// in RESET mode (after power-up, until its calibration position is reached
// by hand) reports positions in no known frame: the servo refuses it.
std::string initialisation_problem(const DhdLibrary& dhd, char id) {
  int status[dhd::kStatusArraySize] = {};
  if (dhd.get_status(status, id) < 0) return dhd.last_error("dhdGetStatus");
  if (status[dhd::kStatusReset] == 0) return "";
  return "not initialised (dhdGetStatus: RESET mode, its LED blinking): put the handle in its "
         "calibration position (omega, delta, sigma, lambda: the calibration pole in its pit; "
         "Falcon: the grip pulled fully out, then pushed in) until the LED stops blinking, or "
         "initialise it with the SDK's own tools, then start again (docs/devices.md)";
}

// What a missing firmware watchdog leaves: nothing zeroes the force while the loop stalls.
constexpr const char* kStalledLoopKeepsTheForce =
    "if the servo's loop stalls, the arm keeps its last force until the loop runs again (its "
    "first tick after a stall longer than --watchdog-ms writes zero, then ramps back in)";

std::string watchdog_unavailable(const DhdLibrary& dhd) {
  return "no firmware watchdog: " + dhd.path +
         " lacks dhdSetWatchdog (a Force Dimension SDK before 3.3.2; a current one has it): " +
         kStalledLoopKeepsTheForce;
}

std::string watchdog_refused(const std::string& error) {
  return "no firmware watchdog: " + error +
         " (the SDK sets it on compatible devices only); going on without it: " +
         kStalledLoopKeepsTheForce;
}

// For the listing, without changing the device: whether it answers dhdGetWatchdog.
std::string probe_firmware_watchdog(const DhdLibrary& dhd, char id) {
  if (dhd.set_watchdog == nullptr) return watchdog_unavailable(dhd);
  unsigned char units = 0;
  if (dhd.get_watchdog != nullptr && dhd.get_watchdog(&units, id) < 0) {
    return watchdog_refused(dhd.last_error("dhdGetWatchdog"));
  }
  return "";
}

}  // namespace

unsigned char dhd_watchdog_units(double watchdog_s) {
  // Whole units: the firmware's watchdog is never longer than the servo's.
  const double units = std::floor(watchdog_s / dhd::kWatchdogUnit_s + 1e-9);
  return static_cast<unsigned char>(
      std::clamp(units, 1.0, static_cast<double>(dhd::kWatchdogMaxUnits)));
}

DhdDevice::DhdDevice(std::shared_ptr<DhdLibrary> library, DhdDeviceOptions options)
    : library_(std::move(library)), options_(options), mapping_(options.mapping) {}

DhdDevice::~DhdDevice() { stop(); }

void DhdDevice::set_error(std::string error) {
  const std::lock_guard<std::mutex> lock(error_mutex_);
  last_error_ = std::move(error);
}

std::string DhdDevice::last_error() const {
  const std::lock_guard<std::mutex> lock(error_mutex_);
  return last_error_;
}

std::string DhdDevice::firmware_watchdog_warning() const {
  const std::lock_guard<std::mutex> lock(error_mutex_);
  return watchdog_warning_;
}

std::string DhdDevice::set_firmware_watchdog() {
  const DhdLibrary& dhd = *library_;
  firmware_watchdog_s_ = 0.0;
  counters_.firmware_watchdog_us.store(0, std::memory_order_relaxed);
  std::string warning;
  if (dhd.set_watchdog == nullptr) {
    warning = watchdog_unavailable(dhd);
  } else {
    const unsigned char units = dhd_watchdog_units(options_.watchdog_s);
    if (dhd.set_watchdog(units, id_) < 0) {
      warning = watchdog_refused(dhd.last_error("dhdSetWatchdog"));
    } else {
      firmware_watchdog_s_ = units * dhd::kWatchdogUnit_s;
      counters_.firmware_watchdog_us.store(static_cast<std::uint64_t>(units) * 125U,
                                           std::memory_order_relaxed);
    }
  }
  bool changed = false;
  {
    const std::lock_guard<std::mutex> lock(error_mutex_);
    changed = warning != watchdog_warning_;
    watchdog_warning_ = warning;
  }
  // Said once, and again only when it changes (a reopened device).
  if (changed && !warning.empty()) {
    std::fprintf(stderr, "hapticut-servo: warning: forcedimension:%d: %s\n", options_.index,
                 warning.c_str());
    std::fflush(stderr);
  }
  return warning;
}

void DhdDevice::open() {
  const DhdLibrary& dhd = *library_;
  const int count = dhd.get_device_count();
  if (count < 0) {
    const int code = dhd.error_get_last();
    throw std::runtime_error("forcedimension: " + dhd.last_error("dhdGetDeviceCount") +
                             open_hint(code));
  }
  if (count == 0) {
    throw std::runtime_error(
        "forcedimension: no Force Dimension device found (dhdGetDeviceCount() = 0, library " +
        dhd.path +
        "): check the USB cable and power, and the udev rule of docs/devices.md; "
        "`hapticut-servo --list-devices` shows what the library sees");
  }
  if (options_.index >= count) {
    throw std::runtime_error("forcedimension: no device " + std::to_string(options_.index) +
                             ": the library sees " + std::to_string(count) + " (IDs 0 to " +
                             std::to_string(count - 1) + ")");
  }
  const int id = dhd.open_id(static_cast<char>(options_.index));
  if (id < 0) {
    const int code = dhd.error_get_last();
    throw std::runtime_error("forcedimension: device " + std::to_string(options_.index) + ": " +
                             dhd.last_error("dhdOpenID") + open_hint(code));
  }
  id_ = static_cast<char>(id);
  open_ = true;
  const int type = dhd.get_system_type(id_);
  if (type < 0) {
    const std::string error = dhd.last_error("dhdGetSystemType");
    stop();
    throw std::runtime_error("forcedimension: device " + std::to_string(options_.index) + ": " +
                             error);
  }
  const std::string problem = initialisation_problem(dhd, id_);
  if (!problem.empty()) {
    stop();
    throw std::runtime_error("forcedimension: device " + std::to_string(options_.index) + ": " +
                             problem);
  }
  model_ = dhd_model(type);
  if (model_.system_type == 0) model_.system_type = type;
  DeviceLimits device = with_arm_limit_options(dhd_model_limits(model_), options_);
  // A limit set in the device itself (its own tools, or another program) is kept: never above it.
  const double device_limit_N = dhd.get_max_force(id_);
  if (device_limit_N > 0.0 && device_limit_N < device.max_force_N) {
    device.max_force_N = device_limit_N;
  }
  limits_ = mapping_.scene_limits(device);
  connection_.store(kConnected, std::memory_order_release);
}

void DhdDevice::start() {
  if (!open_ || force_enabled_) return;
  const DhdLibrary& dhd = *library_;
  // The firmware's watchdog before anything can push.
  set_firmware_watchdog();
  // Zero first: the device renders nothing until the servo's ramp writes.
  const bool zeroed = dhd.set_force(0.0, 0.0, 0.0, id_) >= 0;
  last_force_command_s_ = monotonic_now_s();
  if (!zeroed || dhd.enable_force(dhd::kOn, id_) < 0) {
    const std::string error = dhd.last_error(zeroed ? "dhdEnableForce" : "dhdSetForce");
    stop();
    throw std::runtime_error("forcedimension: device " + std::to_string(options_.index) + ": " +
                             error);
  }
  force_enabled_ = true;
}

void DhdDevice::stop() {
  if (!open_) return;
  const DhdLibrary& dhd = *library_;
  dhd.set_force(0.0, 0.0, 0.0, id_);
  dhd.stop(id_);
  dhd.close(id_);
  open_ = false;
  force_enabled_ = false;
  connection_.store(kLost, std::memory_order_release);
}

DeviceStatus DhdDevice::fault(const char* call) {
  const DhdLibrary& dhd = *library_;
  // The tick that sees the failure zeroes the force itself: the servo writes
  // nothing to a lost device.
  dhd.set_force(0.0, 0.0, 0.0, id_);
  fault_call_ = call;
  fault_code_ = dhd.error_get_last();
  const char* text = dhd.error_get_last_str();
  std::snprintf(fault_text_, sizeof fault_text_, "%s", text != nullptr ? text : "");
  counters_.faults.fetch_add(1, std::memory_order_relaxed);
  connection_.store(kLost, std::memory_order_release);
  return DeviceStatus::Lost;
}

DeviceStatus DhdDevice::read(double now_s, DeviceSample& sample) {
  if (!connected()) {
    sample = last_sample_;
    return DeviceStatus::Lost;
  }
  const DhdLibrary& dhd = *library_;
  Vec3 position_m;
  if (dhd.get_position(&position_m.x, &position_m.y, &position_m.z, id_) < 0) {
    sample = last_sample_;
    return fault("dhdGetPosition");
  }
  const double position_read_s = monotonic_now_s();
  Matrix3 rotation{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  if (model_.has_wrist) {
    double frame[3][3];
    if (dhd.get_orientation_frame(frame, id_) < 0) {
      sample = last_sample_;
      return fault("dhdGetOrientationFrame");
    }
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) rotation[i][j] = frame[i][j];
    }
  }
  const unsigned int buttons = dhd.get_button_mask(id_);
  sample_read_s_ = position_read_s;
  sample_unwritten_ = true;
  last_sample_.pose.position_mm = mapping_.position_mm(position_m);
  last_sample_.pose.rotation = mapping_.rotation(rotation);
  last_sample_.buttons = buttons & 0xffffU;  // Bits 16 and up are the servo's (device.h).
  last_sample_.time_s = now_s;
  ++last_sample_.sequence;
  counters_.samples.fetch_add(1, std::memory_order_relaxed);
  sample = last_sample_;
  return DeviceStatus::Fresh;
}

void DhdDevice::write(const Vec3& force_N, const Vec3& /*torque_N_mm*/) {
  if (!connected()) return;
  // The safety layer clamps and checks; a non-finite force never reaches the arm regardless.
  const Vec3 device = finite(force_N) ? mapping_.device_force_N(force_N) : Vec3{};
  const DhdLibrary& dhd = *library_;
  const double now_s = monotonic_now_s();
  if (sample_unwritten_) {
    sample_to_force_.add((now_s - sample_read_s_) * 1e6);
    sample_unwritten_ = false;
  }
  // A gap the firmware's watchdog outlasted may have left forces disabled: enabled
  // again, at zero (never the force commanded before the gap), before this tick's.
  if (firmware_watchdog_s_ > 0.0 && now_s - last_force_command_s_ > firmware_watchdog_s_) {
    if (dhd.set_force(0.0, 0.0, 0.0, id_) < 0) {
      fault("dhdSetForce");
      return;
    }
    if (dhd.enable_force(dhd::kOn, id_) < 0) {
      fault("dhdEnableForce");
      return;
    }
    counters_.forces_reenabled.fetch_add(1, std::memory_order_relaxed);
  }
  last_force_command_s_ = now_s;
  const int result = dhd.set_force(device.x, device.y, device.z, id_);
  if (result < 0) {
    fault("dhdSetForce");
    return;
  }
  counters_.forces_written.fetch_add(1, std::memory_order_relaxed);
  if (result == dhd::kMotorSaturated) {
    counters_.motor_saturated.fetch_add(1, std::memory_order_relaxed);
  }
}

void DhdDevice::maintain() {
  if (connected() || !open_) return;
  counters_.reconnect_attempts.fetch_add(1, std::memory_order_relaxed);
  const DhdLibrary& dhd = *library_;
  const std::string error =
      std::string("forcedimension: ") + fault_call_ +
      " failed: " + (fault_text_[0] != '\0' ? fault_text_ : "no description") + " (DHD error " +
      std::to_string(fault_code_) + ")";
  // The device is reopened by its index: its SDK ID may change with a replug.
  dhd.close(id_);
  const int count = dhd.get_device_count();
  const int id = count > options_.index ? dhd.open_id(static_cast<char>(options_.index)) : -1;
  if (id < 0) {
    set_error(error + "; reopening: " +
              (count > options_.index
                   ? dhd.last_error("dhdOpenID")
                   : "no device " + std::to_string(options_.index) +
                         " (dhdGetDeviceCount() = " + std::to_string(count) + ")"));
    return;
  }
  id_ = static_cast<char>(id);
  const int type = dhd.get_system_type(id_);
  if (type != model_.system_type) {
    set_error(error + "; reopening: device " + std::to_string(options_.index) + " is now of type " +
              std::to_string(type) + ", not " + model_.name + ": restart the servo");
    return;
  }
  // Powered off and on again, it waits in RESET mode until initialised by hand.
  const std::string problem = initialisation_problem(dhd, id_);
  if (!problem.empty()) {
    set_error(error + "; reopening: " + problem);
    return;
  }
  // Limits first (as at the start), then the force, at zero.
  const double device_limit_N = dhd.get_max_force(id_);
  if (device_limit_N > 0.0 && device_limit_N < limits_.max_force_N) {
    set_error(error +
              "; reopening: the device's own force limit is now below the servo's: restart "
              "the servo");
    return;
  }
  set_firmware_watchdog();
  if (dhd.set_force(0.0, 0.0, 0.0, id_) < 0) {
    set_error(error + "; reopening: " + dhd.last_error("dhdSetForce"));
    return;
  }
  last_force_command_s_ = monotonic_now_s();
  if (dhd.enable_force(dhd::kOn, id_) < 0) {
    set_error(error + "; reopening: " + dhd.last_error("dhdEnableForce"));
    return;
  }
  set_error("");
  counters_.reconnects.fetch_add(1, std::memory_order_relaxed);
  connection_.store(kConnected, std::memory_order_release);
}

std::vector<std::pair<std::string, std::uint64_t>> DhdDevice::status_counters() const {
  const auto load = [](const std::atomic<std::uint64_t>& count) {
    return count.load(std::memory_order_relaxed);
  };
  return {{"samples", load(counters_.samples)},
          {"forces_written", load(counters_.forces_written)},
          {"motor_saturated", load(counters_.motor_saturated)},
          {"faults", load(counters_.faults)},
          {"reconnects", load(counters_.reconnects)},
          {"reconnect_attempts", load(counters_.reconnect_attempts)},
          {"firmware_watchdog_us", load(counters_.firmware_watchdog_us)},
          {"forces_reenabled", load(counters_.forces_reenabled)},
          {"sample_to_force_ns_p50", sample_to_force_.percentile_ns(0.5)},
          {"sample_to_force_ns_p99", sample_to_force_.percentile_ns(0.99)}};
}

DhdListing list_dhd_devices() {
  DhdListing listing;
  std::string error;
  const std::shared_ptr<DhdLibrary> library = load_dhd_library(error);
  if (!library) {
    listing.library = error;
    return listing;
  }
  listing.library_found = true;
  listing.library = library->path;
  const int count = library->get_device_count();
  if (count < 0) {
    listing.error = library->last_error("dhdGetDeviceCount");
    return listing;
  }
  for (int index = 0; index < count; ++index) {
    DhdDeviceOptions options;
    options.index = index;
    DhdDevice device(library, options);
    DhdDeviceRow row;
    row.index = index;
    row.binding = "forcedimension:" + std::to_string(index);
    try {
      device.open();
      row.system_type = device.model().system_type;
      row.model = device.model().name;
      row.limits = device.limits();
      row.firmware_watchdog_warning = probe_firmware_watchdog(*library, device.sdk_id());
      row.firmware_watchdog = row.firmware_watchdog_warning.empty();
    } catch (const std::exception& e) {
      row.error = e.what();
    }
    listing.devices.push_back(std::move(row));
  }
  return listing;
}

std::string format_dhd_listing(const DhdListing& listing) {
  std::ostringstream out;
  if (!listing.library_found) {
    out << "Force Dimension (DHD): library not loaded: " << listing.library << "\n";
    return out.str();
  }
  out << "Force Dimension (DHD): library " << listing.library << "\n";
  if (!listing.error.empty()) out << "  " << listing.error << "\n";
  if (listing.error.empty() && listing.devices.empty())
    out << "  no Force Dimension devices found\n";
  for (const DhdDeviceRow& row : listing.devices) {
    if (!row.error.empty()) {
      out << "  " << row.binding << "  " << row.error << "\n";
      continue;
    }
    char line[256];
    std::snprintf(line, sizeof line,
                  "  %-18s %-24s type %d, max force %g N, max stiffness %g N/mm\n",
                  row.binding.c_str(), row.model.c_str(), row.system_type, row.limits.max_force_N,
                  row.limits.max_stiffness_N_per_mm);
    out << line;
    out << "    firmware watchdog: "
        << (row.firmware_watchdog
                ? std::string("yes (dhdSetWatchdog; the servo sets it to --watchdog-ms, at most "
                              "31.875 ms)")
                : row.firmware_watchdog_warning)
        << "\n";
  }
  return out.str();
}

DhdDeviceOptions dhd_device_options(const std::string& bare_id, const DeviceOptions& options) {
  std::vector<std::string> keys = arm_device_option_keys();
  keys.insert(keys.begin(), "id");
  check_device_options(options, "forcedimension", keys);
  DhdDeviceOptions out;
  std::string id = bare_id;
  const auto given = options.find("id");
  if (given != options.end()) {
    if (!bare_id.empty()) {
      throw std::invalid_argument("forcedimension: the ID is given twice ('" + bare_id +
                                  "' and id=" + given->second + ")");
    }
    id = given->second;
  }
  if (!id.empty()) {
    char* end = nullptr;
    const long value = std::strtol(id.c_str(), &end, 10);
    if (end == id.c_str() || *end != '\0' || value < 0 || value > 15) {
      throw std::invalid_argument("forcedimension: ID '" + id +
                                  "' must be a device index from 0 to 15");
    }
    out.index = static_cast<int>(value);
  }
  parse_arm_device_options(options, "forcedimension", out);
  return out;
}

std::unique_ptr<DhdDevice> make_dhd_device(const std::string& bare_id, const DeviceOptions& options,
                                           double watchdog_s) {
  DhdDeviceOptions device_options = dhd_device_options(bare_id, options);
  if (watchdog_s > 0.0) device_options.watchdog_s = watchdog_s;
  std::string error;
  std::shared_ptr<DhdLibrary> library = load_dhd_library(error);
  if (!library) throw std::runtime_error(error);
  auto device = std::make_unique<DhdDevice>(std::move(library), device_options);
  device->open();
  return device;
}

}  // namespace hapticut::servo
