#include "realtime.h"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>

#include <cerrno>
#include <cstring>

namespace hapticut::servo {

std::string enter_realtime_priority(int priority) {
  sched_param param{};
  param.sched_priority = priority;
  const int error = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  if (error == 0) return "real-time: SCHED_FIFO priority " + std::to_string(priority);
  return std::string("real-time: SCHED_FIFO not permitted (") + std::strerror(error) +
         "); running at normal priority";
}

std::string lock_memory() {
  if (mlockall(MCL_CURRENT) == 0) return "memory: locked (mlockall)";
  const int error = errno;
  rlimit limit{};
  getrlimit(RLIMIT_MEMLOCK, &limit);
  std::string limit_text = limit.rlim_cur == RLIM_INFINITY
                               ? std::string("unlimited")
                               : std::to_string(limit.rlim_cur / (1024 * 1024)) + " MiB";
  return std::string("memory: mlockall failed (") + std::strerror(error) + ", RLIMIT_MEMLOCK " +
         limit_text + "); running with unlocked memory";
}

}  // namespace hapticut::servo
