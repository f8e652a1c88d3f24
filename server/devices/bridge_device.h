// BridgeDevice: a force device reached through a bridge program over UDP
// (bridge_datagram.h has the two datagrams). A receive thread drains the
// socket, refuses and counts garbage, and hands the newest pose to the tick
// through a LatestValue; write() sends one force datagram per tick with a
// non-blocking sendto (the device's own I/O; UDP never waits) to wherever
// the newest pose came from. A bridge that sends nothing for timeout_ms is
// Lost (the servo zeroes the force at once); when it speaks again the
// device is Fresh and the safety layer ramps the force back in.
#pragma once

#include <netinet/in.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "devices/bridge_datagram.h"
#include "devices/device.h"
#include "devices/device_options.h"
#include "rt/latest_value.h"

namespace hapticut::servo {

struct BridgeDeviceOptions {
  std::string bind_address = "127.0.0.1";  // Loopback unless told otherwise.
  int port = 47810;                        // 0: any free port (tests; see bound_port()).
  double timeout_s = 0.1;                  // Silence longer than this: Lost.
  DeviceLimits limits = default_limits();

  static DeviceLimits default_limits() {
    DeviceLimits limits;
    limits.has_force_output = true;
    limits.max_force_N = 3.0;
    limits.max_torque_N_mm = 0.0;
    limits.max_stiffness_N_per_mm = 1.0;
    limits.workspace_min_mm = {-300, -300, -300};
    limits.workspace_max_mm = {300, 300, 300};
    return limits;
  }
};

struct BridgeDeviceCounters {
  std::atomic<std::uint64_t> poses{0};         // Valid pose datagrams taken.
  std::atomic<std::uint64_t> out_of_order{0};  // Valid but older than one already taken.
  std::array<std::atomic<std::uint64_t>, kBridgeDecodeCount> refused{};  // By BridgeDecode.
  std::atomic<std::uint64_t> forces_sent{0};
  std::atomic<std::uint64_t> send_failures{0};
  std::atomic<std::uint64_t> faults{0};  // Poses flagged as a device fault.

  std::uint64_t garbage() const;  // All refused datagrams.
};

class BridgeDevice final : public Device {
 public:
  explicit BridgeDevice(BridgeDeviceOptions options);
  ~BridgeDevice() override;

  const char* kind() const override { return "bridge"; }
  DeviceLimits limits() const override { return options_.limits; }
  // Binds the socket and starts the receive thread; throws std::runtime_error
  // naming the address and the reason (port in use, bad address).
  void start() override;
  // Sends a zero force, then stops the thread and closes the socket.
  void stop() override;
  DeviceStatus read(double now_s, DeviceSample& sample) override;
  void write(const Vec3& force_N, const Vec3& torque_N_mm) override;
  // poses, garbage (all refused) and refused_<reason>, out_of_order, faults,
  // forces_sent, send_failures.
  std::vector<std::pair<std::string, std::uint64_t>> status_counters() const override;

  int bound_port() const { return bound_port_; }
  const BridgeDeviceCounters& counters() const { return counters_; }
  // The sequence of the last force the bridge says it applied (its echo).
  std::uint64_t applied_force_sequence() const { return last_pose_.applied_force_sequence; }
  // Engage flag sent with the force (the servo sets it while engaged).
  void set_engaged(bool engaged) { engaged_ = engaged; }

 private:
  struct Received {
    BridgePose pose;
    double arrival_s = 0.0;
    sockaddr_in peer{};
  };

  void receive_loop();

  BridgeDeviceOptions options_;
  int socket_ = -1;
  int bound_port_ = 0;
  std::atomic<bool> running_{false};
  std::thread receive_thread_;
  LatestValue<Received> received_;
  std::uint64_t receive_newest_sequence_ = 0;  // Receive thread only.
  double receive_newest_s_ = 0.0;              // Arrival of that pose (receive thread only).

  // Real-time side.
  BridgePose last_pose_;
  std::uint64_t last_taken_ = 0;
  std::uint64_t sample_sequence_ = 0;
  bool have_peer_ = false;
  sockaddr_in peer_{};
  std::uint64_t force_sequence_ = 0;
  double last_now_s_ = 0.0;
  std::atomic<bool> engaged_{true};

  BridgeDeviceCounters counters_;
};

// `--device NAME=bridge:ARGS` (kBridgeDeviceUsage). ARGS, all optional, comma-separated:
//   port=47810, bind=127.0.0.1, timeout_ms=100,
//   max_force=N, max_torque=N_MM, max_stiffness=N_PER_MM, workspace=MM (half-width of a cube)
// Throws std::invalid_argument naming a bad option.
inline constexpr const char* kBridgeDeviceUsage =
    "  bridge:[port=47810][,bind=127.0.0.1][,timeout_ms=100][,max_force=N][,max_torque=N_MM]\n"
    "      [,max_stiffness=N_PER_MM][,workspace=MM]\n"
    "      a force device behind a UDP bridge (examples/bridge_example.py; docs/devices.md)\n";
std::unique_ptr<Device> make_bridge_device(const DeviceOptions& options);
// From the ARGS text ("port=47810,max_force=2").
std::unique_ptr<Device> make_bridge_device(const std::string& args);

}  // namespace hapticut::servo
