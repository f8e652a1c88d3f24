// LatestValue<T>: one writer thread publishes a trivially copyable value, any
// number of reader threads take the newest copy, nobody waits on a lock
// (a sequence lock). The servo hands device samples, snapshots and settings
// between its threads through these, so the real-time tick never blocks.
#pragma once

#include <atomic>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace hapticut::servo {

template <typename T>
class LatestValue {
  static_assert(std::is_trivially_copyable_v<T>, "LatestValue holds plain data only");

 public:
  // Writer only (one thread).
  void publish(const T& value) {
    const std::uint64_t s = sequence_.load(std::memory_order_relaxed);
    sequence_.store(s + 1, std::memory_order_relaxed);  // Odd: writing.
    std::atomic_thread_fence(std::memory_order_release);
    copy_words(words_, reinterpret_cast<const unsigned char*>(&value));
    sequence_.store(s + 2, std::memory_order_release);  // Even: done.
  }

  // Readers: copies the newest complete value into `out` and returns how many
  // values were published so far (0: none yet, `out` untouched). Retries only
  // while a write is in progress, which lasts a copy of sizeof(T) bytes.
  std::uint64_t read(T& out) const {
    for (;;) {
      const std::uint64_t before = sequence_.load(std::memory_order_acquire);
      if (before == 0) return 0;
      if (before & 1U) continue;
      unsigned char buffer[sizeof(T)];
      copy_words_out(buffer);
      std::atomic_thread_fence(std::memory_order_acquire);
      if (sequence_.load(std::memory_order_relaxed) == before) {
        std::memcpy(&out, buffer, sizeof(T));
        return before / 2;
      }
    }
  }

 private:
  static constexpr std::size_t kWords = (sizeof(T) + 7) / 8;
  // Relaxed atomic words: a torn read is detected by the sequence, never a data race.
  static void copy_words(std::atomic<std::uint64_t>* words, const unsigned char* bytes) {
    for (std::size_t i = 0; i < kWords; ++i) {
      std::uint64_t word = 0;
      const std::size_t n = (i + 1) * 8 <= sizeof(T) ? 8 : sizeof(T) - i * 8;
      std::memcpy(&word, bytes + i * 8, n);
      words[i].store(word, std::memory_order_relaxed);
    }
  }
  void copy_words_out(unsigned char* bytes) const {
    for (std::size_t i = 0; i < kWords; ++i) {
      const std::uint64_t word = words_[i].load(std::memory_order_relaxed);
      const std::size_t n = (i + 1) * 8 <= sizeof(T) ? 8 : sizeof(T) - i * 8;
      std::memcpy(bytes + i * 8, &word, n);
    }
  }

  std::atomic<std::uint64_t> sequence_{0};
  std::atomic<std::uint64_t> words_[kWords]{};
};

}  // namespace hapticut::servo
