// The device's stiffness limit in the servo: a scene stiffness above it is
// lowered to it for that blade in every tick (one line on stderr at load), a
// "set" above it is refused naming the limit, one below it is taken; the
// status shows the stiffness in force per blade. A sim device with
// max_stiffness_N_per_mm on the sphere example (coupling 0.1 N/mm).
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "servo.h"
#include "servo_loop.h"
#include "session.h"

namespace hapticut::servo {
namespace {

const std::string kScene = std::string(HAPTICUT_EXAMPLES_DIR) + "/sphere320.hapticut.msgpack";
const std::string kLimitedSim = "scalpel=sim:press,max_stiffness_N_per_mm=0.05";

// One press stroke, as fast as possible, engaged; returns the last tick's stiffness.
double stroke_stiffness(const std::string& device, double rate_Hz, double* limit) {
  SessionConfig config;
  config.scene_path = kScene;
  config.devices = {device};
  config.rate_Hz = rate_Hz;
  config.as_fast_as_possible = true;
  Session session(config);
  auto shared = std::make_unique<LoopShared>();
  shared->exit_when_done = true;
  shared->engaged.store(true);
  run_loop(session, *shared);
  EXPECT_GT(shared->ticks.load(), 100U);
  const Binding& b = session.bindings().at(0);
  EXPECT_NE(b.result.step, StepKind::None);  // The last tick stepped the engine.
  *limit = b.max_stiffness_N_per_mm;
  return b.result.stiffness_N_per_mm;
}

TEST(ServoStiffness, SceneStiffnessAboveTheLimitIsLoweredInTheTick) {
  double limit = -1.0;
  EXPECT_EQ(stroke_stiffness(kLimitedSim, 1000.0, &limit), 0.05);
  EXPECT_EQ(limit, 0.05);
  // At 500 Hz the 1 kHz limit is halved.
  EXPECT_DOUBLE_EQ(stroke_stiffness(kLimitedSim, 500.0, &limit), 0.025);
  EXPECT_DOUBLE_EQ(limit, 0.025);
  // Under the limit, or no limit known: the scene's.
  EXPECT_EQ(stroke_stiffness("scalpel=sim:press,max_stiffness_N_per_mm=0.5", 1000.0, &limit), 0.1);
  EXPECT_EQ(stroke_stiffness("scalpel=sim:press", 1000.0, &limit), 0.1);
  EXPECT_EQ(limit, 0.0);
}

std::string command_error(Servo& servo, const nlohmann::json& message) {
  try {
    servo.command(parse_control_message(message.dump()));
  } catch (const CommandError& e) {
    return e.what();
  }
  return "";
}

TEST(ServoStiffness, SetAboveTheLimitIsRefusedBelowItTaken) {
  Options options;
  options.scene_path = kScene;
  options.devices = {kLimitedSim};
  options.quiet = true;
  Servo servo(options);
  testing::internal::CaptureStderr();
  servo.load(servo.config_from_options());
  const std::string said = testing::internal::GetCapturedStderr();
  EXPECT_EQ(said,
            "hapticut-servo: blade 'scalpel': the scene's stiffness 0.1 N/mm is above device '" +
                kLimitedSim + "''s limit of 0.05 N/mm; lowered to 0.05 N/mm\n");

  nlohmann::json status = servo.status();
  EXPECT_EQ(status["settings"]["stiffness_N_per_mm"], 0.1);  // The scene's, as asked.
  EXPECT_EQ(status["blades"][0]["stiffness_N_per_mm"], 0.05);
  EXPECT_EQ(status["blades"][0]["max_stiffness_N_per_mm"], 0.05);

  // Other settings alone are taken although the scene's stiffness is above the limit.
  EXPECT_EQ(command_error(servo, {{"type", "set"}, {"max_transitions_per_tick", 32}}), "");
  const std::string refused = command_error(
      servo, {{"type", "set"}, {"stiffness_N_per_mm", 0.2}, {"max_transitions_per_tick", 8}});
  EXPECT_EQ(refused,
            "stiffness_N_per_mm: 0.2 N/mm is above the limit of 0.05 N/mm of blade "
            "'scalpel''s device '" +
                kLimitedSim + "'; nothing applied");
  status = servo.status();
  EXPECT_EQ(status["settings"]["max_transitions_per_tick"], 32);  // Nothing of it applied.
  EXPECT_EQ(status["blades"][0]["stiffness_N_per_mm"], 0.05);

  EXPECT_EQ(command_error(servo, {{"type", "set"}, {"stiffness_N_per_mm", 0.04}}), "");
  status = servo.status();
  EXPECT_EQ(status["settings"]["stiffness_N_per_mm"], 0.04);
  EXPECT_EQ(status["blades"][0]["stiffness_N_per_mm"], 0.04);
  EXPECT_EQ(command_error(servo, {{"type", "set"}, {"stiffness_N_per_mm", 0.05}}), "");
}

TEST(ServoStiffness, RefusalAtALowerRateNamesBothLimits) {
  Options options;
  options.scene_path = kScene;
  options.devices = {kLimitedSim};
  options.rate_Hz = 500.0;
  options.quiet = true;
  Servo servo(options);
  testing::internal::CaptureStderr();
  servo.load(servo.config_from_options());
  EXPECT_NE(testing::internal::GetCapturedStderr().find(
                "limit of 0.025 N/mm at 500 Hz (0.05 N/mm at 1 kHz); lowered to 0.025 N/mm"),
            std::string::npos);
  EXPECT_NE(command_error(servo, {{"type", "set"}, {"stiffness_N_per_mm", 0.03}})
                .find("above the limit of 0.025 N/mm at 500 Hz (0.05 N/mm at 1 kHz)"),
            std::string::npos);
}

}  // namespace
}  // namespace hapticut::servo
