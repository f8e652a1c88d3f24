#include "devices/dhd_library.h"

#include "devices/vendor_library.h"

namespace hapticut::servo {

const std::vector<std::string>& dhd_library_names() {
  static const std::vector<std::string> names = {"libdhd.so", "libdhd.so.3", "libdrd.so",
                                                 "libdrd.so.3"};
  return names;
}

DhdLibrary::~DhdLibrary() {
  if (handle != nullptr) dlclose(handle);
}

std::string DhdLibrary::last_error(const char* call) const {
  const int code = error_get_last();
  const char* text = error_get_last_str();
  return std::string(call) + " failed: " + (text != nullptr && *text ? text : "no description") +
         " (DHD error " + std::to_string(code) + ")";
}

std::shared_ptr<DhdLibrary> load_dhd_library(std::string& error) {
  const VendorLibrarySearch search{
      "forcedimension",
      "Force Dimension's DHD library",
      kDhdLibraryVariable,
      dhd_library_names(),
      std::string("install the Force Dimension SDK (https://forcedimension.com/software/sdk) "
                  "and put its lib/release/lin-*-gcc folder on LD_LIBRARY_PATH, or set $") +
          kDhdLibraryVariable + " to its libdhd.so.* file (docs/devices.md)",
      std::string("install Force Dimension's SDK for this machine's architecture, or set $") +
          kDhdLibraryVariable + " to its lib/release/lin-*/libdhd.so.*"};
  auto library = std::make_shared<DhdLibrary>();
  library->handle = open_vendor_library(search, library->path, error);
  if (library->handle == nullptr) return nullptr;
  void* handle = library->handle;
  std::string missing;
  bind_symbol(handle, "dhdGetDeviceCount", library->get_device_count, missing);
  bind_symbol(handle, "dhdOpenID", library->open_id, missing);
  bind_symbol(handle, "dhdGetSystemType", library->get_system_type, missing);
  bind_symbol(handle, "dhdEnableForce", library->enable_force, missing);
  bind_symbol(handle, "dhdGetPosition", library->get_position, missing);
  bind_symbol(handle, "dhdGetOrientationFrame", library->get_orientation_frame, missing);
  bind_symbol(handle, "dhdGetButtonMask", library->get_button_mask, missing);
  bind_symbol(handle, "dhdGetStatus", library->get_status, missing);
  bind_symbol(handle, "dhdSetForce", library->set_force, missing);
  bind_symbol(handle, "dhdGetMaxForce", library->get_max_force, missing);
  bind_symbol(handle, "dhdErrorGetLast", library->error_get_last, missing);
  bind_symbol(handle, "dhdErrorGetLastStr", library->error_get_last_str, missing);
  bind_symbol(handle, "dhdStop", library->stop, missing);
  bind_symbol(handle, "dhdClose", library->close, missing);
  if (!missing.empty()) {
    error = "forcedimension: " + library->path + " lacks " + missing +
            " (not Force Dimension's DHD library, or an SDK older than 3.2: install a current "
            "one)";
    return nullptr;
  }
  std::string optional;
  bind_symbol(handle, "dhdSetWatchdog", library->set_watchdog, optional);
  bind_symbol(handle, "dhdGetWatchdog", library->get_watchdog, optional);
  return library;
}

}  // namespace hapticut::servo
