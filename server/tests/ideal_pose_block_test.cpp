// Every blade's ideal pose (Blade::ideal_pose) in its BladeBlock, the same
// bytes in stream frames and records: after a press onto the sphere example's
// rigid ball, a rigid blade's ideal pose rests above the device's, while
// independent points report the device's pose. The recording's header names
// each blade's coupling, which says what that pose is.
#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hapticut/scene_io.h"
#include "recording/recording_file.h"
#include "servo_loop.h"
#include "session.h"

namespace hapticut::servo {
namespace {

const std::string kScene = std::string(HAPTICUT_EXAMPLES_DIR) + "/sphere320.hapticut.msgpack";

struct PressedBlade {
  BladeBlock block;
  Pose engine_ideal;
  Pose device;
  std::string header_coupling;
};

// The sim's built-in press (down from 45 % to 5 % of the height above the
// centre, into the ball), as fast as possible; the last tick's block.
PressedBlade press(BladeCoupling coupling) {
  auto scene = std::make_shared<Scene>(load_scene(kScene));
  scene->blades.at(0).coupling = coupling;
  SessionConfig config;
  config.scene = scene;
  config.devices = {"scalpel=sim:press"};
  config.as_fast_as_possible = true;
  Session session(config);
  auto shared = std::make_unique<LoopShared>();
  shared->exit_when_done = true;
  shared->engaged.store(true);
  run_loop(session, *shared);
  Binding& b = session.bindings().at(0);
  EXPECT_NE(b.result.step, StepKind::None);
  read_blade_tick_snapshot(*b.blade, b.snapshot);
  std::vector<unsigned char> bytes(sizeof(BladeBlock) +
                                   points_block_bytes(b.snapshot.point_count()));
  EXPECT_EQ(write_blade_block(b.result, b.snapshot, bytes.data()), bytes.size());
  PressedBlade out;
  std::memcpy(&out.block, bytes.data(), sizeof(BladeBlock));
  out.engine_ideal = b.blade->ideal_pose();
  out.device = b.result.sample.pose;
  const std::vector<unsigned char> preamble = recording_preamble(session.recording_info());
  const auto header = nlohmann::json::parse(preamble.begin() + 16, preamble.end());
  out.header_coupling = header["blades"][0]["coupling"].get<std::string>();
  return out;
}

void expect_pose(const double* written, const Pose& pose) {
  const double expected[7] = {pose.position_mm.x, pose.position_mm.y, pose.position_mm.z,
                              pose.rotation.w,    pose.rotation.x,    pose.rotation.y,
                              pose.rotation.z};
  for (int i = 0; i < 7; ++i) EXPECT_EQ(written[i], expected[i]) << "component " << i;
}

TEST(IdealPoseBlock, ARigidBladeRestsOnTheBallAboveTheDevice) {
  const PressedBlade rigid = press(BladeCoupling::Rigid);
  expect_pose(rigid.block.ideal_pose, rigid.engine_ideal);
  expect_pose(rigid.block.pose, rigid.device);
  // The device went into the ball; the knife stayed on it.
  EXPECT_GT(rigid.block.ideal_pose[2], rigid.block.pose[2] + 1.0);
  EXPECT_EQ(rigid.header_coupling, "rigid");
}

TEST(IdealPoseBlock, IndependentPointsReportTheDevicePose) {
  const PressedBlade independent = press(BladeCoupling::Independent);
  expect_pose(independent.block.ideal_pose, independent.engine_ideal);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(independent.block.ideal_pose[i], independent.block.pose[i]);
  EXPECT_EQ(independent.header_coupling, "independent");
}

}  // namespace
}  // namespace hapticut::servo
