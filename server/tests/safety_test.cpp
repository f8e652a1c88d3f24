// The safety layer alone: clamp, ramp, watchdog, NaN guard, engage, the
// passivity hook, and zero force in the tick of every fault.
#include "safety.h"

#include <gtest/gtest.h>

#include <limits>

namespace hapticut::servo {
namespace {

DeviceLimits haptic_limits() {
  DeviceLimits limits;
  limits.has_force_output = true;
  limits.max_force_N = 8.0;
  limits.max_torque_N_mm = 100.0;
  return limits;
}

SafetySettings settings(double ramp_s = 0.0) {
  SafetySettings s;
  s.max_force_N = 5.0;
  s.max_torque_N_mm = 1000.0;  // Above the device's: the device's wins.
  s.ramp_time_s = ramp_s;
  s.watchdog_ticks = 3;
  return s;
}

DeviceSample sample_at(double x, double t, std::uint64_t sequence) {
  DeviceSample s;
  s.pose.position_mm = {x, 0, 0};
  s.time_s = t;
  s.sequence = sequence;
  return s;
}

// One tick with a fresh sample; returns the output.
SafetyOutput tick(SafetyChannel& channel, const Vec3& force, bool engaged = true,
                  DeviceStatus status = DeviceStatus::Fresh, double x = 0.0) {
  static std::uint64_t sequence = 0;
  const DeviceSample s = sample_at(x, double(++sequence) * 1e-3, sequence);
  const bool ok = channel.admit(status, s);
  return channel.render(force, Vec3{1, 0, 0}, ok, 1e-3, engaged, false);
}

TEST(Safety, LimitsAreTheLowerOfDeviceAndRequest) {
  const SafetySettings s = limit_to_device(settings(), haptic_limits());
  EXPECT_EQ(s.max_force_N, 5.0);
  EXPECT_EQ(s.max_torque_N_mm, 100.0);
}

TEST(Safety, ClampKeepsDirection) {
  SafetyChannel channel(settings(), haptic_limits());
  channel.restart();
  const SafetyOutput out = tick(channel, Vec3{30, 40, 0});
  EXPECT_NEAR(norm(out.force_N), 5.0, 1e-12);
  EXPECT_NEAR(out.force_N.x / out.force_N.y, 0.75, 1e-12);
  EXPECT_TRUE(out.flags & kSafetyForceClamped);
  EXPECT_TRUE(out.events & kSafetyForceClamped);
}

TEST(Safety, RampRisesLinearlyFromZero) {
  SafetyChannel channel(settings(0.01), haptic_limits());  // 10 ticks of 1 ms.
  channel.restart();
  const SafetyOutput first = tick(channel, Vec3{1, 0, 0});
  EXPECT_NEAR(first.force_N.x, 0.1, 1e-12);
  EXPECT_TRUE(first.flags & kSafetyRamping);
  SafetyOutput out;
  for (int i = 0; i < 20; ++i) out = tick(channel, Vec3{1, 0, 0});
  EXPECT_EQ(out.force_N.x, 1.0);
  EXPECT_FALSE(out.flags & kSafetyRamping);
}

TEST(Safety, NoForceUntilEngagedThenRamp) {
  SafetyChannel channel(settings(0.01), haptic_limits());
  channel.restart();
  EXPECT_EQ(norm(tick(channel, Vec3{1, 0, 0}, false).force_N), 0.0);
  const SafetyOutput engaged = tick(channel, Vec3{1, 0, 0}, true);
  EXPECT_TRUE(engaged.events & kSafetyEngaged);
  EXPECT_NEAR(engaged.force_N.x, 0.1, 1e-12);  // Ramps from zero at engage.
}

TEST(Safety, EngageButton) {
  SafetySettings s = settings();
  s.engage_buttons = 2;
  SafetyChannel channel(s, haptic_limits());
  channel.restart();
  DeviceSample sample = sample_at(0, 0.001, 1);
  sample.buttons = 2;
  ASSERT_TRUE(channel.admit(DeviceStatus::Fresh, sample));
  EXPECT_EQ(channel.render(Vec3{1, 0, 0}, Vec3{}, true, 1e-3, false, false).force_N.x, 1.0);
  sample.buttons = 1;
  sample.sequence = 2;
  ASSERT_TRUE(channel.admit(DeviceStatus::Fresh, sample));
  EXPECT_EQ(channel.render(Vec3{1, 0, 0}, Vec3{}, true, 1e-3, false, false).force_N.x, 0.0);
}

TEST(Safety, WatchdogZeroesTheForceAfterNStaleTicks) {
  SafetyChannel channel(settings(), haptic_limits());
  channel.restart();
  const DeviceSample s = sample_at(0, 0.001, 1);
  ASSERT_TRUE(channel.admit(DeviceStatus::Fresh, s));
  channel.render(Vec3{1, 0, 0}, Vec3{}, true, 1e-3, true, false);
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(channel.admit(DeviceStatus::Stale, s));
    EXPECT_EQ(channel.render(Vec3{1, 0, 0}, Vec3{}, true, 1e-3, true, false).force_N.x, 1.0);
  }
  EXPECT_FALSE(channel.admit(DeviceStatus::Stale, s));
  const SafetyOutput out = channel.render(Vec3{1, 0, 0}, Vec3{}, false, 1e-3, true, false);
  EXPECT_EQ(norm(out.force_N), 0.0);
  EXPECT_TRUE(out.events & kSafetyWatchdog);
  EXPECT_EQ(channel.fault_count(), 1U);
}

TEST(Safety, NonFinitePoseIsAFaultInTheSameTick) {
  SafetyChannel channel(settings(0.01), haptic_limits());
  channel.restart();
  for (int i = 0; i < 20; ++i) tick(channel, Vec3{1, 0, 0});
  const SafetyOutput bad = tick(channel, Vec3{1, 0, 0}, true, DeviceStatus::Fresh,
                                std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(norm(bad.force_N), 0.0);
  EXPECT_TRUE(bad.events & kSafetyNonFinitePose);
  // Recovery ramps from zero again.
  EXPECT_NEAR(tick(channel, Vec3{1, 0, 0}).force_N.x, 0.1, 1e-12);
}

TEST(Safety, NonFiniteEngineForceIsAFault) {
  SafetyChannel channel(settings(), haptic_limits());
  channel.restart();
  const SafetyOutput out = tick(channel, Vec3{std::numeric_limits<double>::infinity(), 0, 0});
  EXPECT_EQ(norm(out.force_N), 0.0);
  EXPECT_TRUE(out.flags & kSafetyNonFiniteForce);
}

TEST(Safety, LostDeviceIsAFaultOnlyAfterAFirstSample) {
  SafetyChannel channel(settings(), haptic_limits());
  channel.restart();
  const DeviceSample s;
  EXPECT_FALSE(channel.admit(DeviceStatus::Lost, s));
  SafetyOutput out = channel.render(Vec3{}, Vec3{}, false, 1e-3, true, false);
  EXPECT_TRUE(out.flags & kSafetyWaiting);
  EXPECT_EQ(channel.fault_count(), 0U);
  tick(channel, Vec3{1, 0, 0});
  EXPECT_FALSE(channel.admit(DeviceStatus::Lost, s));
  out = channel.render(Vec3{1, 0, 0}, Vec3{}, false, 1e-3, true, false);
  EXPECT_EQ(norm(out.force_N), 0.0);
  EXPECT_TRUE(out.events & kSafetyDeviceLost);
}

TEST(Safety, ALateTickIsAFaultAndTheForceRampsBackIn) {
  SafetyChannel channel(settings(0.01), haptic_limits());
  channel.restart();
  for (int i = 0; i < 20; ++i) tick(channel, Vec3{1, 0, 0});
  ASSERT_NEAR(norm(tick(channel, Vec3{1, 0, 0}).force_N), 1.0, 1e-12);
  // The gap since the last tick is longer than the watchdog time: no step, zero force.
  const SafetySettings& s = channel.settings();
  EXPECT_FALSE(channel.admit(DeviceStatus::Fresh, sample_at(0, 5.0, 1000), s.late_tick_s * 2));
  SafetyOutput out = channel.render(Vec3{1, 0, 0}, Vec3{}, false, 2.0, true, false);
  EXPECT_EQ(norm(out.force_N), 0.0);
  EXPECT_EQ(out.ramp, 0.0);
  EXPECT_TRUE(out.events & kSafetyLateTick);
  EXPECT_EQ(channel.fault_count(), 1U);
  // Then it ramps back in from zero, one period at a time.
  out = tick(channel, Vec3{1, 0, 0});
  EXPECT_NEAR(out.ramp, 0.1, 1e-12);
  EXPECT_NEAR(norm(out.force_N), 0.1, 1e-12);
}

TEST(Safety, ASampleSpanningMoreThanTheWatchdogTimeIsLate) {
  SafetyChannel channel(settings(), haptic_limits());
  channel.restart();
  DeviceSample replayed = sample_at(0, 1.0, 1);
  replayed.dt_s = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(channel.admit(DeviceStatus::Fresh, replayed, 1e-3));
  EXPECT_TRUE(channel.render(Vec3{1, 0, 0}, Vec3{}, false, 1e-3, true, false).flags &
              kSafetyLateTick);
}

TEST(Safety, AComputeThatOutlastsTheWatchdogWritesZero) {
  SafetyChannel channel(settings(), haptic_limits());
  channel.restart();
  ASSERT_TRUE(channel.admit(DeviceStatus::Fresh, sample_at(0, 1.0, 1), 1e-3));
  channel.late_in_tick();
  const SafetyOutput out = channel.render(Vec3{1, 0, 0}, Vec3{}, true, 1e-3, true, false);
  EXPECT_EQ(norm(out.force_N), 0.0);
  EXPECT_TRUE(out.flags & kSafetyLateTick);
}

TEST(Safety, WorkspaceGuard) {
  DeviceLimits limits = haptic_limits();
  limits.workspace_min_mm = {-10, -10, -10};
  limits.workspace_max_mm = {10, 10, 10};
  SafetyChannel channel(settings(), limits);
  channel.restart();
  EXPECT_EQ(tick(channel, Vec3{1, 0, 0}, true, DeviceStatus::Fresh, 5.0).force_N.x, 1.0);
  const SafetyOutput out = tick(channel, Vec3{1, 0, 0}, true, DeviceStatus::Fresh, 50.0);
  EXPECT_EQ(norm(out.force_N), 0.0);
  EXPECT_TRUE(out.events & kSafetyOutsideWorkspace);
}

TEST(Safety, InputOnlyDeviceRendersNothing) {
  SafetyChannel channel(settings(), DeviceLimits{});
  channel.restart();
  const SafetyOutput out = tick(channel, Vec3{1, 0, 0});
  EXPECT_EQ(norm(out.force_N), 0.0);
  EXPECT_TRUE(out.flags & kSafetyNoForceOutput);
}

TEST(Safety, StopRampsDown) {
  SafetySettings s = settings();
  s.stop_ramp_time_s = 0.002;
  SafetyChannel channel(s, haptic_limits());
  channel.restart();
  tick(channel, Vec3{1, 0, 0});
  const DeviceSample sample = sample_at(0, 1.0, 99);
  ASSERT_TRUE(channel.admit(DeviceStatus::Fresh, sample));
  EXPECT_NEAR(channel.render(Vec3{1, 0, 0}, Vec3{}, true, 1e-3, true, true).force_N.x, 0.5, 1e-12);
  ASSERT_TRUE(channel.admit(DeviceStatus::Fresh, sample));
  EXPECT_EQ(channel.render(Vec3{1, 0, 0}, Vec3{}, true, 1e-3, true, true).force_N.x, 0.0);
}

// Halves every force: the hook's output is what is rendered, then clamped.
class HalvingController : public PassivityController {
 public:
  Vec3 observe(const Vec3& force_N, const Vec3& /*velocity*/, double /*dt_s*/) override {
    ++calls;
    return force_N * 0.5;
  }
  int calls = 0;
};

TEST(Safety, PassivityControllerAdjustsTheForce) {
  SafetyChannel channel(settings(), haptic_limits());
  auto controller = std::make_unique<HalvingController>();
  HalvingController* seen = controller.get();
  channel.set_passivity(std::move(controller));
  channel.restart();
  const SafetyOutput out = tick(channel, Vec3{2, 0, 0});
  EXPECT_EQ(out.force_N.x, 1.0);
  EXPECT_TRUE(out.flags & kSafetyPassivity);
  EXPECT_EQ(seen->calls, 1);
}

// The device's stiffness limit is stated at 1 kHz: a slower loop lowers it in
// proportion to its rate, a faster one keeps it; 0 means none known.
TEST(Safety, StiffnessLimitScalesDownBelowOneKilohertz) {
  DeviceLimits limits = haptic_limits();
  EXPECT_EQ(stiffness_limit(limits, 1000.0), 0.0);  // None known.
  limits.max_stiffness_N_per_mm = 0.8;
  EXPECT_EQ(stiffness_limit(limits, 1000.0), 0.8);
  EXPECT_EQ(stiffness_limit(limits, 4000.0), 0.8);
  EXPECT_DOUBLE_EQ(stiffness_limit(limits, 500.0), 0.4);
  EXPECT_DOUBLE_EQ(stiffness_limit(limits, 250.0), 0.2);
  limits.max_stiffness_N_per_mm = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(stiffness_limit(limits, 1000.0), 0.0);
}

TEST(Safety, StiffnessInForceIsTheLowerOfRequestAndLimit) {
  EXPECT_EQ(stiffness_in_force(0.5, 0.2), 0.2);
  EXPECT_EQ(stiffness_in_force(0.1, 0.2), 0.1);
  EXPECT_EQ(stiffness_in_force(0.2, 0.2), 0.2);
  EXPECT_EQ(stiffness_in_force(50.0, 0.0), 50.0);  // No limit known: the request.
}

}  // namespace
}  // namespace hapticut::servo
