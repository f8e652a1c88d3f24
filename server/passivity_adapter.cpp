#include "passivity_adapter.h"

#include <algorithm>

namespace hapticut::servo {

std::unique_ptr<PassivityController> make_passivity_controller(double link_delay_s,
                                                               double rate_Hz) {
  PassivitySettings settings;
  settings.link_delay_ticks =
      std::clamp(link_delay_s * rate_Hz, 0.0, HannafordRyuPassivity::kMaxLinkDelayTicks);
  return std::make_unique<HannafordRyuController>(settings);
}

}  // namespace hapticut::servo
