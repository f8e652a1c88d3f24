#include "devices/pose_mapping.h"

#include <algorithm>
#include <cmath>

namespace hapticut::servo {
namespace {

Vec3 dead_zone_vec(const Vec3& v, double dead_zone) {
  return {apply_dead_zone(v.x, dead_zone), apply_dead_zone(v.y, dead_zone),
          apply_dead_zone(v.z, dead_zone)};
}

Vec3 clamp_vec(const Vec3& v, const Vec3& low, const Vec3& high) {
  return {std::clamp(v.x, low.x, high.x), std::clamp(v.y, low.y, high.y),
          std::clamp(v.z, low.z, high.z)};
}

bool pressed(std::uint32_t now, std::uint32_t before, int index) {
  if (index < 0) return false;
  const std::uint32_t bit = 1U << index;
  return (now & bit) != 0U && (before & bit) == 0U;
}

}  // namespace

PoseMappingSettings mapping_settings_from(const DeviceProfile& profile) {
  PoseMappingSettings s;
  const MappingDefaults& d = profile.mapping;
  s.rate_control = d.rate_control;
  s.dead_zone = d.dead_zone;
  s.translation_gain_mm_per_s = d.translation_gain_mm_per_s;
  s.rotation_gain_rad_per_s = d.rotation_gain_rad_per_s;
  s.translation_range_mm = d.translation_range_mm;
  s.rotation_range_rad = d.rotation_range_rad;
  s.engage_button = d.engage_button;
  s.rehome_button = d.rehome_button;
  s.workspace_min_mm = profile.limits.workspace_min_mm;
  s.workspace_max_mm = profile.limits.workspace_max_mm;
  return s;
}

double apply_dead_zone(double value, double dead_zone) {
  const double magnitude = std::min(std::fabs(value), 1.0);
  if (magnitude <= dead_zone) return 0.0;
  return std::copysign((magnitude - dead_zone) / (1.0 - dead_zone), value);
}

Quaternion rotation_vector_quaternion(const Vec3& rotation_rad) {
  const double angle = norm(rotation_rad);
  if (angle < 1e-12) return {};
  const double s = std::sin(angle / 2) / angle;
  return {std::cos(angle / 2), rotation_rad.x * s, rotation_rad.y * s, rotation_rad.z * s};
}

PoseMapping::PoseMapping(const PoseMappingSettings& settings, const Pose& home)
    : settings_(settings) {
  set_home(home);
}

void PoseMapping::set_home(const Pose& home) {
  home_ = home;
  home_.position_mm =
      clamp_vec(home.position_mm, settings_.workspace_min_mm, settings_.workspace_max_mm);
  pose_ = home_;
  clutch_held_ = false;
}

std::uint32_t PoseMapping::buttons() const {
  return (last_buttons_ & 0xffffU) | (engage_requested_ ? kEngageRequestBit : 0U);
}

const Pose& PoseMapping::update(const Vec3& translation, const Vec3& rotation,
                                std::uint32_t buttons, double dt_s) {
  if (pressed(buttons, last_buttons_, settings_.engage_button)) {
    engage_requested_ = !engage_requested_;
  }
  const bool rehome = pressed(buttons, last_buttons_, settings_.rehome_button);
  last_buttons_ = buttons;
  if (rehome) {
    // Rate control: back to the home pose. Position control: the pose now
    // held becomes the home and stays until the puck is let go (a clutch:
    // the next push moves on from here).
    if (settings_.rate_control) {
      pose_ = home_;
    } else {
      home_ = pose_;
      clutch_held_ = true;
    }
  }

  // A non-finite deflection or time step moves nothing.
  const bool finite = is_finite(translation) && is_finite(rotation) && std::isfinite(dt_s);
  const double dt = finite ? std::clamp(dt_s, 0.0, 0.1) : 0.0;
  const Vec3 t = finite ? dead_zone_vec(translation, settings_.dead_zone) : Vec3{};
  const Vec3 r = finite ? dead_zone_vec(rotation, settings_.dead_zone) : Vec3{};

  if (settings_.rate_control) {
    // Rotation rates are about the tool's own axes (a twist of the puck
    // turns the blade about itself).
    pose_.position_mm =
        clamp_vec(pose_.position_mm + t * (settings_.translation_gain_mm_per_s * dt),
                  settings_.workspace_min_mm, settings_.workspace_max_mm);
    const Quaternion turn =
        rotation_vector_quaternion(r * (settings_.rotation_gain_rad_per_s * dt));
    pose_.rotation = multiply(pose_.rotation, turn).normalized();
  } else {
    if (clutch_held_ && (t != Vec3{} || r != Vec3{})) return pose_;
    clutch_held_ = false;
    pose_.position_mm = clamp_vec(home_.position_mm + t * settings_.translation_range_mm,
                                  settings_.workspace_min_mm, settings_.workspace_max_mm);
    pose_.rotation =
        multiply(home_.rotation, rotation_vector_quaternion(r * settings_.rotation_range_rad))
            .normalized();
  }
  return pose_;
}

}  // namespace hapticut::servo
