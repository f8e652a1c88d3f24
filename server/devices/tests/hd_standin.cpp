// The OpenHaptics stand-in (hd_standin.h). Test code: a lock guards its
// state, which the scheduler thread and the servo's threads share; the
// callbacks run outside it, as they call back into the library.
#include "hd_standin.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "standin_script.h"

namespace {

using HHD = unsigned int;
using HDenum = unsigned int;
using HDCallbackCode = unsigned int;
using HDSchedulerHandle = unsigned long;
using Callback = HDCallbackCode (*)(void*);
struct HDErrorInfo {
  unsigned int errorCode;
  int internalErrorCode;
  HHD hHD;
};

// hd_api.h's values (hdDefines.h).
constexpr unsigned int kCommError = 0x0302;
constexpr unsigned int kIllegalBegin = 0x0400;
constexpr unsigned int kIllegalEnd = 0x0401;
constexpr unsigned int kInvalidOperation = 0x0102;
constexpr HDenum kCurrentButtons = 0x2000;
constexpr HDenum kCurrentTransform = 0x2052;
constexpr HDenum kUsableWorkspace = 0x2551;
constexpr HDenum kNominalMaxStiffness = 0x2602;
constexpr HDenum kNominalMaxForce = 0x2603;
constexpr HDenum kNominalMaxContinuousForce = 0x2604;
constexpr HDenum kCurrentForce = 0x2700;
constexpr HDenum kCalibrationOk = 0x5000;
constexpr HDenum kCalibrationNeedsUpdate = 0x5001;
constexpr HDenum kCalibrationNeedsManualInput = 0x5002;
constexpr HHD kInvalidHandle = 0xFFFFFFFFU;
constexpr std::size_t kMaxCalls = 1 << 18;  // About forty seconds of frames.

struct Script {
  int devices = 1;
  unsigned int init_error = 0;
  std::string calibration = "ok";
  double max_force = 3.3;
  double continuous = 0.88;
  double stiffness = 1.0;
  double ws_min[3] = {-80, -60, -35};
  double ws_max[3] = {80, 60, 35};
  double from[3] = {0, 0, 0};
  double to[3] = {0, 0, 0};
  long frames = 1;
  int buttons = 0;
  double rate = 1000.0;
  long fail_frame_at = 0;
  long fail_count = 1;
  long fail_end_at = 0;
  long stall_at = 0;
  double stall_ms = 0.0;
};

struct Scheduled {
  HDSchedulerHandle handle;
  Callback callback;
  void* data;
};

struct State {
  std::mutex mutex;
  bool configured = false;
  Script script;
  std::vector<HdStandinCall> calls;
  bool initialised = false;
  bool calibrated = false;
  bool in_frame = false;
  long frame = 0;  // Frames begun since configure.
  std::vector<Scheduled> scheduled;
  HDSchedulerHandle next_handle = 1;
  std::thread scheduler;
  std::atomic<bool> running{false};

  ~State() {
    // A test that unloads the library with the scheduler running stops it here.
    running.store(false);
    if (scheduler.joinable()) scheduler.join();
  }
};

State& state() {
  static State s;
  return s;
}

thread_local std::vector<HDErrorInfo> errors;  // Each thread's own error stack.

void push_error(unsigned int code, int internal = 0) { errors.push_back({code, internal, 1}); }

void apply(Script& script, const std::string& text) {
  using hapticut_standin::parse_xyz;
  hapticut_standin::for_each_pair(
      text, [&](const std::string& key, const std::string& value, double number) {
        if (key == "devices") script.devices = static_cast<int>(number);
        if (key == "init_error") script.init_error = std::stoul(value, nullptr, 0);
        if (key == "calibration") script.calibration = value;
        if (key == "max_force") script.max_force = number;
        if (key == "continuous") script.continuous = number;
        if (key == "stiffness") script.stiffness = number;
        if (key == "ws_min") parse_xyz(value, script.ws_min);
        if (key == "ws_max") parse_xyz(value, script.ws_max);
        if (key == "from") parse_xyz(value, script.from);
        if (key == "to") parse_xyz(value, script.to);
        if (key == "frames") script.frames = std::max(1L, static_cast<long>(number));
        if (key == "buttons") script.buttons = static_cast<int>(number);
        if (key == "rate" && number > 0.0) script.rate = number;
        if (key == "fail_frame_at") script.fail_frame_at = static_cast<long>(number);
        if (key == "fail_count") script.fail_count = static_cast<long>(number);
        if (key == "fail_end_at") script.fail_end_at = static_cast<long>(number);
        if (key == "stall_at") script.stall_at = static_cast<long>(number);
        if (key == "stall_ms") script.stall_ms = number;
      });
}

// Locks the state, applying $HAPTICUT_HD_STANDIN at the first call.
std::unique_lock<std::mutex> lock_state() {
  State& s = state();
  std::unique_lock<std::mutex> lock(s.mutex);
  if (!s.configured) {
    s.configured = true;
    s.calls.reserve(kMaxCalls);
    const char* text = std::getenv("HAPTICUT_HD_STANDIN");
    if (text != nullptr) apply(s.script, text);
  }
  return lock;
}

int record(const char* name, double a, double b, double c, int result) {
  State& s = state();
  if (s.calls.size() < kMaxCalls) {
    HdStandinCall call{};
    std::snprintf(call.name, sizeof call.name, "%s", name);
    call.a = a;
    call.b = b;
    call.c = c;
    call.frame = s.frame;
    call.in_frame = s.in_frame ? 1 : 0;
    call.result = result;
    call.time_s = hapticut_standin::now_s();
    s.calls.push_back(call);
  }
  if (result != 0) push_error(static_cast<unsigned int>(result));
  return result;
}

void write_log() {
  const char* path = std::getenv("HAPTICUT_HD_STANDIN_LOG");
  if (path == nullptr) return;
  std::FILE* file = std::fopen(path, "w");
  if (file == nullptr) return;
  for (const HdStandinCall& call : state().calls) {
    std::fprintf(file, "%s %.17g %.17g %.17g %ld %d %d %.9f\n", call.name, call.a, call.b, call.c,
                 call.frame, call.in_frame, call.result, call.time_s);
  }
  std::fclose(file);
}

// The scheduler thread: each period, every scheduled callback once, outside the lock.
void run_scheduler() {
  State& s = state();
  auto next = std::chrono::steady_clock::now();
  while (s.running.load()) {
    std::vector<Scheduled> due;
    std::chrono::nanoseconds period{};
    double stall_ms = 0.0;
    {
      auto lock = lock_state();
      period = std::chrono::nanoseconds(static_cast<long long>(1e9 / s.script.rate));
      if (s.script.stall_at > 0 && s.frame + 1 == s.script.stall_at) stall_ms = s.script.stall_ms;
      due = s.scheduled;
    }
    next += period;
    std::this_thread::sleep_until(next);
    if (stall_ms > 0.0) {
      std::this_thread::sleep_for(std::chrono::microseconds(static_cast<long>(stall_ms * 1e3)));
      next = std::chrono::steady_clock::now();
    }
    for (const Scheduled& item : due) {
      if (item.callback(item.data) == 0) {  // HD_CALLBACK_DONE
        auto lock = lock_state();
        auto& all = s.scheduled;
        all.erase(std::remove_if(all.begin(), all.end(),
                                 [&](const Scheduled& x) { return x.handle == item.handle; }),
                  all.end());
      }
    }
  }
}

}  // namespace

#define STANDIN_EXPORT extern "C" __attribute__((visibility("default")))

STANDIN_EXPORT void hapticut_hd_standin_configure(const char* script) {
  auto lock = lock_state();
  State& s = state();
  s.script = Script{};
  apply(s.script, script != nullptr ? script : "");
  s.calls.clear();
  s.frame = 0;
  s.calibrated = false;
}

STANDIN_EXPORT int hapticut_hd_standin_calls(HdStandinCall* out, int capacity) {
  auto lock = lock_state();
  const std::vector<HdStandinCall>& calls = state().calls;
  const int count = static_cast<int>(calls.size());
  for (int i = 0; i < std::min(count, capacity); ++i) out[i] = calls[static_cast<std::size_t>(i)];
  return count;
}

STANDIN_EXPORT HHD hdInitDevice(const char* name) {
  auto lock = lock_state();
  State& s = state();
  const double named = name != nullptr ? 1.0 : 0.0;
  if (s.script.devices <= 0) {
    record("hdInitDevice", named, 0, 0, static_cast<int>(kCommError));
    return kInvalidHandle;
  }
  if (s.script.init_error != 0) {
    record("hdInitDevice", named, 0, 0, static_cast<int>(s.script.init_error));
    return kInvalidHandle;
  }
  s.initialised = true;
  s.calibrated = s.script.calibration == "ok";
  record("hdInitDevice", named, 0, 0, 0);
  return 1;
}

STANDIN_EXPORT void hdDisableDevice(HHD device) {
  auto lock = lock_state();
  state().initialised = false;
  record("hdDisableDevice", device, 0, 0, 0);
  write_log();
}

STANDIN_EXPORT void hdMakeCurrentDevice(HHD device) {
  auto lock = lock_state();
  record("hdMakeCurrentDevice", device, 0, 0, 0);
}

STANDIN_EXPORT HHD hdGetCurrentDevice() { return 1; }

STANDIN_EXPORT void hdEnable(HDenum capability) {
  auto lock = lock_state();
  record("hdEnable", capability, 0, 0,
         state().initialised ? 0 : static_cast<int>(kInvalidOperation));
}

STANDIN_EXPORT HDenum hdCheckCalibration() {
  auto lock = lock_state();
  State& s = state();
  HDenum answer = kCalibrationOk;
  if (!s.calibrated) {
    answer =
        s.script.calibration == "manual" ? kCalibrationNeedsManualInput : kCalibrationNeedsUpdate;
  }
  record("hdCheckCalibration", answer, 0, 0, 0);
  return answer;
}

STANDIN_EXPORT void hdUpdateCalibration(HDenum style) {
  auto lock = lock_state();
  State& s = state();
  if (s.script.calibration == "update") s.calibrated = true;
  record("hdUpdateCalibration", style, 0, 0, 0);
}

STANDIN_EXPORT void hdGetDoublev(HDenum parameter, double* values) {
  auto lock = lock_state();
  State& s = state();
  const Script& p = s.script;
  switch (parameter) {
    case kNominalMaxForce:
      values[0] = p.max_force;
      break;
    case kNominalMaxContinuousForce:
      values[0] = p.continuous;
      break;
    case kNominalMaxStiffness:
      values[0] = p.stiffness;
      break;
    case kUsableWorkspace:
      for (int i = 0; i < 3; ++i) {
        values[i] = p.ws_min[i];
        values[3 + i] = p.ws_max[i];
      }
      break;
    case kCurrentTransform: {
      if (p.fail_frame_at > 0 && s.frame >= p.fail_frame_at &&
          s.frame < p.fail_frame_at + p.fail_count) {
        record("hdGetDoublev(TRANSFORM)", 0, 0, 0, static_cast<int>(kCommError));
        return;
      }
      const double t = std::min(
          1.0, static_cast<double>(std::max(0L, s.frame - 1)) / static_cast<double>(p.frames));
      for (int i = 0; i < 16; ++i) values[i] = (i % 5 == 0) ? 1.0 : 0.0;  // Identity rotation.
      for (int i = 0; i < 3; ++i) values[12 + i] = p.from[i] + t * (p.to[i] - p.from[i]);
      record("hdGetDoublev(TRANSFORM)", values[12], values[13], values[14], 0);
      return;
    }
    default:
      record("hdGetDoublev", parameter, 0, 0, static_cast<int>(kInvalidOperation));
      return;
  }
  record("hdGetDoublev", parameter, values[0], 0, 0);
}

STANDIN_EXPORT void hdGetIntegerv(HDenum parameter, int* values) {
  auto lock = lock_state();
  if (parameter == kCurrentButtons) values[0] = state().script.buttons;
  record("hdGetIntegerv", parameter, values[0], 0, 0);
}

STANDIN_EXPORT void hdSetDoublev(HDenum parameter, const double* values) {
  auto lock = lock_state();
  State& s = state();
  // A force set outside a frame is an error in OpenHaptics too.
  const int result = parameter == kCurrentForce && s.in_frame ? 0 : static_cast<int>(kIllegalEnd);
  record(parameter == kCurrentForce ? "hdSetDoublev(FORCE)" : "hdSetDoublev", values[0], values[1],
         values[2], result);
}

STANDIN_EXPORT void hdBeginFrame(HHD device) {
  auto lock = lock_state();
  State& s = state();
  if (s.in_frame) {
    record("hdBeginFrame", device, 0, 0, static_cast<int>(kIllegalBegin));
    return;
  }
  s.in_frame = true;
  ++s.frame;
  record("hdBeginFrame", device, 0, 0, 0);
}

STANDIN_EXPORT void hdEndFrame(HHD device) {
  auto lock = lock_state();
  State& s = state();
  const bool fail = s.script.fail_end_at > 0 && s.frame == s.script.fail_end_at;
  const int result = !s.in_frame ? static_cast<int>(kIllegalEnd)
                     : fail      ? static_cast<int>(kCommError)
                                 : 0;
  record("hdEndFrame", device, 0, 0, result);
  s.in_frame = false;
}

STANDIN_EXPORT void hdStartScheduler() {
  auto lock = lock_state();
  State& s = state();
  record("hdStartScheduler", 0, 0, 0, 0);
  if (s.running.load()) return;
  s.running.store(true);
  s.scheduler = std::thread(run_scheduler);
}

STANDIN_EXPORT void hdStopScheduler() {
  std::thread scheduler;
  {
    auto lock = lock_state();
    State& s = state();
    record("hdStopScheduler", 0, 0, 0, 0);
    s.running.store(false);
    scheduler = std::move(s.scheduler);
  }
  // Returns after the last frame, as OpenHaptics's does.
  if (scheduler.joinable()) scheduler.join();
}

STANDIN_EXPORT HDSchedulerHandle hdScheduleAsynchronous(Callback callback, void* data,
                                                        unsigned short priority) {
  auto lock = lock_state();
  State& s = state();
  const HDSchedulerHandle handle = s.next_handle++;
  s.scheduled.push_back({handle, callback, data});
  record("hdScheduleAsynchronous", static_cast<double>(handle), priority, 0, 0);
  return handle;
}

STANDIN_EXPORT void hdUnschedule(HDSchedulerHandle handle) {
  auto lock = lock_state();
  auto& all = state().scheduled;
  const auto before = all.size();
  all.erase(std::remove_if(all.begin(), all.end(),
                           [&](const Scheduled& x) { return x.handle == handle; }),
            all.end());
  record("hdUnschedule", static_cast<double>(handle), 0, 0,
         all.size() < before ? 0 : static_cast<int>(kInvalidOperation));
}

STANDIN_EXPORT HDErrorInfo hdGetError() {
  if (errors.empty()) return {0, 0, 0};
  const HDErrorInfo last = errors.back();
  errors.pop_back();
  return last;
}

STANDIN_EXPORT const char* hdGetErrorString(unsigned int code) {
  switch (code) {
    case kCommError:
      return "Communication error (stand-in)";
    case 0x0301:
      return "Device already initiated (stand-in)";
    case kIllegalBegin:
      return "Illegal begin frame (stand-in)";
    case kIllegalEnd:
      return "Illegal end frame or force outside a frame (stand-in)";
    default:
      return "HD error (stand-in)";
  }
}
