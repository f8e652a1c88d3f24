// SpscRing: a single-producer single-consumer ring of fixed-size byte slots.
// The real-time tick pushes a record (a memcpy, no lock, no allocation); the
// recorder thread pops. A full ring refuses the push and the producer counts
// the drop: the tick never waits for the disk.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace hapticut::servo {

class SpscRing {
 public:
  // Allocates slot_count slots of slot_bytes each (not real-time).
  SpscRing(std::size_t slot_bytes, std::size_t slot_count)
      : slot_bytes_(slot_bytes), slot_count_(slot_count), storage_(slot_bytes * slot_count) {}

  std::size_t slot_bytes() const { return slot_bytes_; }
  std::size_t slot_count() const { return slot_count_; }

  // Producer: a slot to fill, or nullptr when the ring is full.
  unsigned char* begin_push() {
    const std::uint64_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) >= slot_count_) return nullptr;
    return storage_.data() + (head % slot_count_) * slot_bytes_;
  }
  // Producer: publishes the slot begin_push returned.
  void end_push() {
    head_.store(head_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  }

  // Consumer: the oldest filled slot, or nullptr when empty.
  const unsigned char* front() const {
    const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return nullptr;
    return storage_.data() + (tail % slot_count_) * slot_bytes_;
  }
  // Consumer: releases the slot front returned.
  void pop() { tail_.store(tail_.load(std::memory_order_relaxed) + 1, std::memory_order_release); }

 private:
  std::size_t slot_bytes_;
  std::size_t slot_count_;
  std::vector<unsigned char> storage_;
  alignas(64) std::atomic<std::uint64_t> head_{0};
  alignas(64) std::atomic<std::uint64_t> tail_{0};
};

}  // namespace hapticut::servo
