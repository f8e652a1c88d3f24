// LatencyHistogram: durations (microseconds) in logarithmic bins 2 % wide,
// from 0.01 us to about 10 s. One writer (the real-time thread) adds with
// relaxed atomic stores: no lock, no allocation, a fixed array; any thread
// reads percentiles. A percentile is the upper edge of its bin (at most 2 %
// high); the maximum is exact.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>

namespace hapticut::servo {

class LatencyHistogram {
 public:
  static constexpr double kLowest_us = 0.01;
  static constexpr double kGrowth = 1.02;
  static constexpr int kBins = 1400;  // 0.01 us * 1.02^1400 ~ 10^10 us.

  // Writer thread only.
  void add(double value_us) {
    const int bin = bin_of(value_us);
    bins_[bin].store(bins_[bin].load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    count_.store(count_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    if (value_us > max_us_.load(std::memory_order_relaxed)) {
      max_us_.store(value_us, std::memory_order_relaxed);
    }
  }

  // Writer thread only, outside a run.
  void clear() {
    for (auto& b : bins_) b.store(0, std::memory_order_relaxed);
    count_.store(0, std::memory_order_relaxed);
    max_us_.store(0.0, std::memory_order_relaxed);
  }

  std::uint64_t count() const { return count_.load(std::memory_order_relaxed); }
  double max_us() const { return max_us_.load(std::memory_order_relaxed); }

  // The value below which a fraction `quantile` (0..1) of the samples lie.
  double percentile_us(double quantile) const {
    const std::uint64_t n = count();
    if (n == 0) return 0.0;
    const auto wanted =
        static_cast<std::uint64_t>(std::ceil(std::clamp(quantile, 0.0, 1.0) * double(n)));
    std::uint64_t seen = 0;
    for (int i = 0; i < kBins; ++i) {
      seen += bins_[i].load(std::memory_order_relaxed);
      if (seen >= std::max<std::uint64_t>(wanted, 1)) {
        return std::min(upper_edge_us(i), max_us());
      }
    }
    return max_us();
  }

  // The same in whole nanoseconds, as the devices' status counters give it.
  std::uint64_t percentile_ns(double quantile) const {
    return static_cast<std::uint64_t>(std::llround(percentile_us(quantile) * 1e3));
  }

  static int bin_of(double value_us) {
    if (!(value_us > kLowest_us)) return 0;
    const int bin = static_cast<int>(std::log(value_us / kLowest_us) / std::log(kGrowth)) + 1;
    return std::min(bin, kBins - 1);
  }
  static double upper_edge_us(int bin) { return kLowest_us * std::pow(kGrowth, bin); }

 private:
  std::array<std::atomic<std::uint64_t>, kBins> bins_{};
  std::atomic<std::uint64_t> count_{0};
  std::atomic<double> max_us_{0.0};
};

}  // namespace hapticut::servo
