#include "control_server.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <malloc.h>
#include <netinet/tcp.h>
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

#include "hapticut/scene_io.h"
#include "rt/clock.h"
#include "rt/realtime.h"

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

// Closes a connection whose last reply is sent. What the client sent after the
// message that ended it is read and dropped first (a bounded amount): closing
// with unread bytes would reset the connection and could lose that reply.
void close_after_reply(int fd) {
  char scratch[65536];
  for (int i = 0; i < 16 && recv(fd, scratch, sizeof(scratch), MSG_DONTWAIT) > 0; ++i) {
  }
  close(fd);
}

}  // namespace

ControlServer::ControlServer(Servo& servo, const Options& options)
    : servo_(servo), options_(options) {
  // A large message's buffers come from mmap and go back to the system when
  // freed, whatever came before (a fixed threshold: glibc's own rises after
  // the first large free, and memory freed in its heap may stay).
  mallopt(M_MMAP_THRESHOLD, static_cast<int>(kFreeBytesPerClient * 4));
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
      listen(listen_fd_, SOMAXCONN) != 0) {
    const std::string why = errno_text();
    close(listen_fd_);
    throw NetworkError("control port " + options.listen_address + ":" +
                       std::to_string(options.control_port) + ": " + why);
  }
  socklen_t length = sizeof(bind_address);
  getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&bind_address), &length);
  port_ = ntohs(bind_address.sin_port);
  set_nonblocking(listen_fd_);
  // A connection is handed over only once it has sent something: silent ones
  // never reach the waiting pool, and a client's hello is there to be read in
  // the round that accepts it, before any newer connection can close it.
  const int defer_s = static_cast<int>(kHelloDeadline_s);
  setsockopt(listen_fd_, IPPROTO_TCP, TCP_DEFER_ACCEPT, &defer_s, sizeof(defer_s));

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
  stream_thread_ = std::thread([this] { stream(); });
}

void ControlServer::stop() {
  quit_.store(true);
  if (stream_thread_.joinable()) stream_thread_.join();
  if (thread_.joinable()) thread_.join();
  if (!load_worker_.stop(kLoadStopWait_s)) load_left_running_ = true;
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
    fds.push_back({load_worker_.wake_fd(), POLLIN, 0});
    constexpr std::size_t kFirstClient = 3;
    bool pending = false;  // Whole messages left over from the last round.
    const double round_s = monotonic_now_s();
    for (Client& c : clients_) {
      // Not read while its unsent replies are over the budget: it is not reading them.
      // A held refusal is neither read after nor written until its time. Nor while
      // the memory for its next message cannot be reserved. Nor while it waits
      // for its load's reply (its next messages come after it); its hang-up is
      // still seen (POLLRDHUP), and cancels the load.
      const bool held = round_s < c.hold_replies_until_s;
      const bool readable = !held && !c.loading && c.out.size() <= kClientBacklogBudget &&
                            (c.reader.has_message() || read_allowance(c) > 0);
      pending = pending || (readable && c.reader.has_message());
      const bool writable = !held && !c.out.empty();
      fds.push_back({c.fd,
                     static_cast<short>((readable ? POLLIN : 0) | (writable ? POLLOUT : 0) |
                                        (c.loading ? POLLRDHUP : 0)),
                     0});
    }
    const timespec timeout = to_timespec(pending ? 0.0 : 0.05);
    const int ready = ppoll(fds.data(), fds.size(), &timeout, nullptr);
    if (ready < 0 && errno != EINTR) break;
    if (ready > 0 && (fds[0].revents & POLLIN)) accept_clients();
    if (ready > 0 && (fds[1].revents & POLLIN)) drain_stray_datagrams();
    // Before the clients: the loading client's next messages are handled in this round.
    if (load_worker_.busy() && load_worker_.finished()) finish_load();
    const double now_s = monotonic_now_s();
    const std::size_t polled = fds.size() - kFirstClient;
    for (std::size_t i = 0; i < polled && i < clients_.size(); ++i) {
      Client& c = clients_[i];
      const short events = ready > 0 ? fds[i + kFirstClient].revents : 0;
      if (c.fd >= 0 && c.loading) {
        if (events & (POLLRDHUP | POLLHUP | POLLERR)) {
          close(c.fd);  // Gone before its load's reply: the load is cancelled below.
          c.fd = -1;
          continue;
        }
        c.last_message_s = now_s;  // Waiting for its reply, not idle.
      }
      if (c.fd >= 0 && now_s < c.hold_replies_until_s) continue;
      if (c.fd >= 0 && (events & (POLLIN | POLLHUP | POLLERR))) read_client(c);
      if (c.fd >= 0 && c.out.size() <= kClientBacklogBudget) handle_pending(c);
      if (c.fd >= 0) enforce_hello_deadline(c, now_s);
      if (c.fd >= 0 && !c.out.empty() && now_s >= c.hold_replies_until_s) write_client(c);
      if (c.fd < 0) continue;
      if (c.out.size() <= kClientBacklogBudget) {
        c.backlog_since_s = 0.0;
      } else if (c.backlog_since_s == 0.0) {
        c.backlog_since_s = now_s;
      } else if (now_s - c.backlog_since_s > kBacklogCutOff_s) {
        cut_off(c);
      }
    }
    const std::size_t before = clients_.size();
    clients_.erase(std::remove_if(clients_.begin(), clients_.end(),
                                  [this](Client& c) {
                                    if (c.fd >= 0 && !(c.closing && c.out.empty())) return false;
                                    if (c.fd >= 0) close_after_reply(c.fd);
                                    if (c.loading) load_worker_.cancel();  // Nobody waits.
                                    if (c.has_slot) set_subscription(c, 0, 0.0);
                                    release_reservation(c);
                                    return true;
                                  }),
                   clients_.end());
    if (clients_.size() != before) update_stream_interval();
  }
}

void ControlServer::cut_off(Client& client) {
  ++counters_.cut_off_clients;
  std::fprintf(stderr,
               "hapticut-servo: control client %s:%d cut off: %zu bytes of replies unread for "
               "over %g s\n",
               inet_ntoa(client.peer.sin_addr), ntohs(client.peer.sin_port), client.out.size(),
               kBacklogCutOff_s);
  close(client.fd);
  client.fd = -1;
}

void ControlServer::close_now(Client& client, const std::string& why) {
  // One try at saying why; the connection closes whether or not it is read.
  const nlohmann::json reply = {{"type", "error"}, {"ok", false}, {"error", why}};
  const std::string text = frame_message(reply.dump());
  (void)!send(client.fd, text.data(), text.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
  close(client.fd);
  client.fd = -1;
  if (client.has_slot) set_subscription(client, 0, 0.0);
  client.has_slot = false;
  client.hello = false;
}

void ControlServer::enforce_hello_deadline(Client& client, double now_s) {
  if (client.hello || client.closing || now_s - client.accepted_s <= kHelloDeadline_s) return;
  ++counters_.hello_timeouts;
  client.out += frame_message(nlohmann::json{
      {"type", "error"},
      {"ok", false},
      {"error", "no hello within " + std::to_string(static_cast<int>(kHelloDeadline_s)) +
                    " s; closing the connection"}}
                                  .dump());
  client.closing = true;
}

std::vector<ConnectionTimes> ControlServer::connection_times() const {
  std::vector<ConnectionTimes> times;
  times.reserve(clients_.size());
  for (const Client& c : clients_) {
    // A connection that never said hello counts until it is closed, even with
    // its refusal held (a wrong token): so wrong tokens cannot pile up descriptors.
    const bool gone = c.fd < 0 || (c.hello && c.closing);
    times.push_back({c.hello, gone, c.accepted_s, c.last_message_s});
  }
  return times;
}

void ControlServer::make_room_for_hello() {
  // Clients on their way out (an error that closes them, a peer gone) give
  // up their slots first, so that the slots held are those of the clients counted.
  for (Client& c : clients_) {
    if (c.has_slot && (c.fd < 0 || c.closing)) {
      set_subscription(c, 0, 0.0);
      c.has_slot = false;
    }
  }
  const std::size_t idle = client_to_close_for_hello(connection_times());
  if (idle == kNoConnection) return;
  ++counters_.idle_clients_closed;
  close_now(clients_[idle], "closed: a new client said hello while all " +
                                std::to_string(kMaxClients) +
                                " client slots were taken, and this one had been idle longest");
}

void ControlServer::stream() {
  // Frames: wake just after the next one is due (then every 0.1 ms until it
  // is there); else every 20 ms to see whether anyone subscribed.
  while (!quit_.load()) {
    double wait_s = 0.02;
    const double interval_s = servo_.shared().stream_interval_s.load();
    if (interval_s > 0.0 && servo_.shared().running.load()) {
      const double due_s = last_frame_time_s_ + interval_s + 0.0001;
      wait_s = std::clamp(due_s - monotonic_now_s(), 0.0001, interval_s);
    }
    sleep_until(monotonic_now_s() + wait_s);
    send_frames();
  }
}

void ControlServer::accept_clients() {
  for (std::size_t accepted = 0; accepted < kAcceptsPerRound; ++accepted) {
    sockaddr_in peer{};
    socklen_t length = sizeof(peer);
    const int fd = accept(listen_fd_, reinterpret_cast<sockaddr*>(&peer), &length);
    if (fd < 0) return;
    ++counters_.connections;
    // A new connection always gets in: a flood of connections that never say
    // hello closes only the oldest of them, never a client that said hello.
    const std::size_t oldest = waiting_connection_to_close(connection_times());
    if (oldest != kNoConnection) {
      ++counters_.waiting_closed;
      close_now(clients_[oldest], "closed: too many connections waiting for their hello (" +
                                      std::to_string(kMaxWaitingConnections) +
                                      "); this one was the oldest");
    }
    set_nonblocking(fd);
    Client client;
    client.fd = fd;
    client.peer = peer;
    client.accepted_s = monotonic_now_s();
    client.last_message_s = client.accepted_s;
    client.reader.set_limit(kMaxHelloMessageBytes);
    clients_.push_back(std::move(client));
    // Its hello is usually here already: handled now, it cannot be closed
    // to make room for the connections accepted after it.
    Client& accepted_client = clients_.back();
    read_client(accepted_client);
    if (accepted_client.fd >= 0) handle_pending(accepted_client);
  }
}

std::size_t ControlServer::read_allowance(Client& client) {
  std::size_t room = kFreeBytesPerClient;
  std::uint32_t length = 0;
  if (client.reader.next_length(length) && length <= client.reader.limit() &&
      4 + std::size_t(length) > kFreeBytesPerClient) {
    const std::size_t needed = 4 + std::size_t(length);
    if (client.reservation < needed) {
      if (large_message_bytes_ - client.reservation + needed > kMaxLargeMessageBytes) return 0;
      large_message_bytes_ += needed - client.reservation;
      client.reservation = needed;
      client.reader.reserve(needed);
    }
    room = needed;
  }
  const std::size_t buffered = client.reader.buffered();
  return buffered < room ? room - buffered : 0;
}

void ControlServer::release_reservation(Client& client) {
  large_message_bytes_ -= client.reservation;
  client.reservation = 0;
}

void ControlServer::read_client(Client& client) {
  char buffer[65536];
  std::size_t read_bytes = 0;
  // At most a round's budget, and never more than one whole message beyond
  // what is buffered: a flooding client waits for its own messages.
  while (read_bytes < kReadBytesPerRound && !client.reader.has_message()) {
    const std::size_t allowance = std::min(sizeof(buffer), read_allowance(client));
    if (allowance == 0) break;
    const ssize_t n = recv(client.fd, buffer, allowance, 0);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
      close(client.fd);  // Gone: its subscription goes with it.
      client.fd = -1;
      return;
    }
    if (n < 0) break;
    client.reader.feed(buffer, static_cast<std::size_t>(n));
    read_bytes += static_cast<std::size_t>(n);
  }
}

void ControlServer::handle_pending(Client& client) {
  std::string message;
  std::uint32_t length = 0;
  for (int handled = 0; handled < kMessagesPerRound && !client.closing && !client.loading;
       ++handled) {
    const MessageReader::Result r = client.reader.next(message, length);
    if (r == MessageReader::Result::NeedMore) return;
    if (r == MessageReader::Result::TooLarge) {
      ++counters_.oversized;
      ++counters_.errors;
      const nlohmann::json reply = {
          {"type", "error"},
          {"ok", false},
          {"error", "message of " + std::to_string(length) + " bytes exceeds the limit of " +
                        std::to_string(client.reader.limit()) + " bytes" +
                        (client.hello ? "" : " before hello") + "; closing the connection"}};
      client.out += frame_message(reply.dump());
      client.closing = true;
      return;
    }
    client.last_message_s = monotonic_now_s();
    // A large message's reservation covers it until it is handled.
    const bool large = client.reservation != 0;
    handle(client, message);
    release_reservation(client);
    if (large) {
      // Give the memory of a large message back: to the system, not only to the heap.
      message = std::string();
      client.reader.release_spare_capacity();
      malloc_trim(0);
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
  if (client.out.empty() && client.out.capacity() > kFreeBytesPerClient) {
    std::string().swap(client.out);
  }
  if (client.out.size() > kMaxClientBacklog) cut_off(client);  // Not reading its replies.
}

void ControlServer::handle(Client& client, const std::string& text) {
  ++counters_.messages;
  ControlJson id;
  std::string type = "error";
  nlohmann::json reply = answer([&] {
    ControlMessage message;
    try {
      message = parse_control_message(text);
    } catch (const MalformedMessage&) {
      ++counters_.malformed;
      throw;
    }
    id = message.id;
    type = message.type;
    return dispatch(client, message);
  });
  if (reply.is_discarded()) {  // A load, answered when the worker is done (finish_load).
    client.load_id = id;
    return;
  }
  send_reply(client, std::move(reply), type, id);
}

// The reply to what `produce` returns, or the error it throws, as the client
// is told it; counted when it is an error. A discarded value (no reply yet)
// is returned as it is.
template <typename Produce>
nlohmann::json ControlServer::answer(Produce&& produce) {
  nlohmann::json reply;
  try {
    reply = produce();
    if (reply.is_discarded()) return reply;
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
  return reply;
}

void ControlServer::send_reply(Client& client, nlohmann::json reply, const std::string& type,
                               const ControlJson& id) {
  reply["type"] = type;
  if (!id.is_null()) reply["id"] = nlohmann::json::parse(id.dump());
  // Replace, not throw, on invalid UTF-8 (an error message may quote the bad bytes).
  client.out += frame_message(reply.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
}

nlohmann::json ControlServer::start_load(Client& client, ControlJson& message) {
  LoadRequest request = load_request(message, servo_.config_from_options());
  servo_.begin_load();  // Refused while running or while another load is on its way.
  try {
    load_worker_.start([request = std::move(request),
                        buffer_s = options_.record_buffer_s](const LoadStop& stop) mutable {
      return prepare_requested_load(std::move(request), buffer_s, stop);
    });
  } catch (...) {
    servo_.end_load();
    throw;
  }
  client.loading = true;
  return nlohmann::json(nlohmann::json::value_t::discarded);
}

void ControlServer::finish_load() {
  Client* waiting = nullptr;
  for (Client& c : clients_) {
    if (c.loading) waiting = &c;
  }
  if (waiting == nullptr || waiting->fd < 0) {
    // Its client has gone: the scene it asked for is not installed (it was
    // never told it was), and the old one stays, as after a failed load.
    try {
      (void)load_worker_.take();
    } catch (const std::exception&) {
    }
    servo_.end_load();
    if (waiting != nullptr) waiting->loading = false;
    return;
  }
  nlohmann::json reply = answer([&] {
    PreparedLoad prepared;
    try {
      prepared = load_worker_.take();
    } catch (...) {
      servo_.end_load();
      throw;
    }
    servo_.install(std::move(prepared));
    return servo_.loaded_reply();
  });
  waiting->loading = false;
  send_reply(*waiting, std::move(reply), "load", waiting->load_id);
  waiting->load_id = ControlJson();
}

nlohmann::json ControlServer::hello(Client& client, const ControlJson& message) {
  const std::int64_t version =
      integer_field(message, "version", 0, std::numeric_limits<std::int64_t>::max());
  if (version != kProtocolVersion) {
    ++counters_.unauthenticated;
    // An older client would misread the frames (they end with the cut tets):
    // tell it what to do rather than only that it failed.
    throw CommandError("protocol version " + std::to_string(version) +
                       " not supported (this servo speaks version " +
                       std::to_string(kProtocolVersion) +
                       (version < kProtocolVersion
                            ? ", whose frames and recordings carry the cut tets; "
                              "update the client: the hapticut toolkit and the add-on of this "
                              "servo's release"
                            : "; this servo is older than the client") +
                       ")");
  }
  if (!options_.token.empty()) {
    const std::string token = message.contains("token") && message.at("token").is_string()
                                  ? message.at("token").get<std::string>()
                                  : std::string();
    if (!same_token(token, options_.token)) {
      // One try per connection, refused only after a while: a guesser pays a
      // connection and the delay for each guess, and the right token, checked
      // on its own connection, is never held up by the wrong ones.
      ++counters_.unauthenticated;
      ++counters_.wrong_tokens;
      client.closing = true;
      client.hold_replies_until_s = monotonic_now_s() + kWrongTokenDelay_s;
      throw CommandError("wrong or missing token");
    }
  }
  if (!client.hello) {
    make_room_for_hello();
    client.slot = free_slot();
    client.has_slot = true;
    client.reader.set_limit(kMaxMessageBytes);
  }
  client.hello = true;
  return {{"version", kProtocolVersion},
          {"frame_version", kFrameVersion},
          {"record_version", kRecordVersion},
          {"servo", "hapticut-servo " HAPTICUT_VERSION},
          {"stream_source_port", stream_port_}};
}

nlohmann::json ControlServer::dispatch(Client& client, ControlMessage& request) {
  using Handler = nlohmann::json (*)(ControlServer&, Client&, ControlJson&);
  struct Command {
    std::string_view type;
    Handler handle;
  };
  // Every message type of the control channel (docs/protocol.md) and what
  // answers it: the connection's own commands here, the servo's in Servo.
  // Each refuses the fields it does not take, by name; `set` names its own.
  static const std::array<Command, 16> kCommands{{
      {"hello",
       [](ControlServer& s, Client& c, ControlJson& m) {
         refuse_unknown_fields(m, {"version", "token"});
         return s.hello(c, m);
       }},
      {"subscribe",
       [](ControlServer& s, Client& c, ControlJson& m) {
         refuse_unknown_fields(m, {"port", "rate_Hz"});
         return s.subscribe(c, m);
       }},
      {"unsubscribe",
       [](ControlServer& s, Client& c, ControlJson& m) {
         refuse_unknown_fields(m, {});
         return s.unsubscribe(c);
       }},
      {"status",
       [](ControlServer& s, Client&, ControlJson& m) {
         refuse_unknown_fields(m, {});
         return s.status();
       }},
      {"set", [](ControlServer& s, Client& c, ControlJson& m) { return s.set(c, m); }},
      {"load",
       [](ControlServer& s, Client& c, ControlJson& m) {
         refuse_unknown_fields(m, {"path", "scene", "devices", "rate_Hz", "as_fast_as_possible"});
         return s.start_load(c, m);
       }},
      {"start",
       [](ControlServer& s, Client&, ControlJson& m) {
         refuse_unknown_fields(m, {});
         return s.servo_.start_command();
       }},
      {"stop",
       [](ControlServer& s, Client&, ControlJson& m) {
         refuse_unknown_fields(m, {});
         return s.servo_.stop_command();
       }},
      {"engage",
       [](ControlServer& s, Client&, ControlJson& m) {
         refuse_unknown_fields(m, {"engaged"});
         return s.servo_.engage_command(m);
       }},
      {"record",
       [](ControlServer& s, Client&, ControlJson& m) {
         refuse_unknown_fields(m, {"action", "path"});
         return s.servo_.record_command(m);
       }},
      {"pose",
       [](ControlServer& s, Client&, ControlJson& m) {
         refuse_unknown_fields(m, {"blade", "pose", "buttons"});
         return s.servo_.pose_command(m);
       }},
      {"cuts",
       [](ControlServer& s, Client&, ControlJson& m) {
         refuse_unknown_fields(m, {"from"});
         return s.servo_.cuts_command(m);
       }},
      {"reset_cuts",
       [](ControlServer& s, Client&, ControlJson& m) {
         refuse_unknown_fields(m, {});
         return s.servo_.reset_cuts_command();
       }},
      {"save_cuts",
       [](ControlServer& s, Client&, ControlJson& m) {
         refuse_unknown_fields(m, {"path"});
         return s.servo_.save_cuts_command(m);
       }},
      {"load_cuts",
       [](ControlServer& s, Client&, ControlJson& m) {
         refuse_unknown_fields(m, {"path"});
         return s.servo_.load_cuts_command(m);
       }},
      {"shutdown",
       [](ControlServer& s, Client&, ControlJson& m) {
         refuse_unknown_fields(m, {});
         s.servo_.request_shutdown();
         return nlohmann::json::object();
       }},
  }};
  const std::string& type = request.type;
  const Command* found = nullptr;
  for (const Command& command : kCommands) {
    if (command.type == type) found = &command;
  }
  if (!client.hello && type != "hello") {
    ++counters_.out_of_order;
    throw CommandError("\"" + type +
                       "\" before \"hello\" (send hello with the protocol version first)");
  }
  if (found == nullptr) throw CommandError("unknown message type " + quoted_excerpt(type));
  return found->handle(*this, client, request.body);
}

nlohmann::json ControlServer::subscribe(Client& client, const ControlJson& message) {
  const double rate = has_field(message, "rate_Hz")
                          ? number_field(message, "rate_Hz", kMinStreamRate_Hz, kMaxStreamRate_Hz)
                          : options_.stream_rate_Hz;
  const auto port = static_cast<int>(integer_field(message, "port", 1, 65535));
  set_subscription(client, port, rate);
  update_stream_interval();
  return {{"port", port}, {"rate_Hz", rate}, {"stream_source_port", stream_port_}};
}

nlohmann::json ControlServer::unsubscribe(Client& client) {
  set_subscription(client, 0, 0.0);
  update_stream_interval();
  return nlohmann::json::object();
}

nlohmann::json ControlServer::status() {
  nlohmann::json status = servo_.status();
  status["protocol"] = counters_json();
  return status;
}

// The stream's rate is the connection's, the rest the servo's.
nlohmann::json ControlServer::set(Client& client, const ControlJson& message) {
  if (has_field(message, "stream_rate_Hz")) {
    const double rate =
        number_field(message, "stream_rate_Hz", kMinStreamRate_Hz, kMaxStreamRate_Hz);
    if (!client.subscribed) throw CommandError("stream_rate_Hz: not subscribed");
    {
      const std::lock_guard<std::mutex> lock(subscribers_mutex_);
      subscribers_[client.slot].rate_Hz = rate;
    }
    update_stream_interval();
  }
  return servo_.set_parameters(message);
}

std::size_t ControlServer::free_slot() const {
  std::array<bool, kMaxClients> used{};
  for (const Client& c : clients_) {
    if (c.has_slot) used[c.slot] = true;
  }
  std::size_t slot = 0;
  while (slot < kMaxClients && used[slot]) ++slot;
  return slot;  // make_room_for_hello keeps the clients with a slot below kMaxClients.
}

void ControlServer::set_subscription(Client& client, int port, double rate_Hz) {
  const std::lock_guard<std::mutex> lock(subscribers_mutex_);
  Subscriber& s = subscribers_[client.slot];
  s.active = port != 0;
  s.address = client.peer.sin_addr;
  s.port = port;
  s.rate_Hz = rate_Hz;
  s.next_frame_s = 0.0;
  client.subscribed = s.active;
}

void ControlServer::update_stream_interval() {
  double fastest = 0.0;
  {
    const std::lock_guard<std::mutex> lock(subscribers_mutex_);
    for (const Subscriber& s : subscribers_) {
      if (s.active) fastest = std::max(fastest, s.rate_Hz);
    }
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
  // Who gets this frame, decided under the lock; the sends happen outside it.
  std::array<sockaddr_in, kMaxClients> targets{};
  std::size_t count = 0;
  {
    const std::lock_guard<std::mutex> lock(subscribers_mutex_);
    for (Subscriber& s : subscribers_) {
      if (!s.active || header.servo_time_s + 1e-6 < s.next_frame_s) continue;
      s.next_frame_s = std::max(s.next_frame_s + 1.0 / s.rate_Hz, header.servo_time_s);
      sockaddr_in& to = targets[count++];
      to.sin_family = AF_INET;
      to.sin_addr = s.address;
      to.sin_port = htons(static_cast<std::uint16_t>(s.port));
    }
  }
  for (std::size_t i = 0; i < count; ++i) {
    const ssize_t n = sendto(udp_fd_, frame.bytes, frame.size, 0,
                             reinterpret_cast<const sockaddr*>(&targets[i]), sizeof(targets[i]));
    if (n == static_cast<ssize_t>(frame.size)) {
      frames_sent_.fetch_add(1, std::memory_order_relaxed);
      send_age_us_->add((monotonic_now_s() - header.servo_time_s) * 1e6);
    } else {
      frames_dropped_.fetch_add(1, std::memory_order_relaxed);
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
  for (const Client& client : clients_) subscribers += client.subscribed ? 1 : 0;
  return {{"connections", c.connections},
          {"clients", clients_.size()},
          {"subscribers", subscribers},
          {"messages", c.messages},
          {"errors", c.errors},
          {"malformed", c.malformed},
          {"oversized", c.oversized},
          {"out_of_order", c.out_of_order},
          {"unauthenticated", c.unauthenticated},
          {"wrong_tokens", c.wrong_tokens},
          {"hello_timeouts", c.hello_timeouts},
          {"waiting_closed", c.waiting_closed},
          {"idle_clients_closed", c.idle_clients_closed},
          {"cut_off_clients", c.cut_off_clients},
          {"frames_sent", frames_sent_.load()},
          {"frames_dropped", frames_dropped_.load()},
          {"stray_datagrams", c.stray_datagrams},
          {"frame_age_at_send_us",
           {{"p50", send_age_us_->percentile_us(0.5)},
            {"p99", send_age_us_->percentile_us(0.99)},
            {"max", send_age_us_->max_us()}}},
          {"stream_source_port", stream_port_}};
}

}  // namespace hapticut::servo
