#include "cut_feed.h"

#include <algorithm>
#include <thread>

namespace hapticut::servo {

CutFeed::CutFeed(std::size_t tets)
    : capacity_(tets), entries_(std::make_unique<std::atomic<std::int32_t>[]>(tets)) {}

void CutFeed::follow(const CutState& cuts) {
  const std::span<const std::int32_t> order = cuts.cut_order();
  const std::size_t total = std::min(order.size(), capacity_);
  std::uint32_t have = count_.load(std::memory_order_relaxed);
  const bool replaced = cuts.generation() != generation_.load(std::memory_order_relaxed);
  const std::uint64_t sequence = replacing_.load(std::memory_order_relaxed);
  if (replaced) {
    // A reader that copies any entry written from here on sees the odd count
    // or a changed one after its copy, and retries.
    replacing_.store(sequence + 1, std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_release);
    count_.store(0, std::memory_order_relaxed);
    generation_.store(cuts.generation(), std::memory_order_relaxed);
    have = 0;
  }
  for (std::size_t i = have; i < total; ++i) {
    entries_[i].store(order[i], std::memory_order_relaxed);
  }
  count_.store(static_cast<std::uint32_t>(total), std::memory_order_release);
  if (replaced) replacing_.store(sequence + 2, std::memory_order_release);
}

CutFeed::Part CutFeed::read(std::uint32_t from, std::uint32_t most,
                            std::vector<std::int32_t>& out) const {
  for (;;) {
    const std::uint64_t before = replacing_.load(std::memory_order_acquire);
    if (before % 2 != 0) {  // A replacement is half done (a copy of new entries): let it end.
      std::this_thread::yield();
      continue;
    }
    Part part;
    part.generation = generation_.load(std::memory_order_relaxed);
    part.total = count_.load(std::memory_order_acquire);
    out.clear();
    const std::uint32_t start = std::min(from, part.total);
    const std::uint32_t end = start + std::min(most, part.total - start);
    for (std::uint32_t i = start; i < end; ++i) {
      out.push_back(entries_[i].load(std::memory_order_relaxed));
    }
    std::atomic_thread_fence(std::memory_order_acquire);
    if (replacing_.load(std::memory_order_relaxed) == before) return part;
  }
}

}  // namespace hapticut::servo
