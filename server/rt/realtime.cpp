#include "rt/realtime.h"

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

namespace {

std::string cpu_name(int cpu) { return "CPU " + std::to_string(cpu); }

}  // namespace

std::string keep_threads_off_cpu(int cpu) {
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  if (pthread_getaffinity_np(pthread_self(), sizeof(allowed), &allowed) != 0) {
    return "cpu: the thread affinity cannot be read; other threads not moved";
  }
  if (cpu < 0 || cpu >= CPU_SETSIZE) {
    return "cpu: " + cpu_name(cpu) + " cannot be named; other threads not moved";
  }
  if (!CPU_ISSET(cpu, &allowed)) {
    return "cpu: other threads already off " + cpu_name(cpu) + " (" +
           std::to_string(CPU_COUNT(&allowed)) + " CPUs for them)";
  }
  CPU_CLR(cpu, &allowed);
  if (CPU_COUNT(&allowed) == 0) {
    return "cpu: " + cpu_name(cpu) + " is the only CPU allowed; other threads share it";
  }
  const int error = pthread_setaffinity_np(pthread_self(), sizeof(allowed), &allowed);
  if (error != 0) {
    return std::string("cpu: other threads could not be kept off ") + cpu_name(cpu) + " (" +
           std::strerror(error) + ")";
  }
  return "cpu: other threads kept off " + cpu_name(cpu) + " (" +
         std::to_string(CPU_COUNT(&allowed)) + " CPUs left for them)";
}

std::string pin_to_cpu(int cpu) {
  if (cpu < 0 || cpu >= CPU_SETSIZE)
    return "cpu: " + cpu_name(cpu) + " cannot be named; not pinned";
  cpu_set_t one;
  CPU_ZERO(&one);
  CPU_SET(cpu, &one);
  const int error = pthread_setaffinity_np(pthread_self(), sizeof(one), &one);
  if (error == 0) return "cpu: loop pinned to " + cpu_name(cpu);
  return "cpu: loop not pinned to " + cpu_name(cpu) + " (" + std::strerror(error) + ")";
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
