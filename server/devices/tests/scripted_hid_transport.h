// ScriptedHidTransport: a HidTransport that plays recorded reports, for the
// tests. What cannot exist here is the device; the HID device's parser,
// draining and reconnection run unchanged on top of it.
#pragma once

#include <deque>
#include <string>
#include <vector>

#include "devices/hid_transport.h"

namespace hapticut::servo::testing {

class ScriptedHidTransport final : public HidTransport {
 public:
  // What enumerate() lists (a replug may change the path).
  std::vector<HidDeviceInfo> present;
  // Reports the open device will return, oldest first.
  std::deque<std::vector<std::uint8_t>> pending;
  // The next read fails (unplugged): the device vanishes from `present` too.
  bool fail_next_read = false;
  // open() of these paths fails as if permissions were missing.
  std::vector<std::string> unreadable_paths;
  std::vector<std::vector<std::uint8_t>> written;
  std::string opened_path;
  int opens = 0;
  int enumerations = 0;

  std::vector<HidDeviceInfo> enumerate() override {
    ++enumerations;
    return present;
  }
  bool open(const std::string& path, std::string& error) override {
    for (const std::string& p : unreadable_paths) {
      if (p == path) {
        error = path + ": permission denied (the servo needs read and write access)";
        return false;
      }
    }
    for (const HidDeviceInfo& info : present) {
      if (info.path == path) {
        opened_path = path;
        ++opens;
        return true;
      }
    }
    error = path + ": no such device";
    return false;
  }
  bool is_open() const override { return !opened_path.empty(); }
  int read(std::uint8_t* buffer, std::size_t capacity, int /*timeout_ms*/) override {
    if (opened_path.empty()) return -1;
    if (fail_next_read) {
      fail_next_read = false;
      present.clear();
      return -1;
    }
    if (pending.empty()) return 0;
    const std::vector<std::uint8_t> report = pending.front();
    pending.pop_front();
    const std::size_t n = std::min(capacity, report.size());
    std::copy(report.begin(), report.begin() + static_cast<std::ptrdiff_t>(n), buffer);
    return static_cast<int>(n);
  }
  int write(const std::uint8_t* bytes, std::size_t length) override {
    if (opened_path.empty()) return -1;
    written.emplace_back(bytes, bytes + length);
    return static_cast<int>(length);
  }
  void close() override { opened_path.clear(); }
};

inline HidDeviceInfo spacemouse_info(const std::string& path, std::uint16_t product = 0xc62e,
                                     const std::string& serial = "A1B2") {
  HidDeviceInfo info;
  info.path = path;
  info.vendor_id = 0x256f;
  info.product_id = product;
  info.serial = serial;
  info.product = "SpaceMouse Wireless";
  info.usage_page = 0x01;
  info.usage = 0x08;
  info.interface_number = 0;
  return info;
}

}  // namespace hapticut::servo::testing
