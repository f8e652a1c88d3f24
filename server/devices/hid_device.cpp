#include "devices/hid_device.h"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "devices/device_limits_json.h"

namespace hapticut::servo {
namespace {

// Reports drained per pass at most: a device cannot keep the I/O thread busy forever.
constexpr int kMaxReportsPerPass = 256;

double monotonic_s() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

std::string hex16(std::uint16_t value) {
  char text[8];
  std::snprintf(text, sizeof text, "0x%04x", value);
  return text;
}

std::string describe_match(const DeviceProfile& profile) {
  std::string products;
  for (std::uint16_t id : profile.match.product_ids) {
    products += (products.empty() ? "" : ", ") + hex16(id);
  }
  return "profile '" + profile.name + "' (vendor " + hex16(profile.match.vendor_id) + ", product " +
         products + ")";
}

// Transpose of an orthonormal matrix: the tool frame back to the device's.
Vec3 multiply_transposed(const std::array<std::array<double, 3>, 3>& m, const Vec3& v) {
  return {m[0][0] * v.x + m[1][0] * v.y + m[2][0] * v.z,
          m[0][1] * v.x + m[1][1] * v.y + m[2][1] * v.z,
          m[0][2] * v.x + m[1][2] * v.y + m[2][2] * v.z};
}

// A multi-axis controller interface (usage page 1, usage 8) is the one a
// puck reports on when a receiver exposes several.
int interface_preference(const HidDeviceInfo& info) {
  return info.usage_page == 0x01 && info.usage == 0x08 ? 0 : 1;
}

HidInterfaceId interface_id(const HidDeviceInfo& info) {
  return {info.vendor_id, info.product_id, info.serial, info.interface_number, info.usage_page};
}

}  // namespace

HidDeviceOptions hid_device_options(const DeviceProfile& profile) {
  HidDeviceOptions options;
  options.profile = profile;
  options.mapping = mapping_settings_from(profile);
  return options;
}

HidDevice::HidDevice(std::unique_ptr<HidTransport> transport, HidDeviceOptions options)
    : transport_(std::move(transport)),
      options_(std::move(options)),
      mapping_(options_.mapping, options_.home) {
  last_sample_.pose = mapping_.pose();
}

HidDevice::~HidDevice() { stop(); }

std::string HidDevice::last_error() const {
  const std::lock_guard<std::mutex> lock(error_mutex_);
  return last_error_;
}

bool HidDevice::open_matching(std::string& error) {
  std::vector<HidDeviceInfo> candidates;
  const bool reconnecting = identity_product_id_ != 0;
  for (const HidDeviceInfo& info : transport_->enumerate()) {
    if (!profile_matches(options_.profile, interface_id(info))) continue;
    if (reconnecting) {
      // The same unit again: vendor (the profile's), product and serial; the node may differ.
      if (info.product_id != identity_product_id_) continue;
      if (!identity_serial_.empty() && info.serial != identity_serial_) continue;
    } else {
      if (!options_.path.empty() && info.path != options_.path) continue;
      if (!options_.serial.empty() && info.serial != options_.serial) continue;
    }
    candidates.push_back(info);
  }
  if (candidates.empty()) {
    error = "hid: no device matches " + describe_match(options_.profile) +
            (options_.path.empty() || reconnecting ? "" : " at " + options_.path) +
            (options_.serial.empty() ? "" : " with serial " + options_.serial) +
            "; `hapticut-servo --list-devices` shows what is connected";
    return false;
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const HidDeviceInfo& a, const HidDeviceInfo& b) {
                     return interface_preference(a) < interface_preference(b);
                   });
  std::string open_error;
  for (const HidDeviceInfo& info : candidates) {
    if (transport_->open(info.path, open_error)) {
      identity_product_id_ = info.product_id;
      identity_serial_ = info.serial;
      opened_path_ = info.path;
      return true;
    }
  }
  error = "hid: " + open_error;
  return false;
}

void HidDevice::start() {
  if (running_.load()) return;
  std::string error;
  if (!open_matching(error)) {
    {
      const std::lock_guard<std::mutex> lock(error_mutex_);
      last_error_ = error;
    }
    throw std::runtime_error(error);
  }
  connection_count_.fetch_add(1, std::memory_order_relaxed);
  connection_.store(kConnected, std::memory_order_release);
  if (options_.io_thread) {
    running_.store(true);
    io_thread_ = std::thread([this] { io_loop(); });
  }
}

void HidDevice::stop() {
  running_.store(false);
  if (io_thread_.joinable()) io_thread_.join();
  // Nothing left pushing: a zero force report before closing.
  if (connected()) write_force_now({});
  transport_->close();
  connection_.store(kLost, std::memory_order_release);
}

void HidDevice::io_loop() {
  while (running_.load(std::memory_order_relaxed)) {
    if (connected()) {
      pump(options_.read_timeout_ms);
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
}

void HidDevice::mark_lost() {
  transport_->close();
  counters_.disconnects.fetch_add(1, std::memory_order_relaxed);
  connection_.store(kLost, std::memory_order_release);
}

void HidDevice::write_force_now(const ForceCommand& command) {
  std::array<std::uint8_t, kHidReportBufferBytes> report{};
  const InputProfile& in = options_.profile.input;
  const std::size_t length = encode_output_report(
      options_.profile.output, multiply_transposed(in.translation_matrix, command.force_N),
      multiply_transposed(in.translation_matrix, command.torque_N_mm), report);
  if (length == 0) return;
  if (transport_->write(report.data(), length) < 0) {
    mark_lost();
    return;
  }
  counters_.force_reports.fetch_add(1, std::memory_order_relaxed);
}

void HidDevice::pump(int timeout_ms) {
  if (!connected()) return;
  const std::uint32_t connection = connection_count_.load(std::memory_order_relaxed);
  if (connection != io_connection_) {
    // A new connection starts from rest: nothing held over from before the loss.
    io_connection_ = connection;
    io_state_ = HidInputState{};
    io_reports_ = 0;
    input_.publish({io_state_, io_reports_, io_connection_, monotonic_s()});
  }
  std::array<std::uint8_t, kHidReportBufferBytes> buffer{};
  bool changed = false;
  for (int i = 0; i < kMaxReportsPerPass; ++i) {
    const int length = transport_->read(buffer.data(), buffer.size(), i == 0 ? timeout_ms : 0);
    if (length < 0) {
      mark_lost();
      return;
    }
    if (length == 0) break;
    switch (apply_input_report(options_.profile.input, buffer.data(),
                               static_cast<std::size_t>(length), io_state_)) {
      case ReportOutcome::Applied:
        ++io_reports_;
        changed = true;
        counters_.reports.fetch_add(1, std::memory_order_relaxed);
        break;
      case ReportOutcome::UnknownReport:
        counters_.unknown_reports.fetch_add(1, std::memory_order_relaxed);
        break;
      case ReportOutcome::WrongLength:
        counters_.wrong_length.fetch_add(1, std::memory_order_relaxed);
        break;
    }
  }
  if (changed) input_.publish({io_state_, io_reports_, io_connection_, monotonic_s()});

  ForceCommand command;
  const std::uint64_t sequence = force_.read(command);
  if (options_.profile.output.has_report && sequence != io_force_sequence_) {
    io_force_sequence_ = sequence;
    write_force_now(command);
  }
}

DeviceStatus HidDevice::read(double now_s, DeviceSample& sample) {
  const double dt_s = last_read_s_ < 0.0 ? 0.0 : now_s - last_read_s_;
  last_read_s_ = now_s;
  const bool is_connected = connected();
  const std::uint32_t connection = connection_count_.load(std::memory_order_relaxed);

  InputSnapshot snapshot;
  const bool have = input_.read(snapshot) != 0 && snapshot.connection == connection;
  // Lost, or reconnected but nothing published yet: the puck counts as at rest.
  const HidInputState state = is_connected && have ? snapshot.state : HidInputState{};
  // The zero state a new connection starts with is no report.
  const bool new_reports =
      have && snapshot.reports > 0 &&
      (connection != last_connection_seen_ || snapshot.reports != last_reports_seen_);

  if (options_.profile.input.kind == InputKind::Deflection) {
    const ToolFrameAxes axes = to_tool_frame(options_.profile.input, state);
    mapping_.update(axes.translation, axes.rotation, state.buttons, dt_s);
    last_sample_.pose = mapping_.pose();
    last_sample_.buttons = mapping_.buttons();
    if (is_connected) {
      // A puck reports only changes: at rest, its pose is still known each tick.
      last_sample_.time_s = now_s;
      ++last_sample_.sequence;
    }
  } else if (is_connected && new_reports) {
    const ToolFrameAxes axes = to_tool_frame(options_.profile.input, state);
    last_sample_.pose.position_mm = axes.translation;
    last_sample_.pose.rotation = rotation_vector_quaternion(axes.rotation);
    last_sample_.buttons = state.buttons;
    last_sample_.time_s = snapshot.time_s;
    ++last_sample_.sequence;
  }
  const bool fresh =
      is_connected && (options_.profile.input.kind == InputKind::Deflection || new_reports);
  if (have) {
    last_connection_seen_ = connection;
    last_reports_seen_ = snapshot.reports;
  }
  sample = last_sample_;
  if (!is_connected) return DeviceStatus::Lost;
  return fresh ? DeviceStatus::Fresh : DeviceStatus::Stale;
}

void HidDevice::write(const Vec3& force_N, const Vec3& torque_N_mm) {
  if (!options_.profile.output.has_report) return;
  force_.publish({force_N, torque_N_mm});
}

void HidDevice::maintain() {
  if (connected() || identity_product_id_ == 0) return;
  counters_.reconnect_attempts.fetch_add(1, std::memory_order_relaxed);
  std::string error;
  bool opened = false;
  try {
    opened = open_matching(error);
  } catch (const std::exception& failure) {
    error = failure.what();
  }
  {
    const std::lock_guard<std::mutex> lock(error_mutex_);
    last_error_ = opened ? "" : error;
  }
  if (!opened) return;
  counters_.reconnects.fetch_add(1, std::memory_order_relaxed);
  connection_count_.fetch_add(1, std::memory_order_relaxed);
  connection_.store(kConnected, std::memory_order_release);
}

std::vector<std::pair<std::string, std::uint64_t>> HidDevice::status_counters() const {
  const auto load = [](const std::atomic<std::uint64_t>& count) {
    return count.load(std::memory_order_relaxed);
  };
  return {{"reports", load(counters_.reports)},
          {"unknown_reports", load(counters_.unknown_reports)},
          {"wrong_length", load(counters_.wrong_length)},
          {"disconnects", load(counters_.disconnects)},
          {"reconnects", load(counters_.reconnects)},
          {"reconnect_attempts", load(counters_.reconnect_attempts)},
          {"force_reports", load(counters_.force_reports)}};
}

std::vector<HidDeviceRow> list_hid_devices(HidTransport& transport,
                                           const std::vector<DeviceProfile>& profiles) {
  std::vector<HidDeviceRow> rows;
  for (HidDeviceInfo& info : transport.enumerate()) {
    HidDeviceRow row;
    for (const DeviceProfile& profile : profiles) {
      if (profile_matches(profile, interface_id(info))) {
        row.profile = profile.name;
        break;
      }
    }
    row.info = std::move(info);
    rows.push_back(std::move(row));
  }
  return rows;
}

std::vector<HidDeviceRow> list_hid_devices(const std::vector<DeviceProfile>& profiles) {
  const std::unique_ptr<HidTransport> transport = make_hidapi_transport();
  return list_hid_devices(*transport, profiles);
}

std::string format_hid_device_list(const std::vector<HidDeviceRow>& rows) {
  if (rows.empty()) return "no HID devices found\n";
  std::ostringstream out;
  out << "path                 vendor:product  usage page  product                        "
         "profile\n";
  for (const HidDeviceRow& row : rows) {
    char line[512];
    std::snprintf(line, sizeof line, "%-20s %s:%s  %-10s  %-30s %s\n", row.info.path.c_str(),
                  hex16(row.info.vendor_id).c_str() + 2, hex16(row.info.product_id).c_str() + 2,
                  hex16(row.info.usage_page).c_str(),
                  row.info.product.empty() ? "-" : row.info.product.c_str(),
                  row.profile.empty() ? "-" : row.profile.c_str());
    out << line;
  }
  return out.str();
}

std::string list_hid_devices_text(const std::string& profile_directory) {
  return format_hid_device_list(
      list_hid_devices(load_profiles(find_profile_directory(profile_directory))));
}

namespace {

nlohmann::json name_or_null(const std::string& text, const std::string& prefix = "") {
  return text.empty() ? nlohmann::json(nullptr) : nlohmann::json(prefix + text);
}

}  // namespace

std::string format_device_list_json(const std::vector<HidDeviceRow>& rows,
                                    const std::vector<DeviceProfile>& profiles,
                                    const std::vector<DeviceKindInfo>& kinds,
                                    const std::string& profile_directory, double rate_Hz) {
  if (!(rate_Hz > 0.0) || !std::isfinite(rate_Hz)) {
    throw std::invalid_argument("--list-devices: the rate must be a positive number of Hz");
  }
  nlohmann::json devices = nlohmann::json::array();
  for (const HidDeviceRow& row : rows) {
    const HidDeviceInfo& info = row.info;
    devices.push_back({{"path", info.path},
                       {"vendor_id", info.vendor_id},
                       {"product_id", info.product_id},
                       {"serial", info.serial},
                       {"manufacturer", info.manufacturer},
                       {"product", info.product},
                       {"usage_page", info.usage_page},
                       {"usage", info.usage},
                       {"interface_number", info.interface_number},
                       {"profile", name_or_null(row.profile)},
                       {"binding", name_or_null(row.profile, "hid:")}});
  }
  nlohmann::json shipped = nlohmann::json::array();
  for (const DeviceProfile& profile : profiles) {
    shipped.push_back({{"name", profile.name},
                       {"model", profile.model},
                       {"binding", "hid:" + profile.name},
                       {"limits", device_limits_json(profile.limits, rate_Hz)}});
  }
  nlohmann::json others = nlohmann::json::array();
  for (const DeviceKindInfo& kind : kinds) {
    others.push_back({{"kind", kind.kind},
                      {"binding", kind.binding},
                      {"limits", device_limits_json(kind.limits, rate_Hz)}});
  }
  const nlohmann::json out = {{"version", 1},
                              {"hidapi", hidapi_version_string()},
                              {"profile_directory", profile_directory},
                              {"rate_Hz", rate_Hz},
                              {"devices", devices},
                              {"profiles", shipped},
                              {"kinds", others}};
  // Product names are the device's bytes: never let a stray one break the JSON.
  return out.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

std::string list_devices_json(const std::string& profile_directory,
                              const std::vector<DeviceKindInfo>& kinds, double rate_Hz) {
  const std::string directory = find_profile_directory(profile_directory);
  const std::vector<DeviceProfile> profiles = load_profiles(directory);
  return format_device_list_json(list_hid_devices(profiles), profiles, kinds, directory, rate_Hz);
}

std::unique_ptr<Device> make_hid_device(const std::string& args) {
  std::string bare;
  const DeviceOptions options = parse_device_options(args, "hid", bare);
  return make_hid_device(bare, options, make_hidapi_transport());
}

std::unique_ptr<Device> make_hid_device(const std::string& bare_profile,
                                        const DeviceOptions& options) {
  return make_hid_device(bare_profile, options, make_hidapi_transport());
}

std::unique_ptr<Device> make_hid_device(const std::string& bare_profile,
                                        const DeviceOptions& options,
                                        std::unique_ptr<HidTransport> transport) {
  check_device_options(
      options, "hid",
      {"profile", "profiles", "path", "serial", "mode", "gain", "range", "dead_zone", "home"});
  const auto get = [&](const char* key) {
    const auto found = options.find(key);
    return found == options.end() ? std::string() : found->second;
  };
  if (!bare_profile.empty() && options.count("profile") != 0) {
    throw std::invalid_argument("hid: the profile is given twice ('" + bare_profile +
                                "' and profile=" + get("profile") + ")");
  }

  DeviceProfile profile;
  const std::string wanted = bare_profile.empty() ? get("profile") : bare_profile;
  if (!wanted.empty() && (wanted.find('/') != std::string::npos ||
                          std::filesystem::path(wanted).extension() == ".json")) {
    profile = load_profile(wanted);
  } else {
    const std::vector<DeviceProfile> profiles =
        load_profiles(find_profile_directory(get("profiles")));
    const auto named = [&](const DeviceProfile& p) { return p.name == wanted; };
    if (!wanted.empty()) {
      const auto found = std::find_if(profiles.begin(), profiles.end(), named);
      if (found == profiles.end()) {
        std::string names;
        for (const DeviceProfile& p : profiles) names += (names.empty() ? "" : ", ") + p.name;
        throw std::invalid_argument("hid: no profile named '" + wanted + "' (shipped: " + names +
                                    ")");
      }
      profile = *found;
    } else {
      // The first connected device any profile matches (at the given path, if any).
      const std::string path = get("path");
      bool found = false;
      for (const HidDeviceRow& row : list_hid_devices(*transport, profiles)) {
        if (row.profile.empty() || (!path.empty() && row.info.path != path)) continue;
        profile = *std::find_if(profiles.begin(), profiles.end(),
                                [&](const DeviceProfile& p) { return p.name == row.profile; });
        found = true;
        break;
      }
      if (!found) {
        throw std::runtime_error(
            "hid: no connected HID device matches a shipped profile" +
            (path.empty() ? std::string() : " at " + path) +
            "; `hapticut-servo --list-devices` shows what is connected, profile=FILE.json "
            "describes another device");
      }
    }
  }

  HidDeviceOptions device_options = hid_device_options(profile);
  device_options.path = get("path");
  device_options.serial = get("serial");
  const std::string mode = get("mode");
  if (!mode.empty()) {
    if (mode != "rate" && mode != "position") {
      throw std::invalid_argument("hid: option 'mode=" + mode + "' must be rate or position");
    }
    device_options.mapping.rate_control = mode == "rate";
  }
  PoseMappingSettings& mapping = device_options.mapping;
  mapping.translation_gain_mm_per_s =
      device_option_number(options, "gain", mapping.translation_gain_mm_per_s, "hid");
  mapping.translation_range_mm =
      device_option_number(options, "range", mapping.translation_range_mm, "hid");
  mapping.dead_zone = device_option_number(options, "dead_zone", mapping.dead_zone, "hid");
  if (mapping.dead_zone < 0.0 || mapping.dead_zone > 0.9) {
    throw std::invalid_argument("hid: option 'dead_zone' must be in [0, 0.9]");
  }
  const std::string home = get("home");
  if (!home.empty()) {
    double xyz[3] = {0, 0, 0};
    char extra = 0;
    if (std::sscanf(home.c_str(), "%lf:%lf:%lf%c", &xyz[0], &xyz[1], &xyz[2], &extra) != 3) {
      throw std::invalid_argument("hid: option 'home=" + home + "' must be X:Y:Z in mm");
    }
    device_options.home.position_mm = {xyz[0], xyz[1], xyz[2]};
  }
  return std::make_unique<HidDevice>(std::move(transport), std::move(device_options));
}

}  // namespace hapticut::servo
