#include "devices/dhd_library.h"

#include <dlfcn.h>
#include <link.h>

#include <cstdlib>

namespace hapticut::servo {
namespace {

// Binds `pointer` to the symbol `name`; false (with `missing` extended) when absent.
template <typename Function>
bool bind(void* handle, const char* name, Function& pointer, std::string& missing) {
  // POSIX guarantees a data pointer from dlsym converts to a function pointer.
  pointer = reinterpret_cast<Function>(dlsym(handle, name));
  if (pointer != nullptr) return true;
  missing += (missing.empty() ? "" : ", ") + std::string(name);
  return false;
}

std::string loaded_path(void* handle, const std::string& fallback) {
  link_map* map = nullptr;
  if (dlinfo(handle, RTLD_DI_LINKMAP, &map) == 0 && map != nullptr && map->l_name != nullptr &&
      map->l_name[0] != '\0') {
    return map->l_name;
  }
  return fallback;
}

const char* dl_error_text() {
  const char* text = dlerror();
  return text != nullptr ? text : "unknown dlopen error";
}

}  // namespace

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
  void* handle = nullptr;
  std::string tried;
  const char* named = std::getenv(kDhdLibraryVariable);
  if (named != nullptr && *named != '\0') {
    // A path the operator named is the only one tried: a wrong one must not
    // fall back to another SDK silently.
    handle = dlopen(named, RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
      error = std::string("forcedimension: cannot load the DHD library $") + kDhdLibraryVariable +
              "=" + named + ": " + dl_error_text() +
              " (install Force Dimension's SDK for this machine's architecture, or set $" +
              kDhdLibraryVariable + " to its lib/release/lin-*/libdhd.so.*)";
      return nullptr;
    }
  } else {
    for (const std::string& name : dhd_library_names()) {
      handle = dlopen(name.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (handle != nullptr) break;
      tried += "\n  " + name + ": " + dl_error_text();
    }
    if (handle == nullptr) {
      error = std::string("forcedimension: Force Dimension's DHD library was not found; tried:") +
              tried +
              "\n  install the Force Dimension SDK (https://forcedimension.com/software/sdk) "
              "and put its lib/release/lin-*-gcc folder on LD_LIBRARY_PATH, or set $" +
              kDhdLibraryVariable + " to its libdhd.so.* file (docs/devices.md)";
      return nullptr;
    }
  }
  auto library = std::make_shared<DhdLibrary>();
  library->handle = handle;
  library->path = loaded_path(handle, named != nullptr && *named ? named : "");
  std::string missing;
  bind(handle, "dhdGetDeviceCount", library->get_device_count, missing);
  bind(handle, "dhdOpenID", library->open_id, missing);
  bind(handle, "dhdGetSystemType", library->get_system_type, missing);
  bind(handle, "dhdEnableForce", library->enable_force, missing);
  bind(handle, "dhdGetPosition", library->get_position, missing);
  bind(handle, "dhdGetOrientationFrame", library->get_orientation_frame, missing);
  bind(handle, "dhdGetButtonMask", library->get_button_mask, missing);
  bind(handle, "dhdSetForce", library->set_force, missing);
  bind(handle, "dhdGetMaxForce", library->get_max_force, missing);
  bind(handle, "dhdErrorGetLast", library->error_get_last, missing);
  bind(handle, "dhdErrorGetLastStr", library->error_get_last_str, missing);
  bind(handle, "dhdStop", library->stop, missing);
  bind(handle, "dhdClose", library->close, missing);
  if (!missing.empty()) {
    error = "forcedimension: " + library->path + " lacks " + missing +
            " (not Force Dimension's DHD library, or an SDK older than 3.2: install a current "
            "one)";
    return nullptr;
  }
  return library;
}

}  // namespace hapticut::servo
