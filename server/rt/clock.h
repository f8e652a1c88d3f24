// CLOCK_MONOTONIC in seconds and the absolute-time sleep the loop wakes with.
// clock_gettime goes through the vDSO: no system call on Linux x86-64.
#pragma once

#include <cerrno>
#include <cmath>
#include <ctime>

namespace hapticut::servo {

inline double monotonic_now_s() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return double(ts.tv_sec) + double(ts.tv_nsec) * 1e-9;
}

inline timespec to_timespec(double t_s) {
  timespec ts{};
  double whole = 0.0;
  const double fraction = std::modf(t_s, &whole);
  ts.tv_sec = static_cast<time_t>(whole);
  ts.tv_nsec = static_cast<long>(fraction * 1e9);
  if (ts.tv_nsec >= 1000000000L) {
    ts.tv_sec += 1;
    ts.tv_nsec -= 1000000000L;
  }
  return ts;
}

// Sleeps until the absolute CLOCK_MONOTONIC time deadline_s (restarted on EINTR).
inline void sleep_until(double deadline_s) {
  const timespec ts = to_timespec(deadline_s);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace hapticut::servo
