// What the vendor stand-ins (dhd_standin.cpp, hd_standin.cpp) share: their
// scripts' text ("key=value,key=value"), a point in it ("X:Y:Z"), and the
// clock their call records are stamped with. Header-only: each stand-in is a
// shared library of its own, built from one source file.
#pragma once

#include <time.h>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace hapticut_standin {

// Calls `apply(key, value, number)` for each "key=value" pair of `text`, in
// order; `number` is the value read as a number (0 where it is none). Pairs
// without '=' are passed over.
template <typename Apply>
void for_each_pair(const std::string& text, Apply apply) {
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find(',', start);
    if (end == std::string::npos) end = text.size();
    const std::string pair = text.substr(start, end - start);
    start = end + 1;
    const std::size_t eq = pair.find('=');
    if (eq == std::string::npos) continue;
    const std::string value = pair.substr(eq + 1);
    apply(pair.substr(0, eq), value, std::strtod(value.c_str(), nullptr));
  }
}

inline bool parse_xyz(const std::string& text, double out[3]) {
  return std::sscanf(text.c_str(), "%lf:%lf:%lf", &out[0], &out[1], &out[2]) == 3;
}

// CLOCK_MONOTONIC in seconds, the servo's clock (rt/clock.h), so that a
// record's times compare with the servo's own.
inline double now_s() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

}  // namespace hapticut_standin
