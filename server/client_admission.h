// Who keeps a control connection when many are open: the rules that let the
// rightful client in whatever other local processes do. A connection that
// has not said hello holds no client slot, waits at most kHelloDeadline_s and
// may send only a small message; when too many wait, the oldest is closed.
// A hello that finds every client slot taken closes the client idle longest.
// A wrong token is answered after kWrongTokenDelay_s, one try per connection,
// and never locks out the right token: the token's length is what makes
// guessing hopeless (kMinTokenBytes).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace hapticut::servo {

// Clients that said hello: each has a stream slot.
inline constexpr std::size_t kMaxClients = 16;
// Connections waiting for their hello; the oldest is closed for a new one.
inline constexpr std::size_t kMaxWaitingConnections = 256;
// A connection accepted this long ago without a successful hello is closed.
inline constexpr double kHelloDeadline_s = 5.0;
// Accepted per round of the control thread, so that a connection lives at
// least kMaxWaitingConnections / kAcceptsPerRound rounds, each of which reads
// it, before a flood of newer ones can close it.
inline constexpr std::size_t kAcceptsPerRound = 64;
// The largest message before hello: a hello with a token of kMaxTokenBytes fits.
inline constexpr std::uint32_t kMaxHelloMessageBytes = 8192;
// A wrong token's refusal waits this long (the connection then closes).
inline constexpr double kWrongTokenDelay_s = 0.5;
// A token shorter than this is refused at start.
inline constexpr std::size_t kMinTokenBytes = 16;

inline constexpr std::size_t kNoConnection = static_cast<std::size_t>(-1);

// What admission needs to know of a connection.
struct ConnectionTimes {
  bool said_hello = false;
  bool closing = false;  // Already on its way out: never chosen, never counted.
  double accepted_s = 0.0;
  double last_message_s = 0.0;  // The last whole message it sent (accepted_s before one).
};

// The waiting connection to close so that a new one fits (the oldest
// accepted), or kNoConnection when fewer than kMaxWaitingConnections wait.
std::size_t waiting_connection_to_close(const std::vector<ConnectionTimes>& connections);

// The client to close so that a new hello fits (the one whose last message is
// oldest), or kNoConnection when fewer than kMaxClients said hello.
std::size_t client_to_close_for_hello(const std::vector<ConnectionTimes>& connections);

}  // namespace hapticut::servo
