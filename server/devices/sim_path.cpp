#include "devices/sim_path.h"

#include <algorithm>
#include <cmath>

#include "client_files.h"
#include "devices/device_args.h"
#include "hapticut/scene_io.h"
#include "hapticut/scene_tree.h"

namespace hapticut::servo {

SimPath SimPath::from_file(const std::string& path) {
  // The file rules of every path the servo opens (client_files.h): a regular
  // file, opened without waiting, of bounded size; the strict decoder, whose
  // errors never quote the file.
  SceneTree doc;
  try {
    doc = decode_scene_tree(read_regular_file(path, kMaxSimPathBytes), SceneEncoding::Json);
  } catch (const FileRefused& e) {
    throw DeviceError(std::string("sim path ") + e.what());
  } catch (const SceneError& e) {
    throw DeviceError("sim path '" + path + "': not JSON (" + e.what() + ")");
  }
  if (!doc.is_object() || !doc.contains("poses") || !doc["poses"].is_array() ||
      doc["poses"].empty()) {
    throw DeviceError("sim path '" + path + "': /poses: expected a non-empty array");
  }
  std::vector<Key> keys;
  const auto& poses = doc["poses"];
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const std::string where = "sim path '" + path + "': /poses/" + std::to_string(i);
    const auto& row = poses[i];
    if (!row.is_array() || row.size() != 8) {
      throw DeviceError(where + ": expected [t_s, x, y, z, qw, qx, qy, qz]");
    }
    double v[8];
    for (int j = 0; j < 8; ++j) {
      if (!row[j].is_number() || !std::isfinite(row[j].get<double>())) {
        throw DeviceError(where + "/" + std::to_string(j) + ": not a finite number");
      }
      v[j] = row[j].get<double>();
    }
    if (!keys.empty() && !(v[0] > keys.back().time_s)) {
      throw DeviceError(where + "/0: times must increase");
    }
    const Quaternion r = Quaternion{v[4], v[5], v[6], v[7]};
    if (!(r.w * r.w + r.x * r.x + r.y * r.y + r.z * r.z > 0.0)) {
      throw DeviceError(where + ": zero rotation quaternion");
    }
    keys.push_back({v[0], {{v[1], v[2], v[3]}, r.normalized()}});
  }
  const double t0 = keys.front().time_s;
  for (Key& k : keys) k.time_s -= t0;
  return SimPath(std::move(keys));
}

SimPath SimPath::builtin(const std::string& name, const Vec3& lo, const Vec3& hi,
                         double speed_mm_per_s) {
  if (!(speed_mm_per_s > 0.0)) throw DeviceError("sim: speed must be positive");
  const Vec3 c = (lo + hi) * 0.5;
  const Vec3 e = hi - lo;
  const Vec3 top = c + Vec3{0, 0, 0.45 * e.z};
  const Vec3 pressed = c + Vec3{0, 0, 0.05 * e.z};
  const Vec3 across = c + Vec3{0, 0.45 * e.y, 0.05 * e.z};
  std::vector<Vec3> points;
  if (name == "press-slide") {
    points = {top, pressed, across};
  } else if (name == "press") {
    points = {top, pressed};
  } else {
    throw DeviceError("sim: unknown built-in stroke '" + name + "' (known: " + builtin_names() +
                      ")");
  }
  std::vector<Key> keys;
  double t = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (i > 0) t += std::max(1e-3, norm(points[i] - points[i - 1]) / speed_mm_per_s);
    keys.push_back({t, {points[i], {}}});
  }
  return SimPath(std::move(keys));
}

Pose SimPath::at(double time_s) const {
  if (!(time_s > keys_.front().time_s)) return keys_.front().pose;
  if (time_s >= keys_.back().time_s) return keys_.back().pose;
  const auto next = std::upper_bound(keys_.begin(), keys_.end(), time_s,
                                     [](double t, const Key& k) { return t < k.time_s; });
  const Key& b = *next;
  const Key& a = *(next - 1);
  const double s = (time_s - a.time_s) / (b.time_s - a.time_s);
  return {a.pose.position_mm + (b.pose.position_mm - a.pose.position_mm) * s,
          nlerp(a.pose.rotation, b.pose.rotation, s)};
}

}  // namespace hapticut::servo
