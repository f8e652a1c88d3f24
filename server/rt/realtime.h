// Real-time settings of the loop thread: SCHED_FIFO and locked memory, each
// where permitted. Each returns one line saying what happened; the servo
// prints it and runs on either way.
#pragma once

#include <string>

namespace hapticut::servo {

// SCHED_FIFO at `priority` (1-99) for the calling thread.
std::string enter_realtime_priority(int priority);
// mlockall(MCL_CURRENT): the scene, the blades and the buffers already
// allocated stay in RAM. MCL_FUTURE is not asked for: with a small
// RLIMIT_MEMLOCK it would make later allocations (the next scene) fail.
std::string lock_memory();

// --cpu: the loop thread alone on one CPU, so that it keeps its caches (a
// 500-point blade's proxies and the mesh they walk fill most of L2) and no
// thread of the servo's own wakes on its CPU. keep_threads_off_cpu runs on
// the main thread before any other thread starts (threads inherit its
// affinity); pin_to_cpu runs on the loop thread. Each returns one line; where
// the CPU is not available or the mask cannot be set, nothing changes and
// the line says why.
std::string keep_threads_off_cpu(int cpu);
std::string pin_to_cpu(int cpu);

}  // namespace hapticut::servo
