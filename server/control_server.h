// ControlServer: two threads. The control thread serves the control channel
// (TCP, length-prefixed JSON, protocol.h); the stream thread sends the state
// stream (UDP, one frame per datagram to every subscriber) and does nothing
// else, so no message, however large or slow to answer, delays a frame.
// Malformed, oversized, out-of-order or unauthenticated messages are answered
// with an error and counted, never fatal. Each client has a budget per round
// (bytes read, messages handled) and for unsent replies: a client that floods
// or stops reading is held back, then cut off and counted, and the others are
// served between its messages. A `load` is read and built on a worker
// (load_worker.h), one at a time: its client's later messages wait for its
// reply, everyone else is answered meanwhile. The loop hands frames over
// through a lock-free triple buffer and never waits for either thread.
#pragma once

#include <netinet/in.h>

#include <array>
#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "client_admission.h"
#include "control_message.h"
#include "load_worker.h"
#include "protocol.h"
#include "rt/histogram.h"
#include "servo.h"

namespace hapticut::servo {

class NetworkError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ControlCounters {
  std::uint64_t connections = 0;
  std::uint64_t messages = 0;
  std::uint64_t errors = 0;               // Every message answered with an error.
  std::uint64_t malformed = 0;            // Not JSON, not an object, no type.
  std::uint64_t oversized = 0;            // Length prefix over the limit (connection closed).
  std::uint64_t out_of_order = 0;         // Before hello.
  std::uint64_t unauthenticated = 0;      // Wrong token or protocol version.
  std::uint64_t wrong_tokens = 0;         // Hellos with a wrong or missing token.
  std::uint64_t hello_timeouts = 0;       // No hello within kHelloDeadline_s (closed).
  std::uint64_t waiting_closed = 0;       // Closed before hello to make room for newer connections.
  std::uint64_t idle_clients_closed = 0;  // Closed to make room for a new hello.
  std::uint64_t cut_off_clients = 0;      // Replies left unread past the budget's time.
  std::uint64_t stray_datagrams = 0;      // Datagrams that arrived at the stream socket.
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
  // Ends both threads, and a load on its way after at most kLoadStopWait_s.
  void stop();
  // stop() left a load inside a stage to end on its own: exit the process
  // without destructors (std::_Exit), which that thread may still be using.
  bool load_left_running() const { return load_left_running_; }

 private:
  struct Client {
    int fd = -1;
    sockaddr_in peer{};
    MessageReader reader;
    std::string out;
    bool hello = false;
    bool closing = false;        // Close once `out` is sent.
    bool has_slot = false;       // Said hello: `slot` is its own.
    std::size_t slot = 0;        // Its entry in subscribers_.
    bool subscribed = false;     // Its slot is streamed to.
    double backlog_since_s = 0;  // When `out` went over the budget (0: under it).
    double accepted_s = 0.0;
    double last_message_s = 0.0;
    double hold_replies_until_s = 0.0;  // A wrong token's refusal waits until then.
    std::size_t reservation = 0;        // Of large_message_bytes_, for its next message.
    bool loading = false;               // Its `load` is on the worker; its next messages wait.
    ControlJson load_id;                // That load's id, for its reply.
  };
  // A subscription, shared by the two threads under subscribers_mutex_.
  struct Subscriber {
    bool active = false;
    in_addr address{};
    int port = 0;
    double rate_Hz = 0.0;
    double next_frame_s = 0.0;
  };

  void run();
  void serve();
  void stream();
  void set_subscription(Client& client, int port, double rate_Hz);
  void accept_clients();
  void read_client(Client& client);
  std::size_t read_allowance(Client& client);
  void release_reservation(Client& client);
  void handle_pending(Client& client);
  void cut_off(Client& client);
  void close_now(Client& client, const std::string& why);
  void enforce_hello_deadline(Client& client, double now_s);
  void make_room_for_hello();
  std::vector<ConnectionTimes> connection_times() const;
  std::size_t free_slot() const;
  void write_client(Client& client);
  void handle(Client& client, const std::string& text);
  template <typename Produce>
  nlohmann::json answer(Produce&& produce);
  void send_reply(Client& client, nlohmann::json reply, const std::string& type,
                  const ControlJson& id);
  nlohmann::json dispatch(Client& client, ControlMessage& request);
  nlohmann::json start_load(Client& client, ControlJson& message);
  void finish_load();
  nlohmann::json hello(Client& client, const ControlJson& message);
  nlohmann::json subscribe(Client& client, const ControlJson& message);
  nlohmann::json unsubscribe(Client& client);
  nlohmann::json status();
  nlohmann::json set(Client& client, const ControlJson& message);
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
  std::mutex subscribers_mutex_;  // Held for a copy or an update, never across I/O.
  std::array<Subscriber, kMaxClients> subscribers_{};
  std::atomic<std::uint64_t> frames_sent_{0};
  std::atomic<std::uint64_t> frames_dropped_{0};  // Send buffer full (slow client).
  // Tick to sendto, per frame sent (the servo's share of a frame's age).
  std::unique_ptr<LatencyHistogram> send_age_us_ = std::make_unique<LatencyHistogram>();
  double last_frame_time_s_ = 0.0;       // servo_time_s of the last frame fetched (stream thread).
  double stray_pause_until_s_ = 0.0;     // Stream socket not read until then.
  std::size_t large_message_bytes_ = 0;  // Reserved by clients for messages being read.
  LoadWorker<PreparedLoad> load_worker_;
  bool load_left_running_ = false;
  std::thread thread_;
  std::thread stream_thread_;
  std::atomic<bool> quit_{false};
};

// At shutdown, how long a load on its way gets to reach its next stage; a
// longer stage (building the Space of a large scene takes seconds) is left
// behind, so shutdown never waits for a load longer than this.
inline constexpr double kLoadStopWait_s = 0.1;

// Unsent replies: over this a client is not read (it is not reading its
// replies); over it for kBacklogCutOff_s, or over kMaxClientBacklog, it is cut off.
inline constexpr std::size_t kClientBacklogBudget = 1U << 20;
inline constexpr std::size_t kMaxClientBacklog = 4U << 20;
inline constexpr double kBacklogCutOff_s = 2.0;
// Per client per round of the control thread, so that one client's messages
// wait behind each other, not another client's.
inline constexpr std::size_t kReadBytesPerRound = 256U << 10;
// The control channel's input memory: each connection buffers up to
// kFreeBytesPerClient; a longer message is read only once its whole length
// is reserved from kMaxLargeMessageBytes, shared by all clients (room for
// four messages of the largest size), so that every message begun can end.
inline constexpr std::size_t kFreeBytesPerClient = 64U << 10;
inline constexpr std::size_t kMaxLargeMessageBytes = 64U << 20;
inline constexpr int kMessagesPerRound = 32;
inline constexpr double kMinStreamRate_Hz = 1.0;
inline constexpr double kMaxStreamRate_Hz = 1000.0;

}  // namespace hapticut::servo
