#include "devices/profile.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace hapticut::servo {
namespace {

using nlohmann::json;

// A JSON value and the pointer that leads to it, so every error names its field.
struct Field {
  const json& value;
  std::string pointer;
  const std::string& source;

  [[noreturn]] void fail(const std::string& reason) const {
    throw ProfileError(source + ": " + (pointer.empty() ? "/" : pointer) + ": " + reason);
  }
  bool has(const char* key) const { return value.is_object() && value.contains(key); }
  Field at(const char* key) const {
    if (!value.is_object()) fail("must be an object");
    if (!value.contains(key)) Field{value, pointer + "/" + key, source}.fail("missing");
    return {value.at(key), pointer + "/" + key, source};
  }
  Field at(std::size_t index) const {
    return {value.at(index), pointer + "/" + std::to_string(index), source};
  }
  const json::array_t& array() const {
    if (!value.is_array()) fail("must be an array");
    return value.get_ref<const json::array_t&>();
  }
  double number() const {
    if (!value.is_number()) fail("must be a number");
    const double result = value.get<double>();
    if (!std::isfinite(result)) fail("must be finite");
    return result;
  }
  double number(double min, double max) const {
    const double result = number();
    if (result < min || result > max) {
      std::ostringstream reason;
      reason << "must be in [" << min << ", " << max << "], is " << result;
      fail(reason.str());
    }
    return result;
  }
  int integer(long long min, long long max) const {
    if (!value.is_number_integer()) fail("must be an integer");
    const long long result = value.get<long long>();
    if (result < min || result > max) {
      fail("must be in [" + std::to_string(min) + ", " + std::to_string(max) + "], is " +
           std::to_string(result));
    }
    return static_cast<int>(result);
  }
  bool boolean() const {
    if (!value.is_boolean()) fail("must be true or false");
    return value.get<bool>();
  }
  std::string string() const {
    if (!value.is_string()) fail("must be a string");
    return value.get<std::string>();
  }
  // "0x046d" or 1133.
  std::uint16_t id16() const {
    if (value.is_number_integer()) return static_cast<std::uint16_t>(integer(0, 0xffff));
    const std::string text = string();
    char* end = nullptr;
    const unsigned long parsed = std::strtoul(text.c_str(), &end, 0);
    if (text.empty() || *end != '\0' || parsed > 0xffff)
      fail("must be a 16-bit id like \"0x046d\"");
    return static_cast<std::uint16_t>(parsed);
  }
  void only_keys(std::initializer_list<const char*> keys) const {
    if (!value.is_object()) fail("must be an object");
    for (const auto& item : value.items()) {
      const std::string& key = item.key();
      if (std::none_of(keys.begin(), keys.end(), [&](const char* k) { return key == k; })) {
        Field{item.value(), pointer + "/" + key, source}.fail("unknown field");
      }
    }
  }
};

template <typename Enum, std::size_t N>
Enum enum_from(const Field& field, const std::array<const char*, N>& names) {
  const std::string text = field.string();
  for (std::size_t i = 0; i < N; ++i) {
    if (text == names[i]) return static_cast<Enum>(i);
  }
  std::string expected;
  for (const char* name : names) expected += std::string(expected.empty() ? "" : ", ") + name;
  field.fail("\"" + text + "\" is not one of " + expected);
}

constexpr std::array<const char*, 6> kAxisNames{"x", "y", "z", "rx", "ry", "rz"};
constexpr std::array<const char*, 6> kComponentNames{"fx", "fy", "fz", "tx", "ty", "tz"};

ReportField parse_report_field(const Field& f, int report_length, double default_scale) {
  ReportField out;
  out.byte_offset = f.at("byte_offset").integer(0, 63);
  out.width_bytes = f.at("width").integer(1, 4);
  if (out.width_bytes == 3) f.at("width").fail("must be 1, 2 or 4 bytes");
  if (out.byte_offset + out.width_bytes > report_length) {
    f.at("byte_offset")
        .fail("field ends at byte " + std::to_string(out.byte_offset + out.width_bytes) +
              ", past the report's length " + std::to_string(report_length));
  }
  out.is_signed = f.has("signed") ? f.at("signed").boolean() : true;
  out.little_endian =
      f.has("endian")
          ? enum_from<int>(f.at("endian"), std::array<const char*, 2>{"big", "little"}) == 1
          : true;
  const double width_max = std::ldexp(1.0, 8 * out.width_bytes);
  const double raw_min = out.is_signed ? -width_max / 2 : 0.0;
  const double raw_max = out.is_signed ? width_max / 2 - 1 : width_max - 1;
  out.logical_min = f.at("logical_min").number(raw_min, raw_max);
  out.logical_max = f.at("logical_max").number(raw_min, raw_max);
  if (out.logical_max <= out.logical_min) f.at("logical_max").fail("must exceed logical_min");
  out.scale = f.has("scale") ? f.at("scale").number() : default_scale;
  if (out.scale == 0.0) f.at("scale").fail("must not be 0");
  return out;
}

std::array<std::array<double, 3>, 3> parse_matrix(const Field& f) {
  std::array<std::array<double, 3>, 3> m{};
  if (f.array().size() != 3) f.fail("must be 3 rows of 3 numbers");
  for (std::size_t r = 0; r < 3; ++r) {
    const Field row = f.at(r);
    if (row.array().size() != 3) row.fail("must be 3 numbers");
    for (std::size_t c = 0; c < 3; ++c) m[r][c] = row.at(c).number(-1e6, 1e6);
  }
  return m;
}

InputReport parse_input_report(const Field& f) {
  f.only_keys({"report_id", "length", "accept_longer", "axes", "buttons", "comment"});
  InputReport report;
  report.report_id = f.at("report_id").integer(0, 255);
  report.length = f.at("length").integer(1, 64);
  if (f.has("accept_longer")) report.accept_longer = f.at("accept_longer").boolean();
  if (f.has("axes")) {
    const Field axes = f.at("axes");
    for (std::size_t i = 0; i < axes.array().size(); ++i) {
      const Field a = axes.at(i);
      a.only_keys({"axis", "byte_offset", "width", "signed", "endian", "logical_min", "logical_max",
                   "scale"});
      AxisField axis;
      axis.axis = enum_from<DeviceAxis>(a.at("axis"), kAxisNames);
      axis.field = parse_report_field(a, report.length, 1.0);
      report.axes.push_back(axis);
    }
  }
  if (f.has("buttons")) {
    const Field buttons = f.at("buttons");
    for (std::size_t i = 0; i < buttons.array().size(); ++i) {
      const Field b = buttons.at(i);
      b.only_keys({"byte_offset", "bit", "index", "name"});
      ButtonBit button;
      button.byte_offset = b.at("byte_offset").integer(0, report.length - 1);
      button.bit = b.at("bit").integer(0, 7);
      button.index = b.at("index").integer(0, 15);
      report.buttons.push_back(button);
    }
  }
  if (report.axes.empty() && report.buttons.empty()) f.fail("has neither axes nor buttons");
  return report;
}

DeviceProfile parse(const json& document, const std::string& source) {
  const Field root{document, "", source};
  root.only_keys(
      {"$schema", "name", "model", "comment", "match", "input", "output", "mapping", "limits"});
  DeviceProfile p;
  p.source = source;
  p.name = root.at("name").string();
  p.model = root.at("model").string();

  const Field m = root.at("match");
  m.only_keys({"vendor_id", "product_ids", "serial", "interface", "usage_page"});
  p.match.vendor_id = m.at("vendor_id").id16();
  const Field ids = m.at("product_ids");
  if (ids.array().empty()) ids.fail("must list at least one product id");
  for (std::size_t i = 0; i < ids.array().size(); ++i)
    p.match.product_ids.push_back(ids.at(i).id16());
  if (m.has("serial")) p.match.serial = m.at("serial").string();
  if (m.has("interface")) p.match.interface_number = m.at("interface").integer(0, 255);
  if (m.has("usage_page")) p.match.usage_page = m.at("usage_page").id16();

  const Field in = root.at("input");
  in.only_keys({"kind", "reports", "translation_matrix", "rotation_matrix"});
  p.input.kind =
      enum_from<InputKind>(in.at("kind"), std::array<const char*, 2>{"deflection", "position"});
  const Field reports = in.at("reports");
  if (reports.array().empty()) reports.fail("must describe at least one report");
  for (std::size_t i = 0; i < reports.array().size(); ++i) {
    InputReport report = parse_input_report(reports.at(i));
    for (const InputReport& other : p.input.reports) {
      if (other.report_id == report.report_id && other.length == report.length) {
        reports.at(i).fail("a report with id " + std::to_string(report.report_id) + " and length " +
                           std::to_string(report.length) + " is already described");
      }
    }
    p.input.reports.push_back(std::move(report));
  }
  if (in.has("translation_matrix"))
    p.input.translation_matrix = parse_matrix(in.at("translation_matrix"));
  if (in.has("rotation_matrix")) p.input.rotation_matrix = parse_matrix(in.at("rotation_matrix"));

  const Field out = root.at("output");
  if (out.value.is_string()) {
    if (out.string() != "none") out.fail("must be \"none\" or an output report");
  } else {
    out.only_keys({"report_id", "length", "fields", "comment"});
    p.output.has_report = true;
    p.output.report_id = out.at("report_id").integer(0, 255);
    p.output.length = out.at("length").integer(1, 64);
    const Field fields = out.at("fields");
    if (fields.array().empty()) fields.fail("must list at least one field");
    for (std::size_t i = 0; i < fields.array().size(); ++i) {
      const Field f = fields.at(i);
      f.only_keys({"component", "byte_offset", "width", "signed", "endian", "logical_min",
                   "logical_max", "scale"});
      OutputField field;
      field.component = enum_from<OutputComponent>(f.at("component"), kComponentNames);
      field.field = parse_report_field(f, p.output.length, 1.0);
      if (p.output.report_id != 0 && field.field.byte_offset == 0) {
        f.at("byte_offset").fail("byte 0 holds the report id");
      }
      p.output.fields.push_back(field);
    }
  }

  if (root.has("mapping")) {
    const Field map = root.at("mapping");
    map.only_keys({"mode", "dead_zone", "translation_gain_mm_per_s", "rotation_gain_rad_per_s",
                   "translation_range_mm", "rotation_range_rad", "engage_button", "rehome_button"});
    MappingDefaults& d = p.mapping;
    if (map.has("mode")) {
      d.rate_control =
          enum_from<int>(map.at("mode"), std::array<const char*, 2>{"position", "rate"}) == 1;
    }
    if (map.has("dead_zone")) d.dead_zone = map.at("dead_zone").number(0.0, 0.9);
    if (map.has("translation_gain_mm_per_s")) {
      d.translation_gain_mm_per_s = map.at("translation_gain_mm_per_s").number(0.0, 1e4);
    }
    if (map.has("rotation_gain_rad_per_s")) {
      d.rotation_gain_rad_per_s = map.at("rotation_gain_rad_per_s").number(0.0, 100.0);
    }
    if (map.has("translation_range_mm")) {
      d.translation_range_mm = map.at("translation_range_mm").number(0.0, 1e4);
    }
    if (map.has("rotation_range_rad"))
      d.rotation_range_rad = map.at("rotation_range_rad").number(0.0, 3.2);
    if (map.has("engage_button")) d.engage_button = map.at("engage_button").integer(-1, 15);
    if (map.has("rehome_button")) d.rehome_button = map.at("rehome_button").integer(-1, 15);
  }

  const Field lim = root.at("limits");
  lim.only_keys({"max_force_N", "max_torque_N_mm", "max_stiffness_N_per_mm", "workspace_min_mm",
                 "workspace_max_mm"});
  p.limits.has_force_output = p.output.has_report;
  p.limits.max_force_N = lim.at("max_force_N").number(0.0, 100.0);
  p.limits.max_torque_N_mm = lim.at("max_torque_N_mm").number(0.0, 1e5);
  p.limits.max_stiffness_N_per_mm = lim.at("max_stiffness_N_per_mm").number(0.0, 100.0);
  if (p.output.has_report && p.limits.max_force_N <= 0.0) {
    lim.at("max_force_N").fail("must be positive for a device with force output");
  }
  const auto vec = [](const Field& f) {
    if (f.array().size() != 3) f.fail("must be 3 numbers (mm)");
    return Vec3{f.at(std::size_t{0}).number(), f.at(1).number(), f.at(2).number()};
  };
  p.limits.workspace_min_mm = vec(lim.at("workspace_min_mm"));
  p.limits.workspace_max_mm = vec(lim.at("workspace_max_mm"));
  for (int i = 0; i < 3; ++i) {
    if (p.limits.workspace_max_mm[i] <= p.limits.workspace_min_mm[i]) {
      lim.at("workspace_max_mm")
          .at(static_cast<std::size_t>(i))
          .fail("must exceed workspace_min_mm");
    }
  }
  return p;
}

std::string executable_directory() {
  std::error_code error;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", error);
  return error ? std::string() : exe.parent_path().string();
}

}  // namespace

DeviceProfile parse_profile(const std::string& json_text, const std::string& source) {
  json document;
  try {
    document = json::parse(json_text);
  } catch (const json::parse_error& error) {
    throw ProfileError(source + ": not JSON (" + error.what() + ")");
  }
  return parse(document, source);
}

DeviceProfile load_profile(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw ProfileError(path + ": cannot open the profile");
  std::ostringstream text;
  text << file.rdbuf();
  return parse_profile(text.str(), path);
}

std::vector<DeviceProfile> load_profiles(const std::string& directory) {
  std::vector<std::string> paths;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(directory, error)) {
    if (entry.path().extension() == ".json") paths.push_back(entry.path().string());
  }
  if (error)
    throw ProfileError(directory + ": cannot list the profile directory (" + error.message() + ")");
  std::sort(paths.begin(), paths.end());
  std::vector<DeviceProfile> profiles;
  profiles.reserve(paths.size());
  for (const std::string& path : paths) profiles.push_back(load_profile(path));
  return profiles;
}

std::string find_profile_directory(const std::string& explicit_directory) {
  std::vector<std::string> candidates;
  if (!explicit_directory.empty()) {
    candidates.push_back(explicit_directory);
  } else {
    if (const char* env = std::getenv("HAPTICUT_PROFILE_DIR"); env != nullptr && *env != '\0') {
      candidates.emplace_back(env);
    }
    const std::string exe = executable_directory();
    if (!exe.empty()) {
      candidates.push_back(exe + "/devices/profiles");     // hapticut/hapticut-servo
      candidates.push_back(exe + "/../devices/profiles");  // hapticut/bin/hapticut-servo
    }
#ifdef HAPTICUT_SOURCE_PROFILE_DIR
    candidates.emplace_back(HAPTICUT_SOURCE_PROFILE_DIR);
#endif
  }
  std::string looked;
  for (const std::string& candidate : candidates) {
    if (std::filesystem::is_directory(candidate)) return candidate;
    looked += (looked.empty() ? "" : ", ") + candidate;
  }
  throw ProfileError("no device profile directory (looked in " + looked +
                     "; pass profiles=DIR or set HAPTICUT_PROFILE_DIR)");
}

bool profile_matches(const DeviceProfile& profile, const HidInterfaceId& id) {
  const ProfileMatch& m = profile.match;
  if (id.vendor_id != m.vendor_id) return false;
  if (std::find(m.product_ids.begin(), m.product_ids.end(), id.product_id) == m.product_ids.end()) {
    return false;
  }
  if (m.serial && *m.serial != id.serial) return false;
  if (m.interface_number && *m.interface_number != id.interface_number) return false;
  if (m.usage_page && *m.usage_page != id.usage_page) return false;
  return true;
}

}  // namespace hapticut::servo
