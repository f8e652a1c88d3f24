// LoadWorker: one job at a time on a thread of its own, for the control
// server's `load` (reading, parsing and building a scene takes seconds for a
// large one, and the control thread must go on answering the other clients
// meanwhile). The control thread starts a job, learns that it ended through
// wake_fd() (for its poll), and takes the result or the job's exception. A job
// checks LoadStop between its stages; stop() asks it to end and waits a
// bounded time, then leaves a job still inside a stage to end alone: its
// thread owns everything it touches, so the process may exit without it.
#pragma once

#include <sys/eventfd.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>
#include <utility>

namespace hapticut::servo {

// Thrown by LoadStop::check once the job was asked to stop.
class LoadCancelled : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What a job sees of a request to stop it.
class LoadStop {
 public:
  explicit LoadStop(const std::atomic<bool>& requested) : requested_(requested) {}
  bool requested() const { return requested_.load(); }
  // Between two stages: throws LoadCancelled when asked to stop.
  void check() const {
    if (requested()) throw LoadCancelled("the load was cancelled");
  }

 private:
  const std::atomic<bool>& requested_;
};

template <typename Result>
class LoadWorker {
 public:
  using Job = std::function<Result(const LoadStop&)>;

  LoadWorker() : state_(std::make_shared<State>()) {}
  ~LoadWorker() { stop(0.0); }
  LoadWorker(const LoadWorker&) = delete;
  LoadWorker& operator=(const LoadWorker&) = delete;

  // A job was started and its end not yet taken.
  bool busy() const { return thread_.joinable(); }
  // Starts `job` on a new thread; std::logic_error when busy.
  void start(Job job) {
    if (busy()) throw std::logic_error("a load is already running");
    thread_ = std::thread([state = state_, job = std::move(job)] {
      std::optional<Result> result;
      std::exception_ptr error;
      try {
        result.emplace(job(LoadStop(state->stop_requested)));
      } catch (...) {
        error = std::current_exception();
      }
      const std::lock_guard<std::mutex> lock(state->mutex);
      state->result = std::move(result);
      state->error = error;
      state->finished = true;
      state->ended.notify_all();
      const std::uint64_t one = 1;
      (void)!write(state->wake_fd, &one, sizeof(one));
    });
  }
  // The job has returned or thrown: take() will not wait.
  bool finished() const {
    const std::lock_guard<std::mutex> lock(state_->mutex);
    return state_->finished;
  }
  // The finished job's result, or its exception rethrown; the worker is free
  // again. Call only when finished().
  Result take() {
    thread_.join();
    std::optional<Result> result;
    std::exception_ptr error;
    {
      const std::lock_guard<std::mutex> lock(state_->mutex);
      result = std::move(state_->result);
      error = state_->error;
    }
    state_ = std::make_shared<State>();
    if (error) std::rethrow_exception(error);
    return std::move(*result);
  }
  // The job stops at its next LoadStop::check (nothing when none runs: the
  // next job starts with a request of its own).
  void cancel() {
    if (busy()) state_->stop_requested.store(true);
  }
  // Cancels the job and waits at most wait_s for it to end. True: no job is
  // left (none ran, or it ended and its result was dropped); false: the job
  // is still inside a stage, and its thread is left to end alone.
  bool stop(double wait_s) {
    if (!busy()) return true;
    cancel();
    std::unique_lock<std::mutex> lock(state_->mutex);
    const bool ended = state_->ended.wait_for(lock, std::chrono::duration<double>(wait_s),
                                              [this] { return state_->finished; });
    lock.unlock();
    if (ended) {
      thread_.join();
    } else {
      thread_.detach();
    }
    state_ = std::make_shared<State>();
    return ended;
  }
  // Readable once the job has ended (for poll); after take() or stop(), the
  // next job's (ask again each time).
  int wake_fd() const { return state_->wake_fd; }

 private:
  // Shared with the job's thread, so that a thread left to end alone never
  // touches the worker or the server it belonged to.
  struct State {
    State() : wake_fd(eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
      if (wake_fd < 0) throw std::runtime_error("eventfd failed");
    }
    ~State() { close(wake_fd); }
    State(const State&) = delete;
    State& operator=(const State&) = delete;

    std::atomic<bool> stop_requested{false};
    std::mutex mutex;
    std::condition_variable ended;
    bool finished = false;
    std::optional<Result> result;
    std::exception_ptr error;
    int wake_fd = -1;
  };

  std::shared_ptr<State> state_;
  std::thread thread_;
};

}  // namespace hapticut::servo
