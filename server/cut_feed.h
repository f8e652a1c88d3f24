// CutFeed: the session's cut tets, in the order they were cut, for the threads
// beside the loop (the control thread's `cuts` and `save_cuts`): the loop (or
// the control thread while no loop runs) is its one writer and brings it up
// to the engine's CutState after every tick; readers copy any part of it
// without a lock and without ever holding the writer up. Appending publishes
// each entry before the count that covers it; replacing the set (a reset, a
// load) runs under a sequence count that a reader checks after its copy,
// retrying when the set changed under it.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "hapticut/cut_state.h"

namespace hapticut::servo {

class CutFeed {
 public:
  // Room for every tet of the scene (each is cut at most once).
  explicit CutFeed(std::size_t tets);

  // The writer: appends what `cuts` has cut since the last call, or replaces
  // the whole set when `cuts` was reset or set since. Never allocates.
  void follow(const CutState& cuts);

  struct Part {
    std::uint32_t generation = 0;  // CutState::generation of the set read.
    std::uint32_t total = 0;       // Tets cut in that set.
  };
  // Any thread: at most `most` entries from index `from` on, into `out`.
  Part read(std::uint32_t from, std::uint32_t most, std::vector<std::int32_t>& out) const;

 private:
  std::size_t capacity_;
  std::unique_ptr<std::atomic<std::int32_t>[]> entries_;
  std::atomic<std::uint32_t> count_{0};
  std::atomic<std::uint32_t> generation_{0};
  std::atomic<std::uint64_t> replacing_{0};  // Odd while the set is being replaced.
};

}  // namespace hapticut::servo
