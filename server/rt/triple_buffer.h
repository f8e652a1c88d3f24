// TripleBuffer<T>: newest-wins handoff of a large value from one writer to
// one reader without a lock or a copy: the writer fills back(), publish()
// swaps it with the middle slot; the reader's fetch() swaps the middle slot
// with its front() when a new value is there. The servo hands stream frames
// (up to 64 KB) from the real-time tick to the network thread this way.
#pragma once

#include <atomic>
#include <cstdint>

namespace hapticut::servo {

template <typename T>
class TripleBuffer {
 public:
  // Writer.
  T& back() { return slots_[back_]; }
  void publish() { back_ = middle_.exchange(back_ | kNew, std::memory_order_acq_rel) & kIndex; }
  // Reader: true when a newer value than front() was published (it now is front()).
  bool fetch() {
    if ((middle_.load(std::memory_order_relaxed) & kNew) == 0) return false;
    front_ = middle_.exchange(front_, std::memory_order_acq_rel) & kIndex;
    return true;
  }
  const T& front() const { return slots_[front_]; }
  T& front() { return slots_[front_]; }

 private:
  static constexpr std::uint32_t kNew = 4;
  static constexpr std::uint32_t kIndex = 3;
  T slots_[3]{};
  std::uint32_t back_ = 0;   // Writer's.
  std::uint32_t front_ = 1;  // Reader's.
  std::atomic<std::uint32_t> middle_{2};
};

}  // namespace hapticut::servo
