#include "devices/hd_library.h"

#include <cstdio>

#include "devices/vendor_library.h"

namespace hapticut::servo {

const std::vector<std::string>& hd_library_names() {
  static const std::vector<std::string> names = {"libHD.so", "libHD.so.3.4", "libHD.so.3.0"};
  return names;
}

HdLibrary::~HdLibrary() {
  if (handle != nullptr) dlclose(handle);
}

std::string HdLibrary::describe(const char* call, const hd::HDErrorInfo& error) const {
  const char* text = get_error_string(error.errorCode);
  char codes[64];
  std::snprintf(codes, sizeof codes, " (HD error 0x%x, device error %d)", error.errorCode,
                error.internalErrorCode);
  return std::string(call) + " failed: " + (text != nullptr && *text ? text : "no description") +
         codes;
}

std::shared_ptr<HdLibrary> load_hd_library(std::string& error) {
  const std::string libraries_hint =
      "; OpenHaptics's libraries need an old ncurses (libncurses.so.5, libtinfo.so.5: "
      "sudo apt install libncurses5, or a compatibility package) and the Touch device "
      "driver (libPhantomIOLib42.so)";
  const VendorLibrarySearch search{
      "openhaptics",
      "3D Systems' OpenHaptics HD library",
      kHdLibraryVariable,
      hd_library_names(),
      std::string("install OpenHaptics for Linux and the Touch device driver from 3D Systems "
                  "(https://support.3dsystems.com/s/article/OpenHaptics-for-Linux-Developer-"
                  "Edition-v34), or set $") +
          kHdLibraryVariable + " to its libHD.so.* file" + libraries_hint + " (docs/devices.md)",
      std::string("a missing file, another architecture, or a library it needs") + libraries_hint};
  auto library = std::make_shared<HdLibrary>();
  library->handle = open_vendor_library(search, library->path, error);
  if (library->handle == nullptr) return nullptr;
  void* handle = library->handle;
  std::string missing;
  bind_symbol(handle, "hdInitDevice", library->init_device, missing);
  bind_symbol(handle, "hdDisableDevice", library->disable_device, missing);
  bind_symbol(handle, "hdMakeCurrentDevice", library->make_current_device, missing);
  bind_symbol(handle, "hdGetCurrentDevice", library->get_current_device, missing);
  bind_symbol(handle, "hdEnable", library->enable, missing);
  bind_symbol(handle, "hdGetDoublev", library->get_doublev, missing);
  bind_symbol(handle, "hdGetIntegerv", library->get_integerv, missing);
  bind_symbol(handle, "hdSetDoublev", library->set_doublev, missing);
  bind_symbol(handle, "hdCheckCalibration", library->check_calibration, missing);
  bind_symbol(handle, "hdUpdateCalibration", library->update_calibration, missing);
  bind_symbol(handle, "hdStartScheduler", library->start_scheduler, missing);
  bind_symbol(handle, "hdStopScheduler", library->stop_scheduler, missing);
  bind_symbol(handle, "hdScheduleAsynchronous", library->schedule_asynchronous, missing);
  bind_symbol(handle, "hdUnschedule", library->unschedule, missing);
  bind_symbol(handle, "hdBeginFrame", library->begin_frame, missing);
  bind_symbol(handle, "hdEndFrame", library->end_frame, missing);
  bind_symbol(handle, "hdGetError", library->get_error, missing);
  bind_symbol(handle, "hdGetErrorString", library->get_error_string, missing);
  if (!missing.empty()) {
    error = "openhaptics: " + library->path + " lacks " + missing +
            " (not OpenHaptics's HD library: install OpenHaptics 3.x)";
    return nullptr;
  }
  return library;
}

}  // namespace hapticut::servo
