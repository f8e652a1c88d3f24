// HidTransport: the few hidapi calls the HID device makes, behind an
// interface, so the device's parser and reconnection logic run unchanged
// over a scripted transport in the tests (recorded bytes, a device that
// vanishes and comes back). make_hidapi_transport() is the real one.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace hapticut::servo {

// One enumerated HID interface (a device may have several).
struct HidDeviceInfo {
  std::string path;  // "/dev/hidraw3" with the hidraw backend; changes on replug.
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::string serial;
  std::string manufacturer;
  std::string product;
  std::uint16_t usage_page = 0;
  std::uint16_t usage = 0;
  int interface_number = -1;
};

class HidTransport {
 public:
  virtual ~HidTransport() = default;
  HidTransport() = default;
  HidTransport(const HidTransport&) = delete;
  HidTransport& operator=(const HidTransport&) = delete;

  // Every HID interface present. Throws std::runtime_error if hidapi cannot start.
  virtual std::vector<HidDeviceInfo> enumerate() = 0;
  // Opens `path`; on failure returns false and `error` names the path and the
  // reason ("/dev/hidraw3: permission denied (needs read and write ...)").
  virtual bool open(const std::string& path, std::string& error) = 0;
  virtual bool is_open() const = 0;
  // One report into `buffer`, waiting at most timeout_ms (0: never waits).
  // Returns its length, 0 when none is pending, -1 when the device failed
  // (unplugged): the caller closes it.
  virtual int read(std::uint8_t* buffer, std::size_t capacity, int timeout_ms) = 0;
  // One output report, the report id first. Returns bytes written, -1 on failure.
  virtual int write(const std::uint8_t* bytes, std::size_t length) = 0;
  virtual void close() = 0;
};

// hidapi's hidraw backend. hid_init() once per process.
std::unique_ptr<HidTransport> make_hidapi_transport();

// "0.13.1": the hidapi the servo was built against.
std::string hidapi_version_string();

}  // namespace hapticut::servo
