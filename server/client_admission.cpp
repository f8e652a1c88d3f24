#include "client_admission.h"

namespace hapticut::servo {

namespace {

// The connection of the given kind that is least recent by `key`, and how many of that kind
// are open (those already closing are neither chosen nor counted).
template <typename Key>
std::size_t least_recent(const std::vector<ConnectionTimes>& connections, bool said_hello,
                         std::size_t limit, Key key) {
  std::size_t count = 0;
  std::size_t chosen = kNoConnection;
  for (std::size_t i = 0; i < connections.size(); ++i) {
    const ConnectionTimes& c = connections[i];
    if (c.closing || c.said_hello != said_hello) continue;
    ++count;
    if (chosen == kNoConnection || key(c) < key(connections[chosen])) chosen = i;
  }
  return count >= limit ? chosen : kNoConnection;
}

}  // namespace

std::size_t waiting_connection_to_close(const std::vector<ConnectionTimes>& connections) {
  return least_recent(connections, false, kMaxWaitingConnections,
                      [](const ConnectionTimes& c) { return c.accepted_s; });
}

std::size_t client_to_close_for_hello(const std::vector<ConnectionTimes>& connections) {
  return least_recent(connections, true, kMaxClients,
                      [](const ConnectionTimes& c) { return c.last_message_s; });
}

}  // namespace hapticut::servo
