// The DHD stand-in (dhd_standin.h). Test code: a lock guards its state, as
// the tick and the housekeeping thread both call it.
#include "dhd_standin.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <string>
#include <vector>

#include "standin_script.h"

namespace {

constexpr int kErrorCom = 2;                // DHD_ERROR_COM
constexpr std::size_t kMaxCalls = 1 << 18;  // About a minute of ticks.

struct Script {
  int devices = 1;
  int type = 33;
  bool reset = false;  // In RESET mode: not initialised.
  double max_force = -1.0;
  unsigned int buttons = 0;
  double from[3] = {0, 0, 0};
  double to[3] = {0, 0, 0};
  long reads = 1;
  double yaw_deg = 0.0;  // The wrist's rotation about the SDK's z.
  int open_error = 0;
  long fail_position_at = 0;
  long fail_count = 1;
  long fail_force_at = 0;
  int position_result = 0;  // What a dhdGetPosition that succeeds returns (1: DHD_TIMEGUARD).
  int force_result = 0;     // What a dhdSetForce that succeeds returns (2: DHD_MOTOR_SATURATED).
  int watchdog_error = 0;   // dhdSetWatchdog and dhdGetWatchdog fail with this DHD error.
};

constexpr double kWatchdogUnit_s = 125e-6;

struct State {
  std::mutex mutex;
  bool configured = false;
  Script script;
  std::vector<DhdStandinCall> calls;
  long position_calls = 0;
  long force_calls = 0;
  bool open = false;
  // The firmware: its watchdog (units; 0: off), whether forces are on, the last command.
  int watchdog_units = 0;
  bool forces_enabled = false;
  double last_force_s = -1.0;
  double last_force[3] = {0, 0, 0};
};

State& state() {
  // Destroyed when the library is unloaded (a test's dlclose), so nothing is left behind.
  static State s;
  return s;
}

thread_local int last_error = 0;
thread_local char last_error_text[96] = "no error";

void set_error(int code, const char* text) {
  last_error = code;
  std::snprintf(last_error_text, sizeof last_error_text, "%s", text);
}

void apply(Script& script, const std::string& text) {
  hapticut_standin::for_each_pair(
      text, [&](const std::string& key, const std::string& value, double number) {
        if (key == "devices") script.devices = static_cast<int>(number);
        if (key == "type") script.type = static_cast<int>(number);
        if (key == "reset") script.reset = number != 0.0;
        if (key == "max_force") script.max_force = number;
        if (key == "buttons") script.buttons = static_cast<unsigned int>(number);
        if (key == "from") hapticut_standin::parse_xyz(value, script.from);
        if (key == "to") hapticut_standin::parse_xyz(value, script.to);
        if (key == "reads") script.reads = std::max(1L, static_cast<long>(number));
        if (key == "yaw_deg") script.yaw_deg = number;
        if (key == "open_error") script.open_error = static_cast<int>(number);
        if (key == "fail_position_at") script.fail_position_at = static_cast<long>(number);
        if (key == "fail_count") script.fail_count = static_cast<long>(number);
        if (key == "fail_force_at") script.fail_force_at = static_cast<long>(number);
        if (key == "position_result") script.position_result = static_cast<int>(number);
        if (key == "force_result") script.force_result = static_cast<int>(number);
        if (key == "watchdog_error") script.watchdog_error = static_cast<int>(number);
      });
}

// Locks the state, applying $HAPTICUT_DHD_STANDIN at the first call.
std::unique_lock<std::mutex> lock_state() {
  State& s = state();
  std::unique_lock<std::mutex> lock(s.mutex);
  if (!s.configured) {
    s.configured = true;
    s.calls.reserve(kMaxCalls);
    const char* text = std::getenv("HAPTICUT_DHD_STANDIN");
    if (text != nullptr) apply(s.script, text);
  }
  return lock;
}

void push(const char* name, double a, double b, double c, int result, double time_s) {
  State& s = state();
  if (s.calls.size() >= kMaxCalls) return;
  DhdStandinCall call{};
  std::snprintf(call.name, sizeof call.name, "%s", name);
  call.a = a;
  call.b = b;
  call.c = c;
  call.result = result;
  call.time_s = time_s;
  s.calls.push_back(call);
}

// The firmware's watchdog at `now_s`: no force command for longer than its duration
// disabled forces at the last command's time plus the duration.
void expire_watchdog(double now_s) {
  State& s = state();
  if (!s.forces_enabled || s.watchdog_units == 0 || s.last_force_s < 0.0) return;
  const double expired_s = s.last_force_s + s.watchdog_units * kWatchdogUnit_s;
  if (now_s <= expired_s) return;
  s.forces_enabled = false;
  push("firmware_watchdog", s.last_force[0], s.last_force[1], s.last_force[2], 0, expired_s);
}

double last_call_s = 0.0;  // Under the lock: the time of the call record() last stamped.

int record(const char* name, double a, double b, double c, int result) {
  last_call_s = hapticut_standin::now_s();
  expire_watchdog(last_call_s);
  push(name, a, b, c, result, last_call_s);
  return result;
}

void write_log() {
  const char* path = std::getenv("HAPTICUT_DHD_STANDIN_LOG");
  if (path == nullptr) return;
  std::FILE* file = std::fopen(path, "w");
  if (file == nullptr) return;
  for (const DhdStandinCall& call : state().calls) {
    std::fprintf(file, "%s %.17g %.17g %.17g %d %.9f\n", call.name, call.a, call.b, call.c,
                 call.result, call.time_s);
  }
  std::fclose(file);
}

}  // namespace

extern "C" {

__attribute__((visibility("default"))) void hapticut_dhd_standin_configure(const char* script) {
  auto lock = lock_state();
  State& s = state();
  s.script = Script{};
  apply(s.script, script != nullptr ? script : "");
  s.calls.clear();
  s.position_calls = 0;
  s.force_calls = 0;
  s.open = false;
  s.watchdog_units = 0;
  s.forces_enabled = false;
  s.last_force_s = -1.0;
}

__attribute__((visibility("default"))) int hapticut_dhd_standin_calls(DhdStandinCall* out,
                                                                      int capacity) {
  auto lock = lock_state();
  expire_watchdog(hapticut_standin::now_s());
  const std::vector<DhdStandinCall>& calls = state().calls;
  const int count = static_cast<int>(calls.size());
  for (int i = 0; i < std::min(count, capacity); ++i) out[i] = calls[static_cast<std::size_t>(i)];
  return count;
}

__attribute__((visibility("default"))) int hapticut_dhd_standin_applied_force(double time_s,
                                                                              double force[3]) {
  auto lock = lock_state();
  expire_watchdog(hapticut_standin::now_s());
  bool enabled = false;
  double watchdog_s = 0.0;
  double last_s = -1.0;
  double last[3] = {0, 0, 0};
  for (const DhdStandinCall& call : state().calls) {
    if (call.time_s > time_s) break;
    const std::string name = call.name;
    if (call.result < 0) continue;
    if (name == "dhdEnableForce") enabled = call.a != 0.0;
    if (name == "dhdStop" || name == "dhdClose" || name == "firmware_watchdog") enabled = false;
    if (name == "dhdSetWatchdog") watchdog_s = call.a * kWatchdogUnit_s;
    if (name == "dhdSetForce") {
      last_s = call.time_s;
      last[0] = call.a;
      last[1] = call.b;
      last[2] = call.c;
    }
  }
  const bool on = enabled && last_s >= 0.0 && (watchdog_s == 0.0 || time_s - last_s <= watchdog_s);
  for (int i = 0; i < 3; ++i) force[i] = on ? last[i] : 0.0;
  return on ? 1 : 0;
}

__attribute__((visibility("default"))) int dhdGetDeviceCount() {
  auto lock = lock_state();
  return record("dhdGetDeviceCount", 0, 0, 0, state().script.devices);
}

__attribute__((visibility("default"))) int dhdOpenID(char index) {
  auto lock = lock_state();
  State& s = state();
  if (index < 0 || index >= s.script.devices) {
    set_error(5, "no device found (stand-in)");
    return record("dhdOpenID", index, 0, 0, -1);
  }
  if (s.script.open_error != 0) {
    set_error(s.script.open_error, "device in use (stand-in)");
    return record("dhdOpenID", index, 0, 0, -1);
  }
  s.open = true;
  return record("dhdOpenID", index, 0, 0, index);
}

__attribute__((visibility("default"))) int dhdGetSystemType(char id) {
  auto lock = lock_state();
  return record("dhdGetSystemType", id, 0, 0, state().script.type);
}

__attribute__((visibility("default"))) double dhdGetMaxForce(char id) {
  auto lock = lock_state();
  record("dhdGetMaxForce", id, state().script.max_force, 0, 0);
  return state().script.max_force;
}

__attribute__((visibility("default"))) int dhdEnableForce(unsigned char value, char id) {
  auto lock = lock_state();
  record("dhdEnableForce", value, id, 0, 0);
  state().forces_enabled = value != 0;
  return 0;
}

#ifndef HAPTICUT_DHD_STANDIN_NO_WATCHDOG
__attribute__((visibility("default"))) int dhdSetWatchdog(unsigned char units, char id) {
  auto lock = lock_state();
  State& s = state();
  if (s.script.watchdog_error != 0) {
    set_error(s.script.watchdog_error, "not available on this device (stand-in)");
    return record("dhdSetWatchdog", units, id, 0, -1);
  }
  record("dhdSetWatchdog", units, id, 0, 0);
  s.watchdog_units = units;
  return 0;
}

__attribute__((visibility("default"))) int dhdGetWatchdog(unsigned char* units, char id) {
  auto lock = lock_state();
  State& s = state();
  if (s.script.watchdog_error != 0) {
    set_error(s.script.watchdog_error, "not available on this device (stand-in)");
    return record("dhdGetWatchdog", 0, id, 0, -1);
  }
  *units = static_cast<unsigned char>(s.watchdog_units);
  return record("dhdGetWatchdog", *units, id, 0, 0);
}
#endif

__attribute__((visibility("default"))) int dhdGetPosition(double* x, double* y, double* z,
                                                          char /*id*/) {
  auto lock = lock_state();
  State& s = state();
  const long call = ++s.position_calls;
  const Script& p = s.script;
  if (p.fail_position_at > 0 && call >= p.fail_position_at &&
      call < p.fail_position_at + p.fail_count) {
    set_error(kErrorCom, "communication error (stand-in)");
    return record("dhdGetPosition", 0, 0, 0, -1);
  }
  const double t = std::min(1.0, static_cast<double>(call - 1) / static_cast<double>(p.reads));
  *x = p.from[0] + t * (p.to[0] - p.from[0]);
  *y = p.from[1] + t * (p.to[1] - p.from[1]);
  *z = p.from[2] + t * (p.to[2] - p.from[2]);
  return record("dhdGetPosition", *x, *y, *z, p.position_result);
}

__attribute__((visibility("default"))) int dhdGetOrientationFrame(double matrix[3][3],
                                                                  char /*id*/) {
  auto lock = lock_state();
  const double yaw = state().script.yaw_deg * std::acos(-1.0) / 180.0;
  const double c = std::cos(yaw);
  const double s = std::sin(yaw);
  const double about_z[3][3] = {{c, -s, 0}, {s, c, 0}, {0, 0, 1}};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) matrix[i][j] = about_z[i][j];
  }
  return record("dhdGetOrientationFrame", state().script.yaw_deg, 0, 0, 0);
}

__attribute__((visibility("default"))) int dhdGetStatus(int status[32], char id) {
  auto lock = lock_state();
  // Only DHD_MAX_STATUS entries, as the SDK writes: the servo's larger array keeps the rest.
  constexpr int kMaxStatus = 17;
  constexpr int kStatusPower = 0;
  constexpr int kStatusConnected = 1;
  constexpr int kStatusReset = 3;
  for (int i = 0; i < kMaxStatus; ++i) status[i] = 0;
  status[kStatusPower] = 1;
  status[kStatusConnected] = 1;
  status[kStatusReset] = state().script.reset ? 1 : 0;
  return record("dhdGetStatus", id, status[kStatusReset], 0, 0);
}

__attribute__((visibility("default"))) unsigned int dhdGetButtonMask(char /*id*/) {
  auto lock = lock_state();
  record("dhdGetButtonMask", state().script.buttons, 0, 0, 0);
  return state().script.buttons;
}

__attribute__((visibility("default"))) int dhdSetForce(double fx, double fy, double fz,
                                                       char /*id*/) {
  auto lock = lock_state();
  State& s = state();
  const long call = ++s.force_calls;
  if (s.script.fail_force_at > 0 && call == s.script.fail_force_at) {
    set_error(kErrorCom, "communication error (stand-in)");
    return record("dhdSetForce", fx, fy, fz, -1);
  }
  record("dhdSetForce", fx, fy, fz, s.script.force_result);
  s.last_force_s = last_call_s;
  s.last_force[0] = fx;
  s.last_force[1] = fy;
  s.last_force[2] = fz;
  return s.script.force_result;
}

__attribute__((visibility("default"))) int dhdErrorGetLast() { return last_error; }

__attribute__((visibility("default"))) const char* dhdErrorGetLastStr() { return last_error_text; }

__attribute__((visibility("default"))) int dhdStop(char id) {
  auto lock = lock_state();
  record("dhdStop", id, 0, 0, 0);
  state().forces_enabled = false;
  return 0;
}

__attribute__((visibility("default"))) int dhdClose(char id) {
  auto lock = lock_state();
  state().open = false;
  record("dhdClose", id, 0, 0, 0);
  state().forces_enabled = false;
  write_log();
  return 0;
}
}
