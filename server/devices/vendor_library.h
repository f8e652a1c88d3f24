// Loading a vendor's device library with dlopen at run time, shared by the
// kinds built on one (Force Dimension's DHD, dhd_library.h; 3D Systems'
// OpenHaptics HD, hd_library.h): the servo builds without the vendors' SDKs
// and needs a library only when a binding or the listing asks for it.
#pragma once

#include <dlfcn.h>

#include <string>
#include <vector>

namespace hapticut::servo {

// Where to look and what to tell the operator when nothing loads.
struct VendorLibrarySearch {
  const char* kind;      // The device kind, which starts each message ("forcedimension").
  const char* library;   // The library's name for people ("Force Dimension's DHD library").
  const char* variable;  // The environment variable naming its file ("HAPTICUT_DHD_LIB").
  std::vector<std::string> names;  // What dlopen tries, in order, when the variable is unset.
  std::string install;  // What to install or set when no name loads (after "tried: ...").
  std::string named;    // What to check when the variable's file does not load.
};

// dlopen's handle of the library, or nullptr with `error` naming each file
// tried and dlerror()'s reason. A path the variable names is the only one
// tried: a wrong one must never fall back to another installation silently.
// `path` is the file as the loader resolved it.
void* open_vendor_library(const VendorLibrarySearch& search, std::string& path, std::string& error);

// Binds `pointer` to the symbol `name`; false (with `missing` extended) when absent.
template <typename Function>
bool bind_symbol(void* handle, const char* name, Function& pointer, std::string& missing) {
  // POSIX guarantees a data pointer from dlsym converts to a function pointer.
  pointer = reinterpret_cast<Function>(dlsym(handle, name));
  if (pointer != nullptr) return true;
  missing += (missing.empty() ? "" : ", ") + std::string(name);
  return false;
}

}  // namespace hapticut::servo
