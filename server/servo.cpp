#include "servo.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <future>

#include "client_files.h"
#include "devices/viewport_device.h"
#include "hapticut/scene_io.h"
#include "protocol.h"
#include "rt/clock.h"
#include "rt/realtime.h"

namespace hapticut::servo {

namespace {

nlohmann::json flag_names(std::uint32_t flags) {
  nlohmann::json names = nlohmann::json::array();
  for (int bit = 0; bit < kSafetyFlagCount; ++bit) {
    if (flags & (1U << bit)) names.push_back(safety_flag_name(bit));
  }
  return names;
}

const char* status_name(std::uint8_t status) {
  switch (status) {
    case 0:
      return "fresh";
    case 1:
      return "stale";
    default:
      return "lost";
  }
}

nlohmann::json percentiles(const LatencyHistogram& h) {
  return {{"p50", h.percentile_us(0.5)},
          {"p99", h.percentile_us(0.99)},
          {"max", h.max_us()},
          {"count", h.count()}};
}

// A blade's transitions per tick ("set blade_transition_budget"; 0: 16 per
// point): the loop sums them in an int.
constexpr std::int64_t kMaxBladeTransitionBudget = 1000000000;

std::string newtons_per_mm(double k) {
  char text[64];
  std::snprintf(text, sizeof(text), "%g N/mm", k);
  return text;
}

// A binding's stiffness limit for messages: "0.2 N/mm", or at a rate below
// 1 kHz "0.1 N/mm at 500 Hz (0.2 N/mm at 1 kHz)"; for a rigid blade the limit
// on each point's k and where it comes from, "0.004 N/mm per point (a rigid
// blade of 50 points renders 50 k: the device's 0.2 N/mm over 50)".
std::string stiffness_limit_text(const Binding& b, double rate_Hz) {
  std::string device_limit = newtons_per_mm(b.device_max_stiffness_N_per_mm);
  if (rate_Hz < kStiffnessLimitRate_Hz) {
    char rate[32];
    std::snprintf(rate, sizeof(rate), "%g Hz", rate_Hz);
    device_limit += std::string(" at ") + rate + " (" +
                    newtons_per_mm(b.device->limits().max_stiffness_N_per_mm) + " at 1 kHz)";
  }
  if (b.springs == 1) return device_limit;
  const std::string n = std::to_string(b.springs);
  return newtons_per_mm(b.max_stiffness_N_per_mm) + " per point (a rigid blade of " + n +
         " points renders " + n + " k: the device's " + device_limit + " over " + n + ")";
}

}  // namespace

Servo::Servo(const Options& options) : options_(options), shared_(std::make_unique<LoopShared>()) {
  shared_->engaged.store(options.engage);
  housekeeping_thread_ = std::thread([this] { housekeeping(); });
}

Servo::~Servo() {
  try {
    stop();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hapticut-servo: stopping: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "hapticut-servo: stopping failed\n");
  }
  quit_housekeeping_.store(true);
  try {
    if (housekeeping_thread_.joinable()) housekeeping_thread_.join();
  } catch (...) {
    std::fprintf(stderr, "hapticut-servo: housekeeping thread did not join\n");
  }
}

SessionConfig Servo::config_from_options() const {
  SessionConfig c;
  c.scene_path = options_.scene_path;
  c.max_scene_bytes = options_.max_scene_bytes;
  c.devices = options_.devices;
  c.rate_Hz = options_.rate_Hz;
  c.as_fast_as_possible = options_.as_fast_as_possible;
  c.watchdog_ms = options_.watchdog_ms;
  c.safety_request.max_force_N = options_.max_force_N;
  c.safety_request.max_torque_N_mm = options_.max_torque_N_mm;
  c.safety_request.ramp_time_s = options_.ramp_s;
  c.safety_request.stop_ramp_time_s = options_.stop_ramp_s;
  c.safety_request.engage_buttons = options_.engage_buttons;
  c.passivity = options_.passivity;
  c.passivity_link_delay_s = options_.passivity_delay_ms / 1000.0;
  c.remote_bridge_allowed = !options_.token.empty();
  return c;
}

void Servo::load(const SessionConfig& config) {
  begin_load();
  PreparedLoad prepared;
  try {
    prepared = prepare_load(config, options_.record_buffer_s);
  } catch (...) {
    end_load();
    throw;
  }
  install(std::move(prepared));
}

void Servo::begin_load() {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (shared_->running.load() || loop_thread_.joinable()) {
    throw CommandError("cannot load while running (stop first)");
  }
  if (loading_) {
    throw CommandError(
        "another load is in progress (one at a time); send load again once it is answered "
        "(status: loading)");
  }
  loading_ = true;
}

void Servo::end_load() {
  const std::lock_guard<std::mutex> lock(mutex_);
  loading_ = false;
}

void Servo::install(PreparedLoad prepared) {
  std::lock_guard<std::mutex> lock(mutex_);
  loading_ = false;
  // begin_load refused a running servo and start refuses while loading, so
  // the loop is not running: the swap is the one a load always made.
  if (shared_->running.load() || loop_thread_.joinable()) {
    throw CommandError("cannot load while running (stop first)");
  }
  shared_->ring.store(nullptr);
  session_ = std::move(prepared.session);
  recorder_ = std::move(prepared.recorder);
  shared_->settings.publish(session_->runtime_settings());  // The scene's, until a "set".
  run_ended_.store(false);
  // The scene's stiffness above a device's limit: that blade runs at the limit
  // (the loop lowers it every tick, servo_loop.cpp). Said even with --quiet.
  const double scene_k = session_->runtime_settings().stiffness_N_per_mm;
  for (const Binding& b : session_->bindings()) {
    if (stiffness_in_force(scene_k, b.max_stiffness_N_per_mm) == scene_k) continue;
    std::fprintf(stderr,
                 "hapticut-servo: blade '%s': the scene's stiffness %s is above device '%s''s "
                 "limit of %s; lowered to %s\n",
                 b.blade_name.c_str(), newtons_per_mm(scene_k).c_str(), b.device_text.c_str(),
                 stiffness_limit_text(b, session_->rate_Hz()).c_str(),
                 newtons_per_mm(b.max_stiffness_N_per_mm).c_str());
  }
  std::fflush(stderr);
  if (!options_.quiet) {
    std::printf("hapticut-servo: loaded %s: %zu blade(s) at %g Hz\n",
                session_->scene_label().c_str(), session_->bindings().size(), session_->rate_Hz());
    for (const Binding& b : session_->bindings()) {
      std::printf("  blade '%s' (%zu points, %s) <- %s\n", b.blade_name.c_str(),
                  b.snapshot.point_count(), coupling_name(b.blade->coupling()),
                  b.device_text.c_str());
    }
    std::fflush(stdout);
  }
}

void Servo::start() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (loading_) {
    throw CommandError("a load is in progress; start once it is answered (status: loading)");
  }
  if (!session_) throw CommandError("no scene loaded (send \"load\" first)");
  if (loop_thread_.joinable()) throw CommandError("already running");
  LoopShared& s = *shared_;
  s.stop_requested.store(false);
  s.ended_by_itself.store(false);
  s.ticks.store(0);
  s.late_ticks.store(0);
  s.dropped_records.store(0);
  s.frames_published.store(0);
  s.compute_us.clear();
  s.wake_us.clear();
  s.session.fetch_add(1);
  s.exit_when_done = options_.exit_when_done;
  s.duration_s = options_.duration_s;
  run_ended_.store(false);
  std::size_t started = 0;
  try {
    for (Binding& b : session_->bindings()) {
      try {
        b.device->start();
      } catch (const DeviceError&) {
        throw;
      } catch (const std::exception& e) {
        // A device that cannot open (no HID device, bridge port in use).
        throw DeviceError("blade '" + b.blade_name + "': device '" + b.device_text +
                          "': " + e.what());
      }
      ++started;
    }
  } catch (...) {
    for (std::size_t i = 0; i < started; ++i) session_->bindings()[i].device->stop();
    throw;
  }
  if (!options_.record_path.empty()) {
    try {
      recorder_->start(open_operator_recording(options_.record_path), options_.record_path, s);
    } catch (...) {
      for (Binding& b : session_->bindings()) b.device->stop();
      throw;
    }
  }
  const bool fast = session_->as_fast_as_possible();
  const bool realtime = options_.realtime && !fast;
  const int priority = options_.priority;
  std::string memory_message = lock_memory();
  std::promise<std::string> started_message;
  auto message_future = started_message.get_future();
  s.running.store(true);
  loop_thread_ = std::thread([this, realtime, priority, &started_message] {
    std::string message =
        realtime ? enter_realtime_priority(priority)
                 : std::string("real-time: not asked for (") +
                       (options_.realtime ? "as fast as possible" : "--no-realtime") + ")";
    if (options_.cpu >= 0) message += "; " + pin_to_cpu(options_.cpu);
    started_message.set_value(message);
    run_loop(*session_, *shared_);
  });
  realtime_message_ = message_future.get();
  ++runs_;
  if (!options_.quiet) {
    std::printf("hapticut-servo: run %d started; %s; %s\n", runs_, realtime_message_.c_str(),
                memory_message.c_str());
    std::fflush(stdout);
  }
}

nlohmann::json Servo::stop() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!loop_thread_.joinable()) return nullptr;
  shared_->stop_requested.store(true);
  return finish_run_locked();
}

nlohmann::json Servo::finish_run_locked() {
  loop_thread_.join();
  if (recorder_) recorder_->stop(*shared_);
  for (Binding& b : session_->bindings()) b.device->stop();
  report_events_locked();
  nlohmann::json stats = stats_locked();
  std::printf("stats %s\n", stats.dump().c_str());
  std::fflush(stdout);
  return stats;
}

nlohmann::json Servo::stats_locked() const {
  const LoopShared& s = *shared_;
  nlohmann::json out;
  out["run"] = runs_;
  out["ticks"] = s.ticks.load();
  out["late_ticks"] = s.late_ticks.load();
  out["time_s"] = s.time_s.load();
  out["compute_us"] = percentiles(s.compute_us);
  out["wake_latency_us"] = percentiles(s.wake_us);
  out["frames_published"] = s.frames_published.load();
  out["dropped_records"] = s.dropped_records.load();
  out["ended_by_itself"] = s.ended_by_itself.load();
  out["recording"] = {{"active", recorder_ && recorder_->active()},
                      {"path", recorder_ ? recorder_->path() : std::string()},
                      {"written", recorder_ ? recorder_->written() : 0},
                      {"error", recorder_ ? recorder_->error() : std::string()}};
  out["blades"] = nlohmann::json::array();
  RuntimeSettings settings;
  const bool has_settings = session_ && s.settings.read(settings) != 0;
  if (session_) {
    for (std::size_t i = 0; i < session_->bindings().size() && i < kMaxBlades; ++i) {
      const Binding& b = session_->bindings()[i];
      SafetyReport report;
      const bool has = s.reports[i].read(report) != 0;
      nlohmann::json events = nlohmann::json::object();
      for (int bit = 0; bit < kSafetyFlagCount; ++bit) {
        if (report.events[bit]) events[safety_flag_name(bit)] = report.events[bit];
      }
      nlohmann::json device_counters = nlohmann::json::object();
      for (const auto& [name, count] : b.device->status_counters()) device_counters[name] = count;
      const double k_in_force =
          has_settings ? stiffness_in_force(settings.stiffness_N_per_mm, b.max_stiffness_N_per_mm)
                       : 0.0;
      out["blades"].push_back(
          {{"name", b.blade_name},
           {"device", b.device_text},
           {"kind", b.device->kind()},
           {"device_counters", device_counters},
           {"device_error", b.device->last_error()},
           {"passivity", b.passivity},
           {"coupling", coupling_name(b.blade->coupling())},
           {"stiffness_N_per_mm", k_in_force},
           {"max_stiffness_N_per_mm", b.max_stiffness_N_per_mm},
           {"rendered_stiffness_N_per_mm", b.springs * k_in_force},
           {"device_max_stiffness_N_per_mm", b.device_max_stiffness_N_per_mm},
           {"device_status", has ? status_name(report.device_status) : "none"},
           {"flags", flag_names(report.flags)},
           {"faults", report.faults},
           {"events", events},
           {"ramp", report.ramp},
           {"force_N", {report.force_N[0], report.force_N[1], report.force_N[2]}},
           {"engine_force_N",
            {report.engine_force_N[0], report.engine_force_N[1], report.engine_force_N[2]}}});
    }
  }
  return out;
}

nlohmann::json Servo::status() {
  std::lock_guard<std::mutex> lock(mutex_);
  nlohmann::json out = stats_locked();
  const char* state = !session_                 ? "idle"
                      : shared_->running.load() ? "running"
                      : loop_thread_.joinable() ? "ending"
                      : runs_ > 0               ? "stopped"
                                                : "loaded";
  out["state"] = state;
  out["scene"] = session_ ? session_->scene_label() : std::string();
  out["rate_Hz"] = session_ ? session_->rate_Hz() : 0.0;
  out["loading"] = loading_;
  out["engaged"] = shared_->engaged.load();
  out["realtime"] = realtime_message_;
  RuntimeSettings settings;
  if (session_ && shared_->settings.read(settings) != 0) {
    out["settings"] = {{"stiffness_N_per_mm", settings.stiffness_N_per_mm},
                       {"shading", settings.force_shading},
                       {"max_transitions_per_tick", settings.max_transitions_per_tick},
                       {"capped_tick_force_N", settings.capped_tick_force_N},
                       {"blade_transition_budget", settings.blade_transition_budget}};
  }
  return out;
}

void Servo::report_events_locked() {
  if (!session_ || options_.quiet) return;
  for (std::size_t i = 0; i < session_->bindings().size() && i < kMaxBlades; ++i) {
    SafetyReport report;
    if (shared_->reports[i].read(report) == 0) continue;
    for (int bit = 0; bit < kSafetyFlagCount; ++bit) {
      const std::uint32_t flag = 1U << bit;
      if ((flag & kSafetyFaults) == 0) continue;
      if (report.events[bit] > reported_[i][bit]) {
        std::fprintf(stderr, "hapticut-servo: blade '%s': fault %s (%llu so far); force zero\n",
                     session_->bindings()[i].blade_name.c_str(), safety_flag_name(bit),
                     static_cast<unsigned long long>(report.events[bit]));
        reported_[i][bit] = report.events[bit];
      }
    }
  }
}

void Servo::housekeeping() {
  int round = 0;
  while (!quit_housekeeping_.load()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock() || !session_) continue;
    report_events_locked();
    if (loop_thread_.joinable() && !shared_->running.load()) {
      finish_run_locked();  // Ended by itself (stroke done, duration).
      run_ended_.store(true);
      continue;
    }
    if (++round % 5 == 0 && loop_thread_.joinable()) {
      for (Binding& b : session_->bindings()) b.device->maintain();
    }
  }
}

// "set": settings per tick (validated as the scene file's, handed to the loop
// through a LatestValue: the next tick steps with them), safety limits, the
// stream rate. All or nothing: a bad value applies none. Every number is
// checked against the engine's range for it (parameter_range.h, the scene
// file's table).
nlohmann::json Servo::set_parameters(const ControlJson& message) {
  static const char* const kKnown[] = {"type",
                                       "id",
                                       "stiffness_N_per_mm",
                                       "shading",
                                       "max_transitions_per_tick",
                                       "capped_tick_force_N",
                                       "blade_transition_budget",
                                       "max_force_N",
                                       "max_torque_N_mm",
                                       "ramp_time_s",
                                       "stream_rate_Hz"};
  for (const auto& [key, value] : message.items()) {
    if (std::find(std::begin(kKnown), std::end(kKnown), key) == std::end(kKnown)) {
      throw CommandError("unknown parameter " + quoted_excerpt(key) +
                         " (known: stiffness_N_per_mm, shading, max_transitions_per_tick, "
                         "capped_tick_force_N, blade_transition_budget, max_force_N, "
                         "max_torque_N_mm, ramp_time_s, stream_rate_Hz); nothing applied");
    }
  }
  std::lock_guard<std::mutex> lock(mutex_);
  RuntimeSettings settings;
  const bool has_settings = shared_->settings.read(settings) != 0;
  bool settings_changed = false;
  LimitsRequest limits;
  shared_->limits.read(limits);
  bool limits_changed = false;
  nlohmann::json applied = nlohmann::json::object();
  for (const auto& [key, value] : message.items()) {
    const char* name = key.c_str();
    if (key == "type" || key == "id") continue;
    if (key == "stiffness_N_per_mm") {
      settings.stiffness_N_per_mm = number_field(message, name, setting_range::kStiffness);
      settings_changed = true;
    } else if (key == "capped_tick_force_N") {
      settings.capped_tick_force_N = number_field(message, name, setting_range::kCappedTickForce);
      settings_changed = true;
    } else if (key == "max_transitions_per_tick") {
      const auto& range = setting_range::kMaxTransitions;
      settings.max_transitions_per_tick =
          static_cast<int>(integer_field(message, name, static_cast<std::int64_t>(range.minimum),
                                         static_cast<std::int64_t>(range.maximum)));
      settings_changed = true;
    } else if (key == "blade_transition_budget") {
      settings.blade_transition_budget =
          static_cast<int>(integer_field(message, name, 0, kMaxBladeTransitionBudget));
      settings_changed = true;
    } else if (key == "shading") {
      settings.force_shading = boolean_field(message, name);
      settings_changed = true;
    } else if (key == "max_force_N") {
      limits.max_force_N = number_field(message, name, setting_range::kMaxForce);
      limits_changed = true;
    } else if (key == "max_torque_N_mm") {
      limits.max_torque_N_mm = number_field(message, name, setting_range::kMaxTorque);
      limits_changed = true;
    } else if (key == "ramp_time_s") {
      limits.ramp_time_s = number_field(message, name, setting_range::kRampTime);
      limits_changed = true;
    }
    applied[key] = value;
  }
  if (settings_changed) {
    if (!session_ || !has_settings) throw CommandError("settings per tick: no scene loaded");
    try {
      settings.validate();
    } catch (const std::invalid_argument& e) {
      throw CommandError(std::string(e.what()) + "; nothing applied");
    }
    // Asked for explicitly: above a device's limit it is refused, not lowered
    // (the scene's own stiffness, kept when a "set" leaves it out, is lowered by the loop).
    const Binding* b = message.contains("stiffness_N_per_mm")
                           ? session_->stiffness_exceeded(settings.stiffness_N_per_mm)
                           : nullptr;
    if (b != nullptr) {
      throw CommandError("stiffness_N_per_mm: " + newtons_per_mm(settings.stiffness_N_per_mm) +
                         " is above the limit of " + stiffness_limit_text(*b, session_->rate_Hz()) +
                         " of blade '" + b->blade_name + "''s device '" + b->device_text +
                         "'; nothing applied");
    }
    shared_->settings.publish(settings);
  }
  if (limits_changed) shared_->limits.publish(limits);
  return {{"applied", applied}, {"note", "safety limits only lower the device's"}};
}

nlohmann::json Servo::loaded_reply() {
  std::lock_guard<std::mutex> lock(mutex_);
  nlohmann::json blades = nlohmann::json::array();
  for (const Binding& b : session_->bindings()) {
    blades.push_back({{"name", b.blade_name},
                      {"points", b.snapshot.point_count()},
                      {"device", b.device_text},
                      {"kind", b.device->kind()},
                      {"coupling", coupling_name(b.blade->coupling())},
                      {"max_stiffness_N_per_mm", b.max_stiffness_N_per_mm},
                      {"device_max_stiffness_N_per_mm", b.device_max_stiffness_N_per_mm}});
  }
  return {{"blades", blades},
          {"rate_Hz", session_->rate_Hz()},
          {"frame_bytes", session_->frame_bytes()},
          {"record_bytes", session_->recording_info().record_bytes}};
}

nlohmann::json Servo::record_command(const ControlJson& message) {
  const std::string action =
      has_field(message, "action") ? string_field(message, "action", kMaxTypeBytes) : "start";
  if (action != "start" && action != "stop") {
    throw CommandError("action: expected \"start\" or \"stop\"");
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (!recorder_) throw CommandError("no scene loaded");
  if (action == "stop") {
    recorder_->stop(*shared_);
    return {{"written", recorder_->written()}, {"dropped", shared_->dropped_records.load()}};
  }
  if (!has_field(message, "path")) throw CommandError("record start needs \"path\"");
  const std::string requested = string_field(message, "path", kMaxPathBytes);
  if (recorder_->active()) {
    throw CommandError("already recording to '" + recorder_->path() + "' (stop it first)");
  }
  try {
    std::string path;
    std::FILE* file = create_recording_file(options_.record_dir, requested, path);
    recorder_->start(file, path, *shared_);
  } catch (const std::runtime_error& e) {
    throw CommandError(std::string("record: ") + e.what());
  }
  return {{"recording", recorder_->path()}};
}

nlohmann::json Servo::pose_command(const ControlJson& message) {
  const std::string blade = string_field(message, "blade", kMaxNameBytes);
  const auto& p = message.contains("pose") ? message.at("pose") : ControlJson();
  if (!p.is_array() || p.size() != 7)
    throw CommandError("pose: expected [x, y, z, qw, qx, qy, qz]");
  double v[7];
  for (int i = 0; i < 7; ++i) {
    if (!p[i].is_number()) throw CommandError("pose/" + std::to_string(i) + ": not a number");
    v[i] = p[i].get<double>();  // NaN cannot be written in JSON; the guard still checks.
  }
  const auto buttons = has_field(message, "buttons")
                           ? static_cast<unsigned>(integer_field(message, "buttons", 0, 0xFFFFFFFF))
                           : 0U;
  std::lock_guard<std::mutex> lock(mutex_);
  Binding* b = session_ ? session_->find(blade) : nullptr;
  if (b == nullptr) throw CommandError("pose: no blade " + quoted_excerpt(blade));
  if (b->viewport == nullptr) {
    throw CommandError("pose: blade '" + blade + "' is driven by " + b->device->kind() +
                       ", not a viewport device");
  }
  b->viewport->push({{v[0], v[1], v[2]}, {v[3], v[4], v[5], v[6]}}, buttons, monotonic_now_s());
  return nlohmann::json::object();
}

nlohmann::json Servo::start_command() {
  start();
  return {{"session", shared_->session.load()}};
}

nlohmann::json Servo::stop_command() { return {{"stats", stop()}}; }

nlohmann::json Servo::engage_command(const ControlJson& message) {
  const bool engaged = boolean_field(message, "engaged");
  shared_->engaged.store(engaged);
  return {{"engaged", engaged}};
}

namespace {

// The most cut tets one `cuts` reply carries (a client asks again from where
// it ended: "more").
constexpr std::uint32_t kMaxCutsPerReply = 8192;
// A cuts file: its JSON, a tet index a few bytes each.
constexpr std::uint64_t kMaxCutsFileBytes = 64ULL << 20;
constexpr const char* kCutsFormat = "hapticut.cuts";
constexpr int kCutsVersion = 1;

}  // namespace

nlohmann::json Servo::cuts_command(const ControlJson& message) {
  const auto from = has_field(message, "from")
                        ? static_cast<std::uint32_t>(integer_field(message, "from", 0, 0xFFFFFFFF))
                        : 0U;
  std::lock_guard<std::mutex> lock(mutex_);
  if (!session_) throw CommandError("cuts: no scene loaded");
  std::vector<std::int32_t> tets;
  const CutFeed::Part part = session_->cut_feed().read(from, kMaxCutsPerReply, tets);
  const std::uint32_t start = std::min(from, part.total);
  return {{"generation", part.generation},
          {"total", part.total},
          {"from", start},
          {"tets", tets},
          {"more", start + tets.size() < part.total}};
}

nlohmann::json Servo::reset_cuts_command() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!session_) throw CommandError("reset_cuts: no scene loaded");
  if (loop_thread_.joinable()) {
    // The loop resets them at its next tick, before any blade steps.
    shared_->cut_resets_requested.fetch_add(1);
    return {{"at", "the next tick"}};
  }
  session_->cut_state().reset_cuts();
  session_->cut_feed().follow(session_->cuts());
  return {{"at", "now"}, {"generation", session_->cuts().generation()}};
}

nlohmann::json Servo::save_cuts_command(const ControlJson& message) {
  const std::string requested = string_field(message, "path", kMaxPathBytes);
  std::lock_guard<std::mutex> lock(mutex_);
  if (!session_) throw CommandError("save_cuts: no scene loaded");
  std::vector<std::int32_t> tets;
  const CutFeed::Part part = session_->cut_feed().read(0, 0xFFFFFFFF, tets);
  const nlohmann::json out = {{"format", kCutsFormat},
                              {"version", kCutsVersion},
                              {"scene", session_->scene_label()},
                              {"tet_count", session_->recording_info().tet_count},
                              {"tets", tets}};
  std::string path;
  try {
    std::FILE* file = create_recording_file(options_.record_dir, requested, path);
    const std::string text = out.dump();
    const bool written = std::fwrite(text.data(), 1, text.size(), file) == text.size();
    if (std::fclose(file) != 0 || !written) {
      throw FileRefused("'" + path + "': " + std::strerror(errno));
    }
  } catch (const std::runtime_error& e) {
    throw CommandError(std::string("save_cuts: ") + e.what());
  }
  return {{"path", path}, {"tets", tets.size()}, {"generation", part.generation}};
}

nlohmann::json Servo::load_cuts_command(const ControlJson& message) {
  const std::string requested = string_field(message, "path", kMaxPathBytes);
  std::lock_guard<std::mutex> lock(mutex_);
  if (!session_) throw CommandError("load_cuts: no scene loaded");
  if (loading_) throw CommandError("load_cuts: a load is in progress (status: loading)");
  if (loop_thread_.joinable()) {
    throw CommandError("load_cuts: a run is on (stop it first; reset_cuts works while running)");
  }
  std::string path;
  std::vector<std::uint8_t> bytes;
  try {
    bytes = read_recording_directory_file(options_.record_dir, requested, kMaxCutsFileBytes, path);
  } catch (const std::runtime_error& e) {
    throw CommandError(std::string("load_cuts: ") + e.what());
  }
  const std::string where = "load_cuts: '" + path + "': ";
  const nlohmann::json in = nlohmann::json::parse(bytes.begin(), bytes.end(), nullptr, false);
  if (!in.is_object() || in.value("format", std::string()) != kCutsFormat) {
    throw CommandError(where + "not a cuts file (format \"" + kCutsFormat + "\")");
  }
  if (!in.contains("version") || in.at("version") != kCutsVersion) {
    throw CommandError(where + "version " +
                       (in.contains("version") ? in.at("version").dump() : "none") +
                       ", this servo reads version " + std::to_string(kCutsVersion));
  }
  const std::uint32_t tet_count = session_->recording_info().tet_count;
  if (!in.contains("tet_count") || in.at("tet_count") != tet_count) {
    throw CommandError(where + "saved from a scene of " +
                       (in.contains("tet_count") ? in.at("tet_count").dump() : "unknown") +
                       " tets ('" + in.value("scene", std::string()) + "'); the loaded scene has " +
                       std::to_string(tet_count) + " ('" + session_->scene_label() + "')");
  }
  const auto& list = in.contains("tets") ? in.at("tets") : nlohmann::json();
  if (!list.is_array()) throw CommandError(where + "tets: expected a list of tet indices");
  std::vector<std::int32_t> tets;
  tets.reserve(list.size());
  for (std::size_t i = 0; i < list.size(); ++i) {
    if (!list[i].is_number_integer() || list[i].get<std::int64_t>() < 0 ||
        list[i].get<std::int64_t>() >= tet_count) {
      throw CommandError(where + "tets/" + std::to_string(i) + ": expected a tet index, 0 to " +
                         std::to_string(tet_count - 1));
    }
    tets.push_back(list[i].get<std::int32_t>());
  }
  try {
    session_->cut_state().set_cuts(tets);
  } catch (const std::invalid_argument& e) {
    throw CommandError(where + e.what() + "; the cuts are as they were");
  }
  session_->cut_feed().follow(session_->cuts());
  return {{"path", path}, {"tets", tets.size()}, {"generation", session_->cuts().generation()}};
}

}  // namespace hapticut::servo
