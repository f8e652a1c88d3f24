// The devices of server/devices wired into the servo: their rows in the
// device table, their errors as DeviceError naming the binding, their limits
// in the safety clamp, and the Hannaford-Ryu controller in the safety layer.
#include <gtest/gtest.h>

#include <string>

#include "devices/device_factory.h"
#include "passivity.h"
#include "safety.h"

namespace hapticut::servo {
namespace {

std::string error_of(const std::string& text) {
  try {
    make_device(parse_device_spec(text), DeviceContext{});
  } catch (const DeviceError& e) {
    return e.what();
  }
  return "";
}

TEST(DeviceWiring, HidAndBridgeAreKinds) {
  EXPECT_NE(device_usage().find("hid:"), std::string::npos);
  EXPECT_NE(device_usage().find("bridge:"), std::string::npos);
  const std::string unknown = error_of("warp:9");
  EXPECT_NE(unknown.find("known: sim, replay, viewport, hid, bridge"), std::string::npos);
}

TEST(DeviceWiring, DeviceFactoryErrorsNameTheBinding) {
  const std::string hid = error_of("scalpel=hid:no-such-profile");
  EXPECT_NE(hid.find("device 'scalpel=hid:no-such-profile'"), std::string::npos) << hid;
  EXPECT_NE(hid.find("no profile named"), std::string::npos) << hid;
  const std::string bridge = error_of("scalpel=bridge:max_force=-1");
  EXPECT_NE(bridge.find("device 'scalpel=bridge:max_force=-1'"), std::string::npos) << bridge;
  EXPECT_NE(error_of("bridge:stray").find("'stray' is not key=value"), std::string::npos);
}

TEST(DeviceWiring, BridgeLimitsReachTheClamp) {
  const auto device = make_device(parse_device_spec("bridge:port=0,max_force=0.5"), {});
  ASSERT_TRUE(device->limits().has_force_output);
  SafetySettings request;
  request.max_force_N = 5.0;
  request.ramp_time_s = 0.0;
  SafetyChannel channel(request, device->limits());
  EXPECT_EQ(channel.settings().max_force_N, 0.5);
  channel.restart();
  DeviceSample sample;
  sample.time_s = 1.0;
  sample.sequence = 1;
  ASSERT_TRUE(channel.admit(DeviceStatus::Fresh, sample));
  const SafetyOutput out = channel.render({2, 0, 0}, {}, true, 1e-3, true, false);
  EXPECT_NEAR(norm(out.force_N), 0.5, 1e-12);
  EXPECT_TRUE(out.flags & kSafetyForceClamped);
}

TEST(DeviceWiring, PassivityAdapterDampsEnergyTheLoopWouldGive) {
  // A force pushing the hand along its own motion gives it energy: the
  // controller takes it out and the safety layer flags it.
  DeviceLimits limits;
  limits.has_force_output = true;
  limits.max_force_N = 10.0;
  SafetySettings request;
  request.ramp_time_s = 0.0;
  SafetyChannel channel(request, limits);
  channel.set_passivity(make_passivity_controller(0.0, 1000.0));
  channel.restart();
  bool damped = false;
  for (int k = 0; k < 20; ++k) {
    DeviceSample sample;
    sample.pose.position_mm = {0.1 * k, 0, 0};  // Moving +x at 100 mm/s.
    sample.time_s = 1e-3 * k;
    sample.sequence = static_cast<std::uint64_t>(k) + 1;
    ASSERT_TRUE(channel.admit(DeviceStatus::Fresh, sample));
    const SafetyOutput out = channel.render({1, 0, 0}, {}, true, 1e-3, true, false);
    if (out.flags & kSafetyPassivity) {
      damped = true;
      EXPECT_LT(out.force_N.x, 1.0);
    }
  }
  EXPECT_TRUE(damped);
}

}  // namespace
}  // namespace hapticut::servo
