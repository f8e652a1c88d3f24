// The control server's load worker (load_worker.h): one job at a time, its end
// seen through the wake descriptor, its result or exception taken on the
// caller's thread, a cancel seen between stages, and a stop that never waits
// for a job stuck inside a stage. Also the stages of a Session, where a load
// stops when asked. Under ThreadSanitizer (tests/scripts/tsan.sh) a missing
// ordering between the job's thread and the caller is also a report.
#include "load_worker.h"

#include <gtest/gtest.h>
#include <poll.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

#include "session_load.h"

namespace hapticut::servo {
namespace {

const std::string kScene = std::string(HAPTICUT_EXAMPLES_DIR) + "/sphere320.hapticut.msgpack";

// Waits (a liveness bound, not a timing claim) until the worker's wake
// descriptor says the job ended.
bool woken(int fd) {
  pollfd p{fd, POLLIN, 0};
  return poll(&p, 1, 30000) == 1 && (p.revents & POLLIN);
}

// Released by the test: a job waiting on it is inside one stage.
struct Gate {
  std::atomic<bool> open{false};
  void wait() const {
    while (!open.load()) std::this_thread::yield();
  }
};

TEST(LoadWorker, TheResultIsTakenOnceTheWakeDescriptorSaysTheJobEnded) {
  LoadWorker<int> worker;
  EXPECT_FALSE(worker.busy());
  worker.start([](const LoadStop&) { return 42; });
  EXPECT_TRUE(worker.busy());
  ASSERT_TRUE(woken(worker.wake_fd()));
  EXPECT_TRUE(worker.finished());
  EXPECT_EQ(worker.take(), 42);
  EXPECT_FALSE(worker.busy());
  // A new job has its own descriptor, not yet readable.
  pollfd p{worker.wake_fd(), POLLIN, 0};
  EXPECT_EQ(poll(&p, 1, 0), 0);
}

TEST(LoadWorker, AJobsExceptionIsRethrownByTake) {
  LoadWorker<int> worker;
  worker.start([](const LoadStop&) -> int { throw std::invalid_argument("no such scene"); });
  ASSERT_TRUE(woken(worker.wake_fd()));
  EXPECT_THROW(worker.take(), std::invalid_argument);
  EXPECT_FALSE(worker.busy());
}

TEST(LoadWorker, OneJobAtATime) {
  LoadWorker<int> worker;
  auto gate = std::make_shared<Gate>();
  worker.start([gate](const LoadStop&) {
    gate->wait();
    return 1;
  });
  EXPECT_THROW(worker.start([](const LoadStop&) { return 2; }), std::logic_error);
  gate->open.store(true);
  ASSERT_TRUE(woken(worker.wake_fd()));
  EXPECT_EQ(worker.take(), 1);
  worker.start([](const LoadStop&) { return 3; });
  ASSERT_TRUE(woken(worker.wake_fd()));
  EXPECT_EQ(worker.take(), 3);
}

TEST(LoadWorker, ACancelledJobEndsAtItsNextStage) {
  LoadWorker<int> worker;
  worker.start([](const LoadStop& stop) {
    for (;;) {
      stop.check();  // Between stages.
      std::this_thread::yield();
    }
    return 0;
  });
  worker.cancel();
  ASSERT_TRUE(woken(worker.wake_fd()));
  EXPECT_THROW(worker.take(), LoadCancelled);
}

TEST(LoadWorker, ACancelWithNoJobLeavesTheNextJobAlone) {
  LoadWorker<int> worker;
  worker.cancel();
  worker.start([](const LoadStop& stop) {
    stop.check();
    return 7;
  });
  ASSERT_TRUE(woken(worker.wake_fd()));
  EXPECT_EQ(worker.take(), 7);
}

TEST(LoadWorker, StopJoinsAJobThatReachesItsNextStage) {
  LoadWorker<int> worker;
  worker.start([](const LoadStop& stop) {
    for (;;) {
      stop.check();
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return 0;
  });
  EXPECT_TRUE(worker.stop(30.0));
  EXPECT_FALSE(worker.busy());
}

TEST(LoadWorker, StopLeavesAJobInsideAStageToEndAlone) {
  auto gate = std::make_shared<Gate>();
  auto ended = std::make_shared<std::atomic<bool>>(false);
  {
    LoadWorker<int> worker;
    worker.start([gate, ended](const LoadStop& stop) {
      gate->wait();  // One long stage: no check inside it.
      ended->store(true);
      stop.check();
      return 0;
    });
    // The gate is shut: stop cannot have waited for the stage to end.
    EXPECT_FALSE(worker.stop(0.05));
    EXPECT_FALSE(worker.busy());
    EXPECT_FALSE(ended->load());
  }
  // The worker is gone; the job's thread ends without it.
  gate->open.store(true);
  while (!ended->load()) std::this_thread::yield();
}

TEST(LoadWorker, ASessionIsBuiltInStagesAndStopsBetweenThem) {
  SessionConfig config;
  config.scene_path = kScene;
  config.devices = {"scalpel=sim"};
  int stages = 0;
  const PreparedLoad prepared = prepare_load(config, 1.0, [&stages] { ++stages; });
  ASSERT_NE(prepared.session, nullptr);
  ASSERT_NE(prepared.recorder, nullptr);
  // Read, parsed, the Space, the shading, one blade.
  EXPECT_EQ(stages, 5);
  for (int stop_at = 1; stop_at <= stages; ++stop_at) {
    int seen = 0;
    EXPECT_THROW(prepare_load(config, 1.0,
                              [&] {
                                if (++seen == stop_at) throw LoadCancelled("cancelled");
                              }),
                 LoadCancelled)
        << "stage " << stop_at;
    EXPECT_EQ(seen, stop_at);
  }
}

}  // namespace
}  // namespace hapticut::servo
