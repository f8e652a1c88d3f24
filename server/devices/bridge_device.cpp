#include "devices/bridge_device.h"

#include <arpa/inet.h>
#include <poll.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace hapticut::servo {
namespace {

double monotonic_s() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

// The receive thread wakes at least this often to notice stop().
constexpr int kPollTimeout_ms = 20;
// A datagram bigger than any valid one is read whole and refused (wrong length).
constexpr std::size_t kReceiveBufferBytes = 2048;

}  // namespace

std::uint64_t BridgeDeviceCounters::garbage() const {
  std::uint64_t total = 0;
  for (const auto& count : refused) total += count.load(std::memory_order_relaxed);
  return total;
}

BridgeDevice::BridgeDevice(BridgeDeviceOptions options) : options_(std::move(options)) {}

BridgeDevice::~BridgeDevice() { stop(); }

void BridgeDevice::start() {
  if (running_.load()) return;
  const std::string where = options_.bind_address + ":" + std::to_string(options_.port);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(options_.port));
  if (inet_pton(AF_INET, options_.bind_address.c_str(), &address.sin_addr) != 1) {
    throw std::runtime_error("bridge: '" + options_.bind_address + "' is not an IPv4 address");
  }
  socket_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (socket_ < 0) throw std::runtime_error("bridge: socket: " + std::string(std::strerror(errno)));
  if (::bind(socket_, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    const std::string reason = std::strerror(errno);
    ::close(socket_);
    socket_ = -1;
    throw std::runtime_error("bridge: cannot listen on " + where + " (" + reason + ")");
  }
  socklen_t length = sizeof address;
  ::getsockname(socket_, reinterpret_cast<sockaddr*>(&address), &length);
  bound_port_ = ntohs(address.sin_port);
  running_.store(true);
  receive_thread_ = std::thread([this] { receive_loop(); });
}

void BridgeDevice::stop() {
  if (socket_ < 0) return;
  // Nothing left pushing: a zero force to the bridge before going.
  write({}, {});
  running_.store(false);
  if (receive_thread_.joinable()) receive_thread_.join();
  ::close(socket_);
  socket_ = -1;
}

void BridgeDevice::receive_loop() {
  std::array<std::uint8_t, kReceiveBufferBytes> buffer{};
  while (running_.load(std::memory_order_relaxed)) {
    pollfd wait{socket_, POLLIN, 0};
    if (::poll(&wait, 1, kPollTimeout_ms) <= 0) continue;
    // Drain everything pending; keep the newest valid pose.
    for (;;) {
      sockaddr_in peer{};
      socklen_t peer_length = sizeof peer;
      const ssize_t length = ::recvfrom(socket_, buffer.data(), buffer.size(), MSG_DONTWAIT,
                                        reinterpret_cast<sockaddr*>(&peer), &peer_length);
      if (length < 0) break;
      BridgePose pose;
      const BridgeDecode result =
          decode_bridge_pose(buffer.data(), static_cast<std::size_t>(length), pose);
      if (result != BridgeDecode::Ok) {
        counters_.refused[static_cast<int>(result)].fetch_add(1, std::memory_order_relaxed);
        continue;
      }
      const double arrival_s = monotonic_s();
      // After a silence longer than the timeout a bridge may have restarted
      // (its sequence begins again): its first pose starts a new count.
      const bool restarted = arrival_s - receive_newest_s_ > options_.timeout_s;
      if (pose.sequence <= receive_newest_sequence_ && !restarted) {
        counters_.out_of_order.fetch_add(1, std::memory_order_relaxed);
        continue;
      }
      receive_newest_sequence_ = pose.sequence;
      receive_newest_s_ = arrival_s;
      counters_.poses.fetch_add(1, std::memory_order_relaxed);
      if ((pose.flags & kBridgePoseFaultFlag) != 0U) {
        counters_.faults.fetch_add(1, std::memory_order_relaxed);
      }
      received_.publish({pose, arrival_s, peer});
    }
  }
}

DeviceStatus BridgeDevice::read(double now_s, DeviceSample& sample) {
  last_now_s_ = now_s;
  Received received;
  const std::uint64_t count = received_.read(received);
  if (count == 0) {
    sample = {};
    return DeviceStatus::Lost;  // Nothing heard yet.
  }
  peer_ = received.peer;
  have_peer_ = true;
  const bool fresh = count != last_taken_;
  if (fresh) {
    last_taken_ = count;
    last_pose_ = received.pose;
    ++sample_sequence_;
  }
  sample.pose = last_pose_.pose;
  sample.buttons = last_pose_.buttons;
  sample.time_s = received.arrival_s;
  sample.sequence = sample_sequence_;
  sample.dt_s = 0.0;  // A live device: the engine steps with the measured tick.
  const bool silent = now_s - received.arrival_s > options_.timeout_s;
  if (silent || (last_pose_.flags & kBridgePoseFaultFlag) != 0U) return DeviceStatus::Lost;
  return fresh ? DeviceStatus::Fresh : DeviceStatus::Stale;
}

void BridgeDevice::write(const Vec3& force_N, const Vec3& torque_N_mm) {
  if (!have_peer_ || socket_ < 0) return;
  BridgeForce force;
  force.sequence = ++force_sequence_;
  force.time_s = last_now_s_;
  // A non-finite force never leaves: it goes as zero.
  const bool finite = is_finite(force_N) && is_finite(torque_N_mm);
  force.force_N = finite ? force_N : Vec3{};
  force.torque_N_mm = finite ? torque_N_mm : Vec3{};
  force.pose_sequence = last_pose_.sequence;
  force.flags = engaged_.load(std::memory_order_relaxed) ? kBridgeForceEngagedFlag : 0U;
  const auto bytes = encode_bridge_force(force);
  const ssize_t sent = ::sendto(socket_, bytes.data(), bytes.size(), MSG_DONTWAIT,
                                reinterpret_cast<const sockaddr*>(&peer_), sizeof peer_);
  if (sent == static_cast<ssize_t>(bytes.size())) {
    counters_.forces_sent.fetch_add(1, std::memory_order_relaxed);
  } else {
    counters_.send_failures.fetch_add(1, std::memory_order_relaxed);
  }
}

std::vector<std::pair<std::string, std::uint64_t>> BridgeDevice::status_counters() const {
  const auto load = [](const std::atomic<std::uint64_t>& count) {
    return count.load(std::memory_order_relaxed);
  };
  std::vector<std::pair<std::string, std::uint64_t>> out = {
      {"poses", load(counters_.poses)},
      {"garbage", counters_.garbage()},
      {"out_of_order", load(counters_.out_of_order)},
      {"faults", load(counters_.faults)},
      {"forces_sent", load(counters_.forces_sent)},
      {"send_failures", load(counters_.send_failures)},
  };
  for (int reason = 1; reason < kBridgeDecodeCount; ++reason) {
    std::string name =
        std::string("refused_") + bridge_decode_name(static_cast<BridgeDecode>(reason));
    std::replace(name.begin(), name.end(), ' ', '_');
    out.emplace_back(std::move(name), load(counters_.refused[reason]));
  }
  return out;
}

std::unique_ptr<Device> make_bridge_device(const std::string& args) {
  std::string bare;
  const DeviceOptions options = parse_device_options(args, "bridge", bare);
  if (!bare.empty()) {
    throw std::invalid_argument("bridge: option '" + bare + "' is not key=value");
  }
  return make_bridge_device(options);
}

std::unique_ptr<Device> make_bridge_device(const DeviceOptions& options) {
  check_device_options(
      options, "bridge",
      {"port", "bind", "timeout_ms", "max_force", "max_torque", "max_stiffness", "workspace"});
  BridgeDeviceOptions device;
  const double port = device_option_number(options, "port", device.port, "bridge");
  if (port < 0 || port > 65535 || port != std::floor(port)) {
    throw std::invalid_argument("bridge: option 'port' must be an integer in [0, 65535]");
  }
  device.port = static_cast<int>(port);
  if (const auto bind = options.find("bind"); bind != options.end()) {
    device.bind_address = bind->second;
  }
  const double timeout_ms =
      device_option_number(options, "timeout_ms", 1e3 * device.timeout_s, "bridge");
  if (timeout_ms < 1.0 || timeout_ms > 10000.0) {
    throw std::invalid_argument("bridge: option 'timeout_ms' must be in [1, 10000]");
  }
  device.timeout_s = timeout_ms * 1e-3;
  DeviceLimits& limits = device.limits;
  limits.max_force_N = device_option_number(options, "max_force", limits.max_force_N, "bridge");
  limits.max_torque_N_mm =
      device_option_number(options, "max_torque", limits.max_torque_N_mm, "bridge");
  limits.max_stiffness_N_per_mm =
      device_option_number(options, "max_stiffness", limits.max_stiffness_N_per_mm, "bridge");
  const double half =
      device_option_number(options, "workspace", limits.workspace_max_mm.x, "bridge");
  if (limits.max_force_N < 0.0 || limits.max_force_N > 100.0 || limits.max_torque_N_mm < 0.0 ||
      limits.max_stiffness_N_per_mm < 0.0 || half <= 0.0) {
    throw std::invalid_argument(
        "bridge: max_force must be in [0, 100] N; max_torque, max_stiffness >= 0; workspace > 0");
  }
  limits.workspace_min_mm = {-half, -half, -half};
  limits.workspace_max_mm = {half, half, half};
  return std::make_unique<BridgeDevice>(std::move(device));
}

}  // namespace hapticut::servo
