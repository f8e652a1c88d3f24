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

}  // namespace hapticut::servo
