// The device's stiffness limit in the servo: a scene stiffness above it is
// lowered to it for that blade in every tick (one line on stderr at load), a
// "set" above it is refused naming the limit, one below it is taken; the
// status shows the stiffness in force per blade. A sim device with
// max_stiffness_N_per_mm on the sphere example (coupling 0.1 N/mm, 50 points).
// A rigid blade renders the sum of its points' springs, n k: the limit then
// applies to that sum.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "hapticut/scene_io.h"
#include "hapticut/space.h"
#include "passivity.h"
#include "servo.h"
#include "servo_loop.h"
#include "session.h"

namespace hapticut::servo {
namespace {

const std::string kScene = std::string(HAPTICUT_EXAMPLES_DIR) + "/sphere320.hapticut.msgpack";
const std::string kLimitedSim = "scalpel=sim:press,max_stiffness_N_per_mm=0.05";

// The sphere example with its blade's coupling set (the scene file's is the default).
std::shared_ptr<const Scene> sphere_scene(BladeCoupling coupling) {
  auto scene = std::make_shared<Scene>(load_scene(kScene));
  scene->blades.at(0).coupling = coupling;
  return scene;
}

// One press stroke, as fast as possible, engaged; returns the last tick's stiffness.
double stroke_stiffness(const std::string& device, double rate_Hz, double* limit,
                        BladeCoupling coupling = BladeCoupling::Independent) {
  SessionConfig config;
  config.scene = sphere_scene(coupling);
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
    servo.set_parameters(parse_control_message(message.dump()).body);
  } catch (const CommandError& e) {
    return e.what();
  }
  return "";
}

// A servo with the sphere example loaded, its blade of the given coupling
// bound to `device`; what the load said on stderr in `said`.
std::unique_ptr<Servo> loaded_servo(BladeCoupling coupling, const std::string& device,
                                    std::string& said, double rate_Hz = 0.0) {
  Options options;
  options.scene_path = kScene;
  options.devices = {device};
  options.rate_Hz = rate_Hz;
  options.quiet = true;
  auto servo = std::make_unique<Servo>(options);
  SessionConfig config = servo->config_from_options();
  config.scene = sphere_scene(coupling);
  testing::internal::CaptureStderr();
  servo->load(config);
  said = testing::internal::GetCapturedStderr();
  return servo;
}

TEST(ServoStiffness, SetAboveTheLimitIsRefusedBelowItTaken) {
  Options options;
  options.scene_path = kScene;
  options.devices = {kLimitedSim};
  options.quiet = true;
  Servo servo(options);
  SessionConfig config = servo.config_from_options();
  config.scene = sphere_scene(BladeCoupling::Independent);
  testing::internal::CaptureStderr();
  servo.load(config);
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
  std::string said;
  auto servo = loaded_servo(BladeCoupling::Independent, kLimitedSim, said, 500.0);
  EXPECT_NE(said.find("limit of 0.025 N/mm at 500 Hz (0.05 N/mm at 1 kHz); lowered to 0.025 N/mm"),
            std::string::npos);
  EXPECT_NE(command_error(*servo, {{"type", "set"}, {"stiffness_N_per_mm", 0.03}})
                .find("above the limit of 0.025 N/mm at 500 Hz (0.05 N/mm at 1 kHz)"),
            std::string::npos);
}

TEST(ServoStiffness, ARigidBladeRendersTheSumOfItsSprings) {
  EXPECT_EQ(rendered_springs(BladeCoupling::Rigid, 50), 50);
  EXPECT_EQ(rendered_springs(BladeCoupling::Independent, 50), 1);
  EXPECT_EQ(point_stiffness_limit(0.5, 50), 0.01);
  EXPECT_EQ(point_stiffness_limit(0.5, 1), 0.5);
  EXPECT_EQ(point_stiffness_limit(0.0, 50), 0.0);  // No limit known stays none.
}

// 0.5 N/mm at the device: the scene's 0.1 N/mm is fine for one point, but a
// rigid blade of 50 points would render 5 N/mm; it steps with 0.5 / 50.
const std::string kStiffSim = "scalpel=sim:press,max_stiffness_N_per_mm=0.5";

TEST(ServoStiffness, ARigidBladeIsLoweredToTheLimitOverItsPoints) {
  double limit = -1.0;
  EXPECT_EQ(stroke_stiffness(kStiffSim, 1000.0, &limit, BladeCoupling::Rigid), 0.01);
  EXPECT_EQ(limit, 0.01);
  EXPECT_DOUBLE_EQ(stroke_stiffness(kStiffSim, 500.0, &limit, BladeCoupling::Rigid), 0.005);
  // The same device and k on independent points: one point's k is within the limit.
  EXPECT_EQ(stroke_stiffness(kStiffSim, 1000.0, &limit, BladeCoupling::Independent), 0.1);
  EXPECT_EQ(limit, 0.5);
  // No limit known: the scene's k, rigid or not.
  EXPECT_EQ(stroke_stiffness("scalpel=sim:press", 1000.0, &limit, BladeCoupling::Rigid), 0.1);
  EXPECT_EQ(limit, 0.0);
}

TEST(ServoStiffness, ARigidBladeSetOverTheLimitInSumIsRefused) {
  std::string said;
  auto servo = loaded_servo(BladeCoupling::Rigid, kStiffSim, said);
  EXPECT_EQ(said,
            "hapticut-servo: blade 'scalpel': the scene's stiffness 0.1 N/mm is above device '" +
                kStiffSim +
                "''s limit of 0.01 N/mm per point (a rigid blade of 50 points renders 50 k: the "
                "device's 0.5 N/mm over 50); lowered to 0.01 N/mm\n");
  nlohmann::json status = servo->status();
  const nlohmann::json& blade = status["blades"][0];
  EXPECT_EQ(blade["coupling"], "rigid");
  EXPECT_EQ(blade["stiffness_N_per_mm"], 0.01);
  EXPECT_EQ(blade["max_stiffness_N_per_mm"], 0.01);
  EXPECT_EQ(blade["device_max_stiffness_N_per_mm"], 0.5);
  EXPECT_DOUBLE_EQ(blade["rendered_stiffness_N_per_mm"].get<double>(), 0.5);

  // 0.02 N/mm is a tenth of the limit for one point, but 50 of them render 1 N/mm.
  EXPECT_EQ(command_error(*servo, {{"type", "set"}, {"stiffness_N_per_mm", 0.02}}),
            "stiffness_N_per_mm: 0.02 N/mm is above the limit of 0.01 N/mm per point (a rigid "
            "blade of 50 points renders 50 k: the device's 0.5 N/mm over 50) of blade "
            "'scalpel''s device '" +
                kStiffSim + "'; nothing applied");
  EXPECT_EQ(servo->status()["settings"]["stiffness_N_per_mm"], 0.1);  // Nothing applied.
  EXPECT_EQ(command_error(*servo, {{"type", "set"}, {"stiffness_N_per_mm", 0.008}}), "");
  status = servo->status();
  EXPECT_EQ(status["blades"][0]["stiffness_N_per_mm"], 0.008);
  EXPECT_DOUBLE_EQ(status["blades"][0]["rendered_stiffness_N_per_mm"].get<double>(), 0.4);

  // Independent points on the same device: 0.02 N/mm is taken, and it is what is rendered.
  auto independent = loaded_servo(BladeCoupling::Independent, kStiffSim, said);
  EXPECT_EQ(said, "");
  EXPECT_EQ(command_error(*independent, {{"type", "set"}, {"stiffness_N_per_mm", 0.02}}), "");
  status = independent->status();
  EXPECT_EQ(status["blades"][0]["coupling"], "independent");
  EXPECT_EQ(status["blades"][0]["max_stiffness_N_per_mm"], 0.5);
  EXPECT_EQ(status["blades"][0]["rendered_stiffness_N_per_mm"], 0.02);
}

// The passivity controller measures the environment's stiffness from the
// blade's summed force, so behind a rigid blade it sees (and damps by) n k,
// not one point's k. The blade pressed level onto the sphere's top at
// 100 mm/s, its force fed to the controller as the safety layer does.
double passivity_stiffness(BladeCoupling coupling) {
  const auto scene = sphere_scene(coupling);
  Blade blade(Space::from_scene(*scene), scene->blades.at(0));
  HannafordRyuPassivity passivity;
  const Vec3 velocity{0.0, 0.0, -100.0};
  const double dt_s = 0.001;
  blade.reset({{0.0, 0.0, 40.0}, {}});
  for (int k = 1; k <= 150; ++k) {  // Down to z = 25, below the top at about 29.7.
    const BladeTick tick = blade.step({{0.0, 0.0, 40.0 - 0.1 * k}, {}}, dt_s);
    passivity.observe(tick.force_N, velocity, dt_s);
  }
  EXPECT_GT(blade.last_tick().force_N.z, 1.0);  // In contact: the test measures something.
  return passivity.stiffness_N_per_mm();
}

TEST(ServoStiffness, PassivitySeesARigidBladesSumOfSprings) {
  const double k = 0.1;  // The sphere example's.
  EXPECT_NEAR(passivity_stiffness(BladeCoupling::Rigid), 50 * k, 0.05 * 50 * k);
  // Independent points over a ball: only those over its top push back.
  EXPECT_LT(passivity_stiffness(BladeCoupling::Independent), 0.5 * 50 * k);
}

}  // namespace
}  // namespace hapticut::servo
