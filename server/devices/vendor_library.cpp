#include "devices/vendor_library.h"

#include <link.h>

#include <cstdlib>

namespace hapticut::servo {
namespace {

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

void* open_vendor_library(const VendorLibrarySearch& search, std::string& path,
                          std::string& error) {
  const char* named = std::getenv(search.variable);
  if (named != nullptr && *named != '\0') {
    void* handle = dlopen(named, RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
      error = std::string(search.kind) + ": cannot load $" + search.variable + "=" + named + ": " +
              dl_error_text() + " (" + search.named + ")";
      return nullptr;
    }
    path = loaded_path(handle, named);
    return handle;
  }
  std::string tried;
  for (const std::string& name : search.names) {
    void* handle = dlopen(name.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle != nullptr) {
      path = loaded_path(handle, name);
      return handle;
    }
    tried += "\n  " + name + ": " + dl_error_text();
  }
  error = std::string(search.kind) + ": " + search.library + " was not found; tried:" + tried +
          "\n  " + search.install;
  return nullptr;
}

}  // namespace hapticut::servo
