// The UDP bridge: its datagrams byte by byte, and the bridge device against
// examples/bridge_example.py over loopback (a bridge that runs, goes silent,
// sends garbage).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "devices/bridge_datagram.h"
#include "devices/bridge_device.h"

namespace hapticut::servo {
namespace {

double monotonic_s() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

TEST(BridgeDatagram, PoseLayoutIsFixedAndRoundTrips) {
  BridgePose pose;
  pose.sequence = 0x0102030405060708ULL;
  pose.time_s = 1.5;
  pose.pose.position_mm = {1.0, -2.0, 3.0};
  pose.pose.rotation = {0.0, 1.0, 0.0, 0.0};
  pose.buttons = 5;
  pose.flags = 0;
  pose.applied_force_sequence = 77;
  const auto bytes = encode_bridge_pose(pose);
  // "HCBP", version 1, kind 1, then the sequence little-endian.
  const std::uint8_t header[] = {'H', 'C', 'B', 'P', 1, 0, 1, 0, 8, 7, 6, 5, 4, 3, 2, 1};
  EXPECT_TRUE(std::equal(std::begin(header), std::end(header), bytes.begin()));
  EXPECT_EQ(bytes[80], 5);   // buttons
  EXPECT_EQ(bytes[88], 77);  // applied force sequence
  BridgePose back;
  ASSERT_EQ(decode_bridge_pose(bytes.data(), bytes.size(), back), BridgeDecode::Ok);
  EXPECT_EQ(back.sequence, pose.sequence);
  EXPECT_EQ(back.pose.position_mm, pose.pose.position_mm);
  EXPECT_EQ(back.pose.rotation.x, 1.0);
  EXPECT_EQ(back.applied_force_sequence, 77U);
}

TEST(BridgeDatagram, ForceLayoutRoundTrips) {
  BridgeForce force;
  force.sequence = 9;
  force.force_N = {0.5, -1.0, 2.0};
  force.torque_N_mm = {10, 20, 30};
  force.pose_sequence = 8;
  force.flags = kBridgeForceEngagedFlag;
  const auto bytes = encode_bridge_force(force);
  EXPECT_EQ(bytes[6], 2);  // kind
  BridgeForce back;
  ASSERT_EQ(decode_bridge_force(bytes.data(), bytes.size(), back), BridgeDecode::Ok);
  EXPECT_EQ(back.force_N, force.force_N);
  EXPECT_EQ(back.torque_N_mm, force.torque_N_mm);
  EXPECT_EQ(back.pose_sequence, 8U);
  EXPECT_EQ(back.flags, kBridgeForceEngagedFlag);
}

TEST(BridgeDatagram, GarbageIsRefusedWithItsReason) {
  BridgePose pose;
  pose.sequence = 1;
  const auto good = encode_bridge_pose(pose);
  BridgePose out;
  auto bytes = good;
  EXPECT_EQ(decode_bridge_pose(bytes.data(), 95, out), BridgeDecode::WrongLength);
  bytes[0] = 0;
  EXPECT_EQ(decode_bridge_pose(bytes.data(), bytes.size(), out), BridgeDecode::BadMagic);
  bytes = good;
  bytes[4] = 2;
  EXPECT_EQ(decode_bridge_pose(bytes.data(), bytes.size(), out), BridgeDecode::BadVersion);
  bytes = good;
  bytes[6] = 2;
  EXPECT_EQ(decode_bridge_pose(bytes.data(), bytes.size(), out), BridgeDecode::BadKind);
  pose.pose.position_mm.y = NAN;
  bytes = encode_bridge_pose(pose);
  EXPECT_EQ(decode_bridge_pose(bytes.data(), bytes.size(), out), BridgeDecode::NotFinite);
  pose.pose.position_mm.y = 0;
  pose.pose.rotation = {0.1, 0, 0, 0};
  bytes = encode_bridge_pose(pose);
  EXPECT_EQ(decode_bridge_pose(bytes.data(), bytes.size(), out), BridgeDecode::BadRotation);
  EXPECT_STREQ(bridge_decode_name(BridgeDecode::BadRotation), "bad rotation");
}

TEST(BridgeDevice, FactoryChecksItsOptions) {
  const auto error_of = [](const std::string& args) {
    try {
      make_bridge_device(args);
    } catch (const std::exception& error) {
      return std::string(error.what());
    }
    return std::string();
  };
  EXPECT_EQ(error_of("port=0,timeout_ms=50,max_force=2.5"), "");
  EXPECT_EQ(error_of("port=70000"), "bridge: option 'port' must be an integer in [0, 65535]");
  EXPECT_EQ(error_of("timeout_ms=0"), "bridge: option 'timeout_ms' must be in [1, 10000]");
  EXPECT_EQ(error_of("host=x").rfind("bridge: unknown option 'host'", 0), 0U);
  EXPECT_EQ(error_of("47810"), "bridge: option '47810' is not key=value");
  auto device = make_bridge_device("port=0,max_force=2.5,max_stiffness=0.8,workspace=100");
  EXPECT_EQ(device->limits().max_force_N, 2.5);
  EXPECT_EQ(device->limits().max_stiffness_N_per_mm, 0.8);
  EXPECT_EQ(device->limits().workspace_min_mm, (Vec3{-100, -100, -100}));
  auto bad_address = make_bridge_device("bind=localhost");
  EXPECT_THROW(bad_address->start(), std::runtime_error);
}

// examples/bridge_example.py as a child process; its summary is its stdout.
// posix_spawn, not fork: the bridge device's thread is already running, and a
// forked child that allocates could wait forever on a lock that thread held.
class ExampleBridge {
 public:
  ExampleBridge(int port, const std::vector<std::string>& extra) {
    std::vector<std::string> args{HAPTICUT_PYTHON, HAPTICUT_BRIDGE_EXAMPLE, "--servo",
                                  "127.0.0.1:" + std::to_string(port), "--summary"};
    args.insert(args.end(), extra.begin(), extra.end());
    std::vector<char*> argv;
    argv.reserve(args.size() + 1);
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    int pipe_fds[2];
    EXPECT_EQ(::pipe2(pipe_fds, O_CLOEXEC), 0);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], STDOUT_FILENO);
    const int spawned = ::posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(pipe_fds[1]);
    EXPECT_EQ(spawned, 0) << "cannot start " << argv[0] << ": " << std::strerror(spawned);
    if (spawned != 0) pid_ = -1;
    stdout_ = pipe_fds[0];
  }
  ~ExampleBridge() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    if (stdout_ >= 0) ::close(stdout_);
  }
  bool running() {
    if (pid_ <= 0) return false;
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == 0) return true;
    exit_status_ = status;
    exited_ = true;
    pid_ = -1;
    return false;
  }
  // Waits (at most 20 s) for the bridge to exit; its summary line.
  nlohmann::json summary() {
    std::string text;
    char buffer[512];
    const double give_up = monotonic_s() + 20.0;
    for (;;) {
      const double left_s = give_up - monotonic_s();
      pollfd readable{stdout_, POLLIN, 0};
      if (left_s <= 0 || ::poll(&readable, 1, static_cast<int>(left_s * 1000) + 1) <= 0) {
        ADD_FAILURE() << "the bridge example did not finish within 20 s; it printed: " << text;
        return nlohmann::json::object();
      }
      const ssize_t n = ::read(stdout_, buffer, sizeof buffer);
      if (n <= 0) break;
      text.append(buffer, static_cast<std::size_t>(n));
    }
    int status = exit_status_;
    if (pid_ > 0) {
      ::waitpid(pid_, &status, 0);
      exited_ = true;
    }
    pid_ = -1;
    EXPECT_TRUE(exited_ && WIFEXITED(status) && WEXITSTATUS(status) == 0) << text;
    return nlohmann::json::parse(text, nullptr, false);
  }

 private:
  pid_t pid_ = -1;
  int stdout_ = -1;
  int exit_status_ = 0;
  bool exited_ = false;
};

struct LoopTally {
  int fresh = 0;
  int stale = 0;
  int lost = 0;
  int lost_after_fresh = 0;  // Lost ticks that followed a Fresh one.
  double min_z = 1e9;
  double max_force = 0.0;
};

// A 1 kHz-ish loop: a floor at z = 0 with k = 0.2 N/mm, as the servo would
// render it; from start until the bridge has exited (and a little after).
LoopTally run_loop(BridgeDevice& device, ExampleBridge& bridge) {
  LoopTally tally;
  bool seen_fresh = false;
  const double give_up = monotonic_s() + 30.0;
  double end = give_up;
  while (monotonic_s() < end) {
    if (end == give_up && !bridge.running()) end = monotonic_s() + 0.2;
    DeviceSample sample;
    const DeviceStatus status = device.read(monotonic_s(), sample);
    Vec3 force;
    if (status == DeviceStatus::Fresh) {
      ++tally.fresh;
      seen_fresh = true;
    } else if (status == DeviceStatus::Stale) {
      ++tally.stale;
    } else {
      ++tally.lost;
      if (seen_fresh) ++tally.lost_after_fresh;
    }
    if (status != DeviceStatus::Lost) {
      tally.min_z = std::min(tally.min_z, sample.pose.position_mm.z);
      if (sample.pose.position_mm.z < 0) force = {0, 0, -0.2 * sample.pose.position_mm.z};
      tally.max_force = std::max(tally.max_force, force.z);
    }
    device.write(force, {});
    std::this_thread::sleep_for(std::chrono::microseconds(1000));
  }
  return tally;
}

BridgeDeviceOptions loopback_options() {
  BridgeDeviceOptions options;
  options.port = 0;
  options.timeout_s = 0.1;
  return options;
}

TEST(BridgeDevice, ExampleBridgeClosesTheLoopOverLoopback) {
  BridgeDevice device(loopback_options());
  device.start();
  ASSERT_GT(device.bound_port(), 0);
  ExampleBridge bridge(device.bound_port(), {"--duration", "1.5", "--rate", "500"});
  const LoopTally tally = run_loop(device, bridge);
  const nlohmann::json summary = bridge.summary();
  device.stop();
  EXPECT_GT(tally.fresh, 200);
  EXPECT_LT(tally.min_z, 0.0);  // The scripted hand reached the floor...
  EXPECT_GT(tally.max_force, 0.1);
  // ... and felt the force: the bridge received forces and echoed their sequence.
  EXPECT_GT(summary["forces_received"].get<int>(), 200);
  EXPECT_GT(summary["max_force_N"].get<double>(), 0.1);
  EXPECT_GT(summary["last_force_sequence"].get<int>(), 0);
  EXPECT_GT(summary["min_z_mm"].get<double>(), -10.0);  // The floor held it up.
  EXPECT_EQ(device.counters().garbage(), 0U);
  EXPECT_GE(device.counters().poses.load(), static_cast<std::uint64_t>(tally.fresh));
}

TEST(BridgeDevice, ABridgeThatGoesSilentIsLost) {
  BridgeDevice device(loopback_options());
  device.start();
  ExampleBridge bridge(device.bound_port(),
                       {"--duration", "1.2", "--rate", "500", "--silent-after", "0.5"});
  const LoopTally tally = run_loop(device, bridge);
  bridge.summary();
  device.stop();
  EXPECT_GT(tally.fresh, 100);
  // Silent for its last 0.7 s (and 0.2 s after it exits), Lost after the 0.1 s
  // timeout: at least ~0.6 s of Lost ticks.
  EXPECT_GT(tally.lost_after_fresh, 300);
  DeviceSample sample;
  EXPECT_EQ(device.read(monotonic_s(), sample), DeviceStatus::Lost);
}

TEST(BridgeDevice, GarbageIsRefusedAndCountedAndTheLoopGoesOn) {
  BridgeDevice device(loopback_options());
  device.start();
  ExampleBridge bridge(device.bound_port(),
                       {"--duration", "1.0", "--rate", "500", "--garbage-every", "3"});
  const LoopTally tally = run_loop(device, bridge);
  const nlohmann::json summary = bridge.summary();
  device.stop();
  const auto garbage_sent = summary["garbage_sent"].get<std::uint64_t>();
  EXPECT_GT(garbage_sent, 50U);
  EXPECT_EQ(device.counters().garbage(), garbage_sent);
  for (BridgeDecode reason : {BridgeDecode::WrongLength, BridgeDecode::BadMagic,
                              BridgeDecode::BadVersion, BridgeDecode::NotFinite}) {
    EXPECT_GT(device.counters().refused[static_cast<int>(reason)].load(), 0U)
        << bridge_decode_name(reason);
  }
  EXPECT_EQ(device.counters().poses.load(), summary["poses_sent"].get<std::uint64_t>());
  EXPECT_GT(tally.fresh, 100);
  EXPECT_TRUE(std::isfinite(tally.min_z));
}

}  // namespace
}  // namespace hapticut::servo
