// Who keeps a control connection when many are open (client_admission.h).
#include "client_admission.h"

#include <gtest/gtest.h>

namespace hapticut::servo {
namespace {

std::vector<ConnectionTimes> waiting(std::size_t count) {
  std::vector<ConnectionTimes> connections;
  for (std::size_t i = 0; i < count; ++i) {
    const double t = 10.0 - static_cast<double>(i);  // The last is the oldest.
    connections.push_back({false, false, t, t});
  }
  return connections;
}

TEST(ClientAdmission, TheOldestWaitingConnectionMakesRoomOnlyWhenFull) {
  std::vector<ConnectionTimes> connections = waiting(kMaxWaitingConnections - 1);
  EXPECT_EQ(waiting_connection_to_close(connections), kNoConnection);
  connections = waiting(kMaxWaitingConnections);
  EXPECT_EQ(waiting_connection_to_close(connections), kMaxWaitingConnections - 1);
  // Clients that said hello are never closed for a waiting one, nor counted.
  connections.back().said_hello = true;
  EXPECT_EQ(waiting_connection_to_close(connections), kNoConnection);
}

TEST(ClientAdmission, ConnectionsOnTheirWayOutAreNotCounted) {
  std::vector<ConnectionTimes> connections = waiting(kMaxWaitingConnections);
  connections.front().closing = true;
  EXPECT_EQ(waiting_connection_to_close(connections), kNoConnection);
}

TEST(ClientAdmission, ANewHelloClosesTheClientIdleLongest) {
  std::vector<ConnectionTimes> connections;
  for (std::size_t i = 0; i < kMaxClients; ++i) {
    connections.push_back({true, false, 0.0, 100.0 + static_cast<double>(i)});
  }
  connections[7].last_message_s = 50.0;
  connections.push_back({false, false, 200.0, 200.0});  // The one saying hello.
  EXPECT_EQ(client_to_close_for_hello(connections), 7U);
  connections[3].closing = true;
  EXPECT_EQ(client_to_close_for_hello(connections), kNoConnection);
}

}  // namespace
}  // namespace hapticut::servo
