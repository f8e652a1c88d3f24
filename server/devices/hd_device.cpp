#include "devices/hd_device.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "rt/clock.h"

namespace hapticut::servo {
namespace {

// How long stop() waits for the callback to set a zero force before
// stopping the scheduler regardless (hdDisableDevice stops the force then).
constexpr double kStopZeroWait_s = 0.05;

bool finite(const Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

std::string device_label(const std::string& name) {
  return name.empty() ? std::string("the default device") : "device '" + name + "'";
}

// What an error of hdInitDevice asks the operator to do.
std::string init_hint(hd::HDerror code) {
  switch (code) {
    case hd::kDeviceAlreadyInitiated:
      return "; another program (or another servo) holds the device: close it";
    case hd::kInvalidLicense:
      return "; OpenHaptics's licence is missing or expired: install the runtime again";
    default:
      return "; check the cable and power, that the Touch is /dev/ttyACM* and your user is in "
             "its group (dialout), and that Touch_Setup names the device (docs/devices.md)";
  }
}

}  // namespace

HdDevice::HdDevice(std::shared_ptr<HdLibrary> library, HdDeviceOptions options)
    : library_(std::move(library)), options_(std::move(options)), mapping_(options_.mapping) {}

HdDevice::~HdDevice() { stop(); }

void HdDevice::set_error(std::string error) {
  const std::lock_guard<std::mutex> lock(error_mutex_);
  last_error_ = std::move(error);
}

std::string HdDevice::last_error() const {
  const std::lock_guard<std::mutex> lock(error_mutex_);
  return last_error_;
}

void HdDevice::initialise(bool reopening) {
  const HdLibrary& hd = *library_;
  const std::string what = "openhaptics: " + device_label(options_.name) + ": ";
  const hd::HHD handle =
      hd.init_device(options_.name.empty() ? hd::kDefaultDevice : options_.name.c_str());
  const hd::HDErrorInfo init_error = hd.get_error();
  if (handle == hd::kInvalidHandle || init_error.errorCode != hd::kSuccess) {
    throw std::runtime_error(what + hd.describe("hdInitDevice", init_error) +
                             init_hint(init_error.errorCode));
  }
  handle_ = handle;
  open_ = true;
  hd.make_current_device(handle_);
  // A Touch reset by its inkwell or by homing calibrates itself; one that
  // needs the stylus placed somewhere first cannot be used until it is.
  hd::HDenum calibration = hd.check_calibration();
  if (calibration == hd::kCalibrationNeedsUpdate) {
    hd.update_calibration(hd::kCalibrationAuto);
    calibration = hd.check_calibration();
  }
  const hd::HDErrorInfo calibration_error = hd.get_error();
  if (calibration_error.errorCode != hd::kSuccess) {
    release();
    throw std::runtime_error(what + hd.describe("hdCheckCalibration", calibration_error));
  }
  if (calibration != hd::kCalibrationOk) {
    release();
    throw std::runtime_error(
        what + "not calibrated (hdCheckCalibration: " +
        (calibration == hd::kCalibrationNeedsManualInput ? "needs manual input"
                                                         : "needs an update") +
        "): put the stylus in its inkwell (Touch) or run Touch_Diagnostic's calibration, then "
        "start again");
  }
  double max_force_N = 0.0;
  double continuous_N = 0.0;
  double stiffness = 0.0;
  double workspace[6] = {0, 0, 0, 0, 0, 0};
  hd.get_doublev(hd::kNominalMaxForce, &max_force_N);
  hd.get_doublev(hd::kNominalMaxContinuousForce, &continuous_N);
  hd.get_doublev(hd::kNominalMaxStiffness, &stiffness);
  hd.get_doublev(hd::kUsableWorkspaceDimensions, workspace);
  const hd::HDErrorInfo limits_error = hd.get_error();
  if (limits_error.errorCode != hd::kSuccess) {
    release();
    throw std::runtime_error(what + hd.describe("hdGetDoublev", limits_error));
  }
  // The continuous force is what the motors hold without overheating; the
  // peak (nominal max) only for moments, so it only bounds a bad reading.
  DeviceLimits device;
  device.has_force_output = true;
  device.max_force_N = continuous_N > 0.0
                           ? std::min(continuous_N, max_force_N > 0.0 ? max_force_N : continuous_N)
                           : max_force_N;
  device.max_stiffness_N_per_mm = stiffness;  // OpenHaptics states it in N/mm.
  device.workspace_min_mm = {workspace[0], workspace[1], workspace[2]};
  device.workspace_max_mm = {workspace[3], workspace[4], workspace[5]};
  if (!(device.max_force_N > 0.0)) {
    release();
    throw std::runtime_error(what + "the device states no force limit (HD_NOMINAL_MAX_FORCE " +
                             std::to_string(max_force_N) + " N): not a force device");
  }
  // A binding's own limit may only lower the device's.
  const double device_force_N = device.max_force_N;
  const double device_stiffness = device.max_stiffness_N_per_mm;
  device = with_arm_limit_options(device, options_);
  device.max_force_N = std::min(device.max_force_N, device_force_N);
  if (device_stiffness > 0.0) {
    device.max_stiffness_N_per_mm = std::min(device.max_stiffness_N_per_mm, device_stiffness);
  }
  const DeviceLimits scene = mapping_.scene_limits(device);
  if (reopening && (scene.max_force_N > limits_.max_force_N + 1e-12 ||
                    scene.max_stiffness_N_per_mm < limits_.max_stiffness_N_per_mm - 1e-12)) {
    release();
    throw std::runtime_error(what + "its limits changed while it was lost: restart the servo");
  }
  if (!reopening) limits_ = scene;
}

void HdDevice::open() {
  initialise(false);
  connection_.store(kConnected, std::memory_order_release);
}

void HdDevice::start_scheduler() {
  const HdLibrary& hd = *library_;
  stopping_.store(false, std::memory_order_release);
  callback_done_.store(false, std::memory_order_release);
  hd.make_current_device(handle_);
  // Limits were read in initialise(); only now may the device push.
  hd.enable(hd::kForceOutput);
  callback_ = hd.schedule_asynchronous(&HdDevice::frame_callback, this, hd::kMaxSchedulerPriority);
  hd.start_scheduler();
  const hd::HDErrorInfo error = hd.get_error();
  running_ = true;
  if (error.errorCode != hd::kSuccess) {
    const std::string text = hd.describe("hdStartScheduler", error);
    release();
    throw std::runtime_error("openhaptics: " + device_label(options_.name) + ": " + text);
  }
}

void HdDevice::start() {
  if (!open_ || running_) return;
  start_scheduler();
}

void HdDevice::release() {
  if (!open_) return;
  const HdLibrary& hd = *library_;
  if (running_) {
    if (!callback_done_.load(std::memory_order_acquire)) hd.unschedule(callback_);
    hd.stop_scheduler();
    running_ = false;
  }
  hd.disable_device(handle_);
  handle_ = hd::kInvalidHandle;
  open_ = false;
}

void HdDevice::stop() {
  if (!open_) return;
  if (running_ && !callback_done_.load(std::memory_order_acquire)) {
    // The callback sets a zero force in its next frame; the scheduler stops after it.
    const std::uint64_t before = zeroed_while_stopping_.load(std::memory_order_acquire);
    stopping_.store(true, std::memory_order_release);
    const double deadline = monotonic_now_s() + kStopZeroWait_s;
    while (zeroed_while_stopping_.load(std::memory_order_acquire) == before &&
           !callback_done_.load(std::memory_order_acquire) && monotonic_now_s() < deadline) {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  }
  release();
  connection_.store(kLost, std::memory_order_release);
}

hd::HDCallbackCode HdDevice::frame_callback(void* self) {
  return static_cast<HdDevice*>(self)->frame();
}

void HdDevice::fault(const char* call, const hd::HDErrorInfo& error) {
  fault_call_ = call;
  fault_error_ = error;
  counters_.faults.fetch_add(1, std::memory_order_relaxed);
  connection_.store(kLost, std::memory_order_release);
}

hd::HDCallbackCode HdDevice::frame() {
  const HdLibrary& hd = *library_;
  counters_.frames.fetch_add(1, std::memory_order_relaxed);
  const bool lost = !connected();
  hd.begin_frame(handle_);
  FrameSample sample{};
  hd::HDint buttons = 0;
  hd.get_doublev(hd::kCurrentTransform, sample.transform);
  hd.get_integerv(hd::kCurrentButtons, &buttons);
  const hd::HDErrorInfo read_error = hd.get_error();
  const double now = monotonic_now_s();
  const bool stopping = stopping_.load(std::memory_order_acquire);
  Vec3 force;
  if (!lost && read_error.errorCode == hd::kSuccess) {
    sample.buttons = static_cast<std::uint32_t>(buttons);
    sample.time_s = now;
    samples_.publish(sample);
    ForceCommand command{};
    if (!stopping && forces_.read(command) > 0) {
      if (now - command.time_s <= options_.watchdog_s) {
        force = command.device_force_N;
        if (command.sample_time_s != last_applied_sample_time_s_ && command.sample_time_s > 0.0) {
          last_applied_sample_time_s_ = command.sample_time_s;
          sample_to_force_.add((now - command.sample_time_s) * 1e6);
        }
      } else {
        counters_.stale_force_frames.fetch_add(1, std::memory_order_relaxed);
      }
    }
  }
  const double values[3] = {force.x, force.y, force.z};
  hd.set_doublev(hd::kCurrentForce, values);
  hd.end_frame(handle_);
  if (stopping) zeroed_while_stopping_.fetch_add(1, std::memory_order_acq_rel);
  if (lost || read_error.errorCode != hd::kSuccess) {
    // This frame set zero: the callback ends, maintain() takes over.
    if (!lost) fault("hdGetDoublev(HD_CURRENT_TRANSFORM)", read_error);
    callback_done_.store(true, std::memory_order_release);
    return hd::kCallbackDone;
  }
  const hd::HDErrorInfo write_error = hd.get_error();
  if (write_error.errorCode != hd::kSuccess) {
    // The force of this frame may not have reached the device: the next
    // frame, seeing the device lost, sets zero and ends the callback.
    fault("hdEndFrame", write_error);
  }
  return hd::kCallbackContinue;
}

DeviceStatus HdDevice::read(double /*now_s*/, DeviceSample& sample) {
  if (!connected()) {
    sample = last_sample_;
    return DeviceStatus::Lost;
  }
  FrameSample frame{};
  const std::uint64_t published = samples_.read(frame);
  if (published == 0 || published == samples_seen_) {
    sample = last_sample_;
    return DeviceStatus::Stale;
  }
  samples_seen_ = published;
  const double* t = frame.transform;
  Matrix3 rotation{};  // Column-major: element (row i, column j) is t[4 j + i].
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) rotation[i][j] = t[4 * j + i];
  }
  last_sample_.pose.position_mm =
      mapping_.position_mm({t[12] / 1000.0, t[13] / 1000.0, t[14] / 1000.0});
  last_sample_.pose.rotation = mapping_.rotation(rotation);
  last_sample_.buttons = frame.buttons & 0xffffU;  // Bits 16 and up are the servo's (device.h).
  last_sample_.time_s = frame.time_s;
  ++last_sample_.sequence;
  last_sample_frame_time_s_ = frame.time_s;
  counters_.samples.fetch_add(1, std::memory_order_relaxed);
  sample = last_sample_;
  return DeviceStatus::Fresh;
}

void HdDevice::write(const Vec3& force_N, const Vec3& /*torque_N_mm*/) {
  if (!connected()) return;
  // The safety layer clamps and checks; a non-finite force never reaches the arm regardless.
  const Vec3 device = finite(force_N) ? mapping_.device_force_N(force_N) : Vec3{};
  forces_.publish({device, monotonic_now_s(), last_sample_frame_time_s_});
  counters_.forces_written.fetch_add(1, std::memory_order_relaxed);
}

void HdDevice::maintain() {
  if (connected()) return;
  if (!reopen_pending_) {
    // Only once the callback has ended (after the frame that set zero) does
    // this thread call the library; a device stop() ended is not reopened.
    if (!open_ || !callback_done_.load(std::memory_order_acquire)) return;
    fault_text_ = "openhaptics: " + library_->describe(fault_call_, fault_error_);
    release();
    reopen_pending_ = true;
  }
  counters_.reconnect_attempts.fetch_add(1, std::memory_order_relaxed);
  try {
    initialise(true);
    start_scheduler();
  } catch (const std::exception& e) {
    set_error(fault_text_ + "; reopening: " + e.what());
    return;
  }
  reopen_pending_ = false;
  set_error("");
  counters_.reconnects.fetch_add(1, std::memory_order_relaxed);
  connection_.store(kConnected, std::memory_order_release);
}

std::vector<std::pair<std::string, std::uint64_t>> HdDevice::status_counters() const {
  const auto load = [](const std::atomic<std::uint64_t>& count) {
    return count.load(std::memory_order_relaxed);
  };
  return {{"frames", load(counters_.frames)},
          {"samples", load(counters_.samples)},
          {"forces_written", load(counters_.forces_written)},
          {"stale_force_frames", load(counters_.stale_force_frames)},
          {"faults", load(counters_.faults)},
          {"reconnects", load(counters_.reconnects)},
          {"reconnect_attempts", load(counters_.reconnect_attempts)},
          {"sample_to_force_ns_p50", sample_to_force_.percentile_ns(0.5)},
          {"sample_to_force_ns_p99", sample_to_force_.percentile_ns(0.99)}};
}

HdListing list_hd_devices() {
  HdListing listing;
  std::string error;
  const std::shared_ptr<HdLibrary> library = load_hd_library(error);
  if (!library) {
    listing.library = error;
    return listing;
  }
  listing.library_found = true;
  listing.library = library->path;
  HdDeviceRow row;
  row.binding = "openhaptics";
  try {
    HdDevice device(library, HdDeviceOptions{});
    device.open();
    row.limits = device.limits();
  } catch (const std::exception& e) {
    row.error = e.what();
  }
  listing.devices.push_back(std::move(row));
  return listing;
}

std::string format_hd_listing(const HdListing& listing) {
  std::ostringstream out;
  if (!listing.library_found) {
    out << "3D Systems (OpenHaptics): library not loaded: " << listing.library << "\n";
    return out.str();
  }
  out << "3D Systems (OpenHaptics): library " << listing.library << "\n";
  for (const HdDeviceRow& row : listing.devices) {
    if (!row.error.empty()) {
      out << "  " << row.binding << "  " << row.error << "\n";
      continue;
    }
    char line[256];
    std::snprintf(line, sizeof line, "  %-18s max continuous force %g N, max stiffness %g N/mm\n",
                  row.binding.c_str(), row.limits.max_force_N, row.limits.max_stiffness_N_per_mm);
    out << line;
  }
  return out.str();
}

HdDeviceOptions hd_device_options(const std::string& bare_name, const DeviceOptions& options) {
  std::vector<std::string> keys = arm_device_option_keys();
  keys.insert(keys.begin(), "device");
  check_device_options(options, "openhaptics", keys);
  HdDeviceOptions out;
  out.name = bare_name;
  const auto given = options.find("device");
  if (given != options.end()) {
    if (!bare_name.empty()) {
      throw std::invalid_argument("openhaptics: the device is named twice ('" + bare_name +
                                  "' and device=" + given->second + ")");
    }
    out.name = given->second;
  }
  parse_arm_device_options(options, "openhaptics", out);
  return out;
}

std::unique_ptr<Device> make_hd_device(const std::string& bare_name, const DeviceOptions& options,
                                       double watchdog_s) {
  HdDeviceOptions device_options = hd_device_options(bare_name, options);
  if (watchdog_s > 0.0) device_options.watchdog_s = watchdog_s;
  std::string error;
  std::shared_ptr<HdLibrary> library = load_hd_library(error);
  if (!library) throw std::runtime_error(error);
  auto device = std::make_unique<HdDevice>(std::move(library), std::move(device_options));
  device->open();
  return device;
}

}  // namespace hapticut::servo
