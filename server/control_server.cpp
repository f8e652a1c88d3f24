#include "control_server.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string_view>

#include "clock.h"
#include "hapticut/scene_io.h"
#include "realtime.h"

namespace hapticut::servo {

namespace {

void set_nonblocking(int fd) { fcntl(fd, F_SETFL, fcntl(fd, F_GETFL, 0) | O_NONBLOCK); }

bool is_loopback(const in_addr& address) { return (ntohl(address.s_addr) >> 24) == 127; }

// Compares in time that depends only on the expected token's length, so that
// the time of a refusal does not tell how much of a guess was right.
bool same_token(std::string_view given, std::string_view expected) {
  unsigned difference = given.size() == expected.size() ? 0U : 1U;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const char g = i < given.size() ? given[i] : '\0';
    difference |= static_cast<unsigned char>(g ^ expected[i]);
  }
  return difference == 0;
}

std::string errno_text() { return std::strerror(errno); }

}  // namespace

ControlServer::ControlServer(Servo& servo, const Options& options)
    : servo_(servo), options_(options) {
  in_addr address{};
  if (inet_pton(AF_INET, options.listen_address.c_str(), &address) != 1) {
    throw NetworkError("--listen: '" + options.listen_address + "' is not an IPv4 address");
  }
  if (!is_loopback(address) && options.token.empty()) {
    throw NetworkError("--listen " + options.listen_address +
                       ": listening beyond loopback needs --token");
  }
  listen_fd_ = socket(AF_INET, SOCK_STREAM, 0);
  const int yes = 1;
  setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  sockaddr_in bind_address{};
  bind_address.sin_family = AF_INET;
  bind_address.sin_addr = address;
  bind_address.sin_port = htons(static_cast<std::uint16_t>(options.control_port));
  if (bind(listen_fd_, reinterpret_cast<sockaddr*>(&bind_address), sizeof(bind_address)) != 0 ||
      listen(listen_fd_, 8) != 0) {
    const std::string why = errno_text();
    close(listen_fd_);
    throw NetworkError("control port " + options.listen_address + ":" +
                       std::to_string(options.control_port) + ": " + why);
  }
  socklen_t length = sizeof(bind_address);
  getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&bind_address), &length);
  port_ = ntohs(bind_address.sin_port);
  set_nonblocking(listen_fd_);

  udp_fd_ = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in udp_address{};
  udp_address.sin_family = AF_INET;
  udp_address.sin_addr = address;
  udp_address.sin_port = 0;
  if (bind(udp_fd_, reinterpret_cast<sockaddr*>(&udp_address), sizeof(udp_address)) != 0) {
    const std::string why = errno_text();
    close(listen_fd_);
    close(udp_fd_);
    throw NetworkError("stream socket: " + why);
  }
  length = sizeof(udp_address);
  getsockname(udp_fd_, reinterpret_cast<sockaddr*>(&udp_address), &length);
  stream_port_ = ntohs(udp_address.sin_port);
  const int send_buffer = 1 << 20;
  setsockopt(udp_fd_, SOL_SOCKET, SO_SNDBUF, &send_buffer, sizeof(send_buffer));
  set_nonblocking(udp_fd_);
}

ControlServer::~ControlServer() {
  stop();
  for (Client& c : clients_) close(c.fd);
  if (listen_fd_ >= 0) close(listen_fd_);
  if (udp_fd_ >= 0) close(udp_fd_);
}

void ControlServer::start() {
  thread_ = std::thread([this] { run(); });
}

void ControlServer::stop() {
  quit_.store(true);
  if (thread_.joinable()) thread_.join();
}

void ControlServer::run() {
  while (!quit_.load()) {
    try {
      serve();
    } catch (const std::exception& e) {
      // A bug in a handler must not take the network down: say so and go on.
      std::fprintf(stderr, "hapticut-servo: network thread: %s (continuing)\n", e.what());
    }
    if (!quit_.load()) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

void ControlServer::serve() {
  std::vector<pollfd> fds;
  while (!quit_.load()) {
    fds.clear();
    fds.push_back({listen_fd_, POLLIN, 0});
    // After a burst of stray datagrams, leave the stream socket alone for a
    // while: a flood then costs the kernel's drops, not this thread's time.
    const bool stray_paused = monotonic_now_s() < stray_pause_until_s_;
    fds.push_back({udp_fd_, static_cast<short>(stray_paused ? 0 : POLLIN), 0});
    for (const Client& c : clients_) {
      fds.push_back({c.fd, static_cast<short>(POLLIN | (c.out.empty() ? 0 : POLLOUT)), 0});
    }
    // Frames: wake just after the next one is due (then every 0.1 ms until it
    // is there); else every 50 ms.
    double wait_s = 0.05;
    const double interval_s = servo_.shared().stream_interval_s.load();
    if (interval_s > 0.0 && servo_.shared().running.load()) {
      const double due_s = last_frame_time_s_ + interval_s + 0.0001;
      wait_s = std::clamp(due_s - monotonic_now_s(), 0.0001, interval_s);
    }
    const timespec timeout = to_timespec(wait_s);
    const int ready = ppoll(fds.data(), fds.size(), &timeout, nullptr);
    if (ready < 0 && errno != EINTR) break;
    send_frames();
    if (ready <= 0) continue;
    if (fds[0].revents & POLLIN) accept_clients();
    if (fds[1].revents & POLLIN) drain_stray_datagrams();
    for (std::size_t i = 2; i < fds.size(); ++i) {
      Client& c = clients_[i - 2];
      if (fds[i].revents & (POLLIN | POLLHUP | POLLERR)) read_client(c);
      if (!c.out.empty() && c.fd >= 0) write_client(c);
    }
    const std::size_t before = clients_.size();
    clients_.erase(std::remove_if(clients_.begin(), clients_.end(),
                                  [](const Client& c) {
                                    if (c.fd >= 0 && !(c.closing && c.out.empty())) return false;
                                    if (c.fd >= 0) close(c.fd);
                                    return true;
                                  }),
                   clients_.end());
    if (clients_.size() != before) update_stream_interval();
  }
}

void ControlServer::accept_clients() {
  for (;;) {
    sockaddr_in peer{};
    socklen_t length = sizeof(peer);
    const int fd = accept(listen_fd_, reinterpret_cast<sockaddr*>(&peer), &length);
    if (fd < 0) return;
    ++counters_.connections;
    if (clients_.size() >= kMaxClients) {
      ++counters_.refused_clients;
      const std::string reply = frame_message(
          R"({"type":"error","ok":false,"error":"too many clients (16); try again later"})");
      (void)!send(fd, reply.data(), reply.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      close(fd);
      continue;
    }
    set_nonblocking(fd);
    Client client;
    client.fd = fd;
    client.peer = peer;
    clients_.push_back(std::move(client));
  }
}

void ControlServer::read_client(Client& client) {
  char buffer[65536];
  for (;;) {
    const ssize_t n = recv(client.fd, buffer, sizeof(buffer), 0);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
      close(client.fd);  // Gone: its subscription goes with it.
      client.fd = -1;
      return;
    }
    if (n < 0) break;
    client.reader.feed(buffer, static_cast<std::size_t>(n));
    std::string message;
    std::uint32_t length = 0;
    for (;;) {
      const MessageReader::Result r = client.reader.next(message, length);
      if (r == MessageReader::Result::NeedMore) break;
      if (r == MessageReader::Result::TooLarge) {
        ++counters_.oversized;
        ++counters_.errors;
        const nlohmann::json reply = {
            {"type", "error"},
            {"ok", false},
            {"error", "message of " + std::to_string(length) + " bytes exceeds the limit of " +
                          std::to_string(kMaxMessageBytes) + " bytes; closing the connection"}};
        client.out += frame_message(reply.dump());
        client.closing = true;
        return;
      }
      handle(client, message);
      if (client.closing) return;
    }
  }
}

void ControlServer::write_client(Client& client) {
  while (!client.out.empty()) {
    const ssize_t n = send(client.fd, client.out.data(), client.out.size(), MSG_NOSIGNAL);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) break;
      close(client.fd);
      client.fd = -1;
      return;
    }
    client.out.erase(0, static_cast<std::size_t>(n));
  }
  if (client.out.size() > kMaxClientBacklog) {  // Not reading its replies: let it go.
    close(client.fd);
    client.fd = -1;
  }
}

void ControlServer::handle(Client& client, const std::string& text) {
  ++counters_.messages;
  nlohmann::json reply;
  ControlJson id;
  std::string type = "error";
  try {
    ControlMessage message;
    try {
      message = parse_control_message(text);
    } catch (const MalformedMessage&) {
      ++counters_.malformed;
      throw;
    }
    id = message.id;
    type = message.type;
    reply = dispatch(client, message);
    reply["ok"] = true;
  } catch (const CommandError& e) {
    reply = {{"ok", false}, {"error", e.what()}};
  } catch (const SceneError& e) {
    reply = {{"ok", false}, {"error", std::string("scene: ") + e.what()}};
  } catch (const DeviceError& e) {
    reply = {{"ok", false}, {"error", e.what()}};
  } catch (const std::exception& e) {
    // A bug: say that it is one, without the library's text.
    reply = {{"ok", false}, {"error", std::string("internal error: ") + e.what()}};
  }
  if (!reply.value("ok", false)) ++counters_.errors;
  reply["type"] = type;
  if (!id.is_null()) reply["id"] = nlohmann::json::parse(id.dump());
  // Replace, not throw, on invalid UTF-8 (an error message may quote the bad bytes).
  client.out += frame_message(reply.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
}

nlohmann::json ControlServer::hello(Client& client, const ControlJson& message) {
  const std::int64_t version =
      integer_field(message, "version", 0, std::numeric_limits<std::int64_t>::max());
  if (version != kProtocolVersion) {
    ++counters_.unauthenticated;
    throw CommandError("protocol version " + std::to_string(version) +
                       " not supported (this servo speaks version " +
                       std::to_string(kProtocolVersion) + ")");
  }
  if (!options_.token.empty()) {
    const double now_s = monotonic_now_s();
    if (now_s < token_locked_until_s_) {
      ++counters_.unauthenticated;
      ++counters_.token_lockouts;
      client.closing = true;
      throw CommandError(
          "too many wrong tokens; hello is refused for " +
          std::to_string(static_cast<int>(std::ceil(token_locked_until_s_ - now_s))) + " s more");
    }
    const std::string token = message.contains("token") && message.at("token").is_string()
                                  ? message.at("token").get<std::string>()
                                  : std::string();
    if (!same_token(token, options_.token)) {
      ++counters_.unauthenticated;
      client.closing = true;
      if (++wrong_tokens_ >= kMaxWrongTokens) {
        wrong_tokens_ = 0;
        token_locked_until_s_ = now_s + kTokenLockout_s;
      }
      throw CommandError("wrong or missing token");
    }
    wrong_tokens_ = 0;
  }
  client.hello = true;
  return {{"version", kProtocolVersion},
          {"frame_version", kFrameVersion},
          {"record_version", kRecordVersion},
          {"servo", "hapticut-servo 0.1.0"},
          {"stream_source_port", stream_port_}};
}

nlohmann::json ControlServer::dispatch(Client& client, const ControlMessage& request) {
  const std::string& type = request.type;
  const ControlJson& message = request.body;
  if (type == "hello") return hello(client, message);
  if (!client.hello) {
    ++counters_.out_of_order;
    throw CommandError("\"" + type +
                       "\" before \"hello\" (send hello with the protocol version first)");
  }
  if (type == "subscribe") {
    const double rate = has_field(message, "rate_Hz")
                            ? number_field(message, "rate_Hz", kMinStreamRate_Hz, kMaxStreamRate_Hz)
                            : options_.stream_rate_Hz;
    const auto port = static_cast<int>(integer_field(message, "port", 1, 65535));
    client.stream_port = port;
    client.stream_address = client.peer.sin_addr;
    client.rate_Hz = rate;
    client.next_frame_s = 0.0;
    update_stream_interval();
    return {{"port", port}, {"rate_Hz", rate}, {"stream_source_port", stream_port_}};
  }
  if (type == "unsubscribe") {
    client.stream_port = 0;
    update_stream_interval();
    return nlohmann::json::object();
  }
  if (type == "status") {
    nlohmann::json status = servo_.status();
    status["protocol"] = counters_json();
    return status;
  }
  if (type == "set" && has_field(message, "stream_rate_Hz")) {
    const double rate =
        number_field(message, "stream_rate_Hz", kMinStreamRate_Hz, kMaxStreamRate_Hz);
    if (client.stream_port == 0) throw CommandError("stream_rate_Hz: not subscribed");
    client.rate_Hz = rate;
    update_stream_interval();
  }
  return servo_.command(request);
}

void ControlServer::update_stream_interval() {
  double fastest = 0.0;
  for (const Client& c : clients_) {
    if (c.fd >= 0 && c.stream_port != 0) fastest = std::max(fastest, c.rate_Hz);
  }
  servo_.shared().stream_interval_s.store(fastest > 0.0 ? 1.0 / fastest : 0.0);
}

void ControlServer::send_frames() {
  LoopShared& shared = servo_.shared();
  if (!shared.frames.fetch()) return;
  FrameBytes& frame = shared.frames.front();
  FrameHeader header;
  std::memcpy(&header, frame.bytes, sizeof(header));
  // The next frame is due one interval after this one's tick (not after this
  // fetch: a late fetch must not delay every frame after it).
  last_frame_time_s_ = header.servo_time_s;
  header.compute_p50_us = shared.compute_us.percentile_us(0.5);
  header.compute_p99_us = shared.compute_us.percentile_us(0.99);
  header.compute_max_us = shared.compute_us.max_us();
  header.wake_p50_us = shared.wake_us.percentile_us(0.5);
  header.wake_p99_us = shared.wake_us.percentile_us(0.99);
  header.wake_max_us = shared.wake_us.max_us();
  header.late_ticks = shared.late_ticks.load();
  std::memcpy(frame.bytes, &header, sizeof(header));
  for (Client& c : clients_) {
    if (c.fd < 0 || c.stream_port == 0) continue;
    if (header.servo_time_s + 1e-6 < c.next_frame_s) continue;
    c.next_frame_s = std::max(c.next_frame_s + 1.0 / c.rate_Hz, header.servo_time_s);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_addr = c.stream_address;
    to.sin_port = htons(static_cast<std::uint16_t>(c.stream_port));
    const ssize_t n = sendto(udp_fd_, frame.bytes, frame.size, 0,
                             reinterpret_cast<const sockaddr*>(&to), sizeof(to));
    if (n == static_cast<ssize_t>(frame.size)) {
      ++counters_.frames_sent;
      send_age_us_->add((monotonic_now_s() - header.servo_time_s) * 1e6);
    } else {
      ++counters_.frames_dropped;
    }
  }
}

void ControlServer::drain_stray_datagrams() {
  char buffer[2048];
  for (int i = 0; i < 256; ++i) {
    if (recv(udp_fd_, buffer, sizeof(buffer), MSG_DONTWAIT) < 0) return;
    ++counters_.stray_datagrams;
  }
  stray_pause_until_s_ = monotonic_now_s() + 0.005;  // A flood: pause 5 ms.
}

nlohmann::json ControlServer::counters_json() const {
  const ControlCounters& c = counters_;
  std::size_t subscribers = 0;
  for (const Client& client : clients_) subscribers += client.stream_port != 0 ? 1 : 0;
  return {{"connections", c.connections},
          {"clients", clients_.size()},
          {"subscribers", subscribers},
          {"messages", c.messages},
          {"errors", c.errors},
          {"malformed", c.malformed},
          {"oversized", c.oversized},
          {"out_of_order", c.out_of_order},
          {"unauthenticated", c.unauthenticated},
          {"token_lockouts", c.token_lockouts},
          {"refused_clients", c.refused_clients},
          {"frames_sent", c.frames_sent},
          {"frames_dropped", c.frames_dropped},
          {"stray_datagrams", c.stray_datagrams},
          {"frame_age_at_send_us",
           {{"p50", send_age_us_->percentile_us(0.5)},
            {"p99", send_age_us_->percentile_us(0.99)},
            {"max", send_age_us_->max_us()}}},
          {"stream_source_port", stream_port_}};
}

}  // namespace hapticut::servo
