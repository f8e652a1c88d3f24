// The devices' Hannaford-Ryu passivity controller (devices/passivity.h) behind
// the safety layer's hook (passivity_hook.h). Session plugs one into every
// device with force output unless --no-passivity.
#pragma once

#include <memory>

#include "devices/passivity.h"
#include "passivity_hook.h"

namespace hapticut::servo {

class HannafordRyuController final : public PassivityController {
 public:
  explicit HannafordRyuController(const PassivitySettings& settings) : controller_(settings) {}

  Vec3 observe(const Vec3& force_N, const Vec3& velocity_mm_per_s, double dt_s) override {
    return controller_.observe(force_N, velocity_mm_per_s, dt_s);
  }
  void reset() override { controller_.reset(); }
  const HannafordRyuPassivity& controller() const { return controller_; }

 private:
  HannafordRyuPassivity controller_;
};

// link_delay_s: the device link's delay beyond the one-tick hold (0 for a
// local device), turned into ticks at rate_Hz and capped at the controller's maximum.
std::unique_ptr<PassivityController> make_passivity_controller(double link_delay_s, double rate_Hz);

}  // namespace hapticut::servo
