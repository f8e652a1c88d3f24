#include "devices/hid_transport.h"

#include <hidapi.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <mutex>
#include <stdexcept>

namespace hapticut::servo {
namespace {

std::string narrow(const wchar_t* text) {
  std::string out;
  if (text == nullptr) return out;
  for (; *text != L'\0'; ++text) {
    // Product and serial strings are ASCII in practice; anything else becomes '?'.
    out.push_back(*text < 0x80 ? static_cast<char>(*text) : '?');
  }
  return out;
}

void start_hidapi() {
  static std::once_flag once;
  static int result = 0;
  std::call_once(once, [] { result = hid_init(); });
  if (result != 0) throw std::runtime_error("hidapi: hid_init failed");
}

// Why a hidraw node cannot be opened, in words a user can act on.
std::string open_failure(const std::string& path) {
  if (::access(path.c_str(), F_OK) != 0) return path + ": no such device (unplugged?)";
  if (::access(path.c_str(), R_OK | W_OK) != 0) {
    const int error = errno;
    if (error == EACCES || error == EPERM) {
      return path +
             ": permission denied (the servo needs read and write access; install the udev rule "
             "of docs/devices.md, then unplug and replug the device)";
    }
    return path + ": " + std::strerror(error);
  }
  const wchar_t* reason = hid_error(nullptr);
  return path + ": cannot open" + (reason != nullptr ? " (" + narrow(reason) + ")" : std::string());
}

class HidapiTransport final : public HidTransport {
 public:
  HidapiTransport() { start_hidapi(); }
  ~HidapiTransport() override { close(); }

  std::vector<HidDeviceInfo> enumerate() override {
    std::vector<HidDeviceInfo> devices;
    hid_device_info* list = hid_enumerate(0, 0);
    for (const hid_device_info* d = list; d != nullptr; d = d->next) {
      HidDeviceInfo info;
      info.path = d->path != nullptr ? d->path : "";
      info.vendor_id = d->vendor_id;
      info.product_id = d->product_id;
      info.serial = narrow(d->serial_number);
      info.manufacturer = narrow(d->manufacturer_string);
      info.product = narrow(d->product_string);
      info.usage_page = d->usage_page;
      info.usage = d->usage;
      info.interface_number = d->interface_number;
      devices.push_back(std::move(info));
    }
    hid_free_enumeration(list);
    return devices;
  }

  bool open(const std::string& path, std::string& error) override {
    close();
    device_ = hid_open_path(path.c_str());
    if (device_ == nullptr) {
      error = open_failure(path);
      return false;
    }
    return true;
  }

  bool is_open() const override { return device_ != nullptr; }

  int read(std::uint8_t* buffer, std::size_t capacity, int timeout_ms) override {
    if (device_ == nullptr) return -1;
    return hid_read_timeout(device_, buffer, capacity, timeout_ms);
  }

  int write(const std::uint8_t* bytes, std::size_t length) override {
    if (device_ == nullptr) return -1;
    return hid_write(device_, bytes, length);
  }

  void close() override {
    if (device_ != nullptr) hid_close(device_);
    device_ = nullptr;
  }

 private:
  hid_device* device_ = nullptr;
};

}  // namespace

std::unique_ptr<HidTransport> make_hidapi_transport() {
  return std::make_unique<HidapiTransport>();
}

std::string hidapi_version_string() {
#if HID_API_VERSION >= HID_API_MAKE_VERSION(0, 10, 0)
  return hid_version_str();
#else
  return HID_API_VERSION_STR;
#endif
}

}  // namespace hapticut::servo
