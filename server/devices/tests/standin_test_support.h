// The GoogleTest fixture of the tests that drive a device kind against its
// vendor stand-in (dhd_standin.h, hd_standin.h): the stand-in is named to the
// device through its library variable and opened here too (dlopen gives both
// the same instance), so the test scripts it and reads its record of calls.
#pragma once

#include <dlfcn.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <string>
#include <vector>

namespace hapticut::servo {

// `Call` is the stand-in's record of one call (a name, arguments a, b, c).
template <typename Call>
class StandinTest : public ::testing::Test {
 protected:
  // `variable` names the library to the device kind; `library` is the stand-in's
  // file; `prefix` starts its two test symbols (PREFIX_configure, PREFIX_calls).
  StandinTest(const char* variable, const char* library, const char* prefix)
      : variable_(variable), library_(library), prefix_(prefix) {}

  void SetUp() override {
    setenv(variable_, library_, 1);
    handle_ = dlopen(library_, RTLD_NOW | RTLD_LOCAL);
    ASSERT_NE(handle_, nullptr) << dlerror();
    configure_ = reinterpret_cast<Configure>(dlsym(handle_, (prefix_ + "_configure").c_str()));
    calls_ = reinterpret_cast<Calls>(dlsym(handle_, (prefix_ + "_calls").c_str()));
    ASSERT_NE(configure_, nullptr);
    ASSERT_NE(calls_, nullptr);
    configure_("");
  }
  void TearDown() override {
    unsetenv(variable_);
    if (handle_ != nullptr) dlclose(handle_);
  }

  // Resets the stand-in's record and counters and applies `script`.
  void configure(const std::string& script) const { configure_(script.c_str()); }

  std::vector<Call> calls() const {
    // Room for calls a stand-in thread records between the count and the copy.
    std::vector<Call> out(static_cast<std::size_t>(calls_(nullptr, 0)) + 64);
    const int copied =
        std::min(calls_(out.data(), static_cast<int>(out.size())), static_cast<int>(out.size()));
    out.resize(static_cast<std::size_t>(copied));
    return out;
  }
  // Index of the first call named `name` (and with first argument `a`, when
  // given) at or after `from`; -1 when none.
  long first(const std::string& name, long from = 0, double a = -1.0) const {
    const std::vector<Call> all = calls();
    for (long i = from; i < static_cast<long>(all.size()); ++i) {
      const Call& call = all[static_cast<std::size_t>(i)];
      if (name == call.name && (a < 0.0 || call.a == a)) return i;
    }
    return -1;
  }

 private:
  using Configure = void (*)(const char*);
  using Calls = int (*)(Call*, int);

  const char* variable_;
  const char* library_;
  std::string prefix_;
  void* handle_ = nullptr;
  Configure configure_ = nullptr;
  Calls calls_ = nullptr;
};

// A force call's three components all zero.
template <typename Call>
bool is_zero_force(const Call& call) {
  return call.a == 0.0 && call.b == 0.0 && call.c == 0.0;
}

}  // namespace hapticut::servo
