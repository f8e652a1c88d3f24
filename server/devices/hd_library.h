// HdLibrary: 3D Systems' OpenHaptics HD library (hd_api.h) loaded with dlopen
// at run time, so that the servo builds and runs without OpenHaptics and only
// an openhaptics binding needs it. Where it looks, in order: the path in
// $HAPTICUT_OPENHAPTICS_LIB, then libHD.so, libHD.so.3.4, libHD.so.3.0
// through the dynamic loader's own search (LD_LIBRARY_PATH, ld.so.cache;
// OpenHaptics for Linux installs into /usr/lib).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "devices/hd_api.h"

namespace hapticut::servo {

// The environment variable naming the library's file.
inline constexpr const char* kHdLibraryVariable = "HAPTICUT_OPENHAPTICS_LIB";
// The names dlopen tries after it.
const std::vector<std::string>& hd_library_names();

struct HdLibrary {
  hd::InitDevice init_device = nullptr;
  hd::DisableDevice disable_device = nullptr;
  hd::MakeCurrentDevice make_current_device = nullptr;
  hd::GetCurrentDevice get_current_device = nullptr;
  hd::Enable enable = nullptr;
  hd::GetDoublev get_doublev = nullptr;
  hd::GetIntegerv get_integerv = nullptr;
  hd::SetDoublev set_doublev = nullptr;
  hd::CheckCalibration check_calibration = nullptr;
  hd::UpdateCalibration update_calibration = nullptr;
  hd::StartScheduler start_scheduler = nullptr;
  hd::StopScheduler stop_scheduler = nullptr;
  hd::ScheduleAsynchronous schedule_asynchronous = nullptr;
  hd::Unschedule unschedule = nullptr;
  hd::BeginFrame begin_frame = nullptr;
  hd::EndFrame end_frame = nullptr;
  hd::GetError get_error = nullptr;
  hd::GetErrorString get_error_string = nullptr;

  std::string path;        // The file loaded (as the loader resolved it).
  void* handle = nullptr;  // dlopen's; closed with the last reference.

  HdLibrary() = default;
  HdLibrary(const HdLibrary&) = delete;
  HdLibrary& operator=(const HdLibrary&) = delete;
  ~HdLibrary();

  // "hdInitDevice failed: <hdGetErrorString> (HD error 0x302, device error N)"
  // for `error`, the calling thread's last HD error.
  std::string describe(const char* call, const hd::HDErrorInfo& error) const;
};

// The library, or nullptr and `error` saying what to install or set: no file
// found (each name tried, with dlerror(): OpenHaptics's libraries need an old
// ncurses, libncurses.so.5, which a current distribution lacks), a file that
// does not load, a symbol missing (not OpenHaptics's HD library).
std::shared_ptr<HdLibrary> load_hd_library(std::string& error);

}  // namespace hapticut::servo
