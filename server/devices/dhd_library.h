// DhdLibrary: Force Dimension's DHD library (dhd_api.h) loaded with dlopen at
// run time, so that the servo builds and runs without the SDK and only a
// forcedimension binding needs it. Where it looks, in order: the path in
// $HAPTICUT_DHD_LIB, then libdhd.so, libdhd.so.3, libdrd.so, libdrd.so.3
// through the dynamic loader's own search (LD_LIBRARY_PATH, ld.so.cache; the
// SDK's lib/release/lin-*-gcc folder is on neither until installed or named).
// libdrd carries libdhd's calls too. dhdSetWatchdog and dhdGetWatchdog are
// optional: a library before SDK 3.3.2 lacks them and still loads, the
// pointers left null (the device then runs without the firmware's watchdog).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "devices/dhd_api.h"

namespace hapticut::servo {

// The environment variable naming the library's file.
inline constexpr const char* kDhdLibraryVariable = "HAPTICUT_DHD_LIB";
// The names dlopen tries after it.
const std::vector<std::string>& dhd_library_names();

struct DhdLibrary {
  dhd::GetDeviceCount get_device_count = nullptr;
  dhd::OpenId open_id = nullptr;
  dhd::GetSystemType get_system_type = nullptr;
  dhd::EnableForce enable_force = nullptr;
  dhd::GetPosition get_position = nullptr;
  dhd::GetOrientationFrame get_orientation_frame = nullptr;
  dhd::GetButtonMask get_button_mask = nullptr;
  dhd::GetStatus get_status = nullptr;
  dhd::SetForce set_force = nullptr;
  dhd::GetMaxForce get_max_force = nullptr;
  dhd::ErrorGetLast error_get_last = nullptr;
  dhd::ErrorGetLastStr error_get_last_str = nullptr;
  dhd::Stop stop = nullptr;
  dhd::Close close = nullptr;
  // Optional (null: the library predates them).
  dhd::SetWatchdog set_watchdog = nullptr;
  dhd::GetWatchdog get_watchdog = nullptr;

  std::string path;        // The file loaded (as the loader resolved it).
  void* handle = nullptr;  // dlopen's; closed with the last reference.

  DhdLibrary() = default;
  DhdLibrary(const DhdLibrary&) = delete;
  DhdLibrary& operator=(const DhdLibrary&) = delete;
  ~DhdLibrary();

  // "dhdOpenID failed: <dhdErrorGetLastStr()> (error N)": the calling thread's last error.
  std::string last_error(const char* call) const;
};

// The library, or nullptr and `error` saying what to install or set: no file
// found (each name tried, with dlerror()), a file that does not load
// (dlerror(): a wrong architecture, a missing dependency), a symbol missing
// (an SDK too old or not DHD's); an optional one missing is no error.
std::shared_ptr<DhdLibrary> load_dhd_library(std::string& error);

}  // namespace hapticut::servo
