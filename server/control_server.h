// ControlServer: the network thread. The control channel (TCP,
// length-prefixed JSON, protocol.h) and the state stream (UDP, one frame per
// datagram to every subscriber). Malformed, oversized, out-of-order or
// unauthenticated messages are answered with an error and counted, never
// fatal; a slow or vanished client costs only its own frames: the loop hands
// frames over through a lock-free triple buffer and never waits for this thread.
#pragma once

#include <netinet/in.h>

#include <atomic>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "control_message.h"
#include "histogram.h"
#include "protocol.h"
#include "servo.h"

namespace hapticut::servo {

class NetworkError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ControlCounters {
  std::uint64_t connections = 0;
  std::uint64_t messages = 0;
  std::uint64_t errors = 0;           // Every message answered with an error.
  std::uint64_t malformed = 0;        // Not JSON, not an object, no type.
  std::uint64_t oversized = 0;        // Length prefix over the limit (connection closed).
  std::uint64_t out_of_order = 0;     // Before hello.
  std::uint64_t unauthenticated = 0;  // Wrong token or protocol version.
  std::uint64_t token_lockouts = 0;   // Hellos refused while wrong tries lock the token.
  std::uint64_t refused_clients = 0;  // Over the client limit.
  std::uint64_t frames_sent = 0;
  std::uint64_t frames_dropped = 0;   // Send buffer full (slow client).
  std::uint64_t stray_datagrams = 0;  // Datagrams that arrived at the stream socket.
};

class ControlServer {
 public:
  // Binds the TCP port and the UDP stream socket; NetworkError when it cannot.
  ControlServer(Servo& servo, const Options& options);
  ~ControlServer();
  ControlServer(const ControlServer&) = delete;
  ControlServer& operator=(const ControlServer&) = delete;

  int port() const { return port_; }
  int stream_port() const { return stream_port_; }
  void start();
  void stop();

 private:
  struct Client {
    int fd = -1;
    sockaddr_in peer{};
    MessageReader reader;
    std::string out;
    bool hello = false;
    bool closing = false;  // Close once `out` is sent.
    int stream_port = 0;   // 0: not subscribed.
    in_addr stream_address{};
    double rate_Hz = 0.0;
    double next_frame_s = 0.0;
  };

  void run();
  void serve();
  void accept_clients();
  void read_client(Client& client);
  void write_client(Client& client);
  void handle(Client& client, const std::string& text);
  nlohmann::json dispatch(Client& client, const ControlMessage& request);
  nlohmann::json hello(Client& client, const ControlJson& message);
  void send_frames();
  void drain_stray_datagrams();
  void update_stream_interval();
  nlohmann::json counters_json() const;

  Servo& servo_;
  Options options_;
  int listen_fd_ = -1;
  int udp_fd_ = -1;
  int port_ = 0;
  int stream_port_ = 0;
  std::vector<Client> clients_;
  ControlCounters counters_;
  // Tick to sendto, per frame sent (the servo's share of a frame's age).
  std::unique_ptr<LatencyHistogram> send_age_us_ = std::make_unique<LatencyHistogram>();
  double last_frame_time_s_ = 0.0;     // servo_time_s of the last frame fetched.
  double stray_pause_until_s_ = 0.0;   // Stream socket not read until then.
  int wrong_tokens_ = 0;               // In a row, from any client.
  double token_locked_until_s_ = 0.0;  // Every hello refused until then.
  std::thread thread_;
  std::atomic<bool> quit_{false};
};

inline constexpr std::size_t kMaxClients = 16;
inline constexpr std::size_t kMaxClientBacklog = 4U << 20;  // Unsent replies before a drop.
inline constexpr double kMinStreamRate_Hz = 1.0;
inline constexpr double kMaxStreamRate_Hz = 1000.0;
// Wrong tokens in a row (from any client) before every hello is refused for a while.
inline constexpr int kMaxWrongTokens = 5;
inline constexpr double kTokenLockout_s = 10.0;

}  // namespace hapticut::servo
