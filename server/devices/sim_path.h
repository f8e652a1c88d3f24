// SimPath: the scripted tool path the sim device follows, timestamped poses
// with linear interpolation (positions) and normalised linear interpolation
// (rotations). From a JSON file or built in.
//
// File: {"poses": [[t_s, x_mm, y_mm, z_mm, qw, qx, qy, qz], ...]}, times
// strictly increasing from any start (shifted to begin at 0).
// Built-in strokes, placed from the scene's bounding box (centre c, size e):
//   press-slide  down from c + (0, 0, 0.45 e_z) to c + (0, 0, 0.05 e_z), then
//                across to c + (0, 0.45 e_y, 0.05 e_z)  (the default)
//   press        only the downward part
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "hapticut/pose.h"

namespace hapticut::servo {

// The largest sim path file read (some 160 000 poses): it is read whole, on
// the thread that loads the scene.
inline constexpr std::uint64_t kMaxSimPathBytes = 16ULL << 20;

class SimPath {
 public:
  struct Key {
    double time_s;
    Pose pose;
  };

  // Throws DeviceError naming the file and the entry that is wrong, never
  // quoting its content. A regular file of at most kMaxSimPathBytes only.
  static SimPath from_file(const std::string& path);
  // Throws DeviceError for an unknown name.
  static SimPath builtin(const std::string& name, const Vec3& scene_min_mm,
                         const Vec3& scene_max_mm, double speed_mm_per_s);
  static const char* builtin_names() { return "press-slide, press"; }

  Pose at(double time_s) const;
  double duration_s() const { return keys_.back().time_s; }
  const std::vector<Key>& keys() const { return keys_; }

 private:
  explicit SimPath(std::vector<Key> keys) : keys_(std::move(keys)) {}
  std::vector<Key> keys_;
};

}  // namespace hapticut::servo
