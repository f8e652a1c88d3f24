// Whole-file reading and atomic writing (file_io.h).
#include "hapticut/file_io.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <system_error>

#if defined(__unix__) || defined(__APPLE__)
#include <unistd.h>
#endif

namespace hapticut {

namespace {

std::string in_quotes(const std::string& text) { return "'" + text + "'"; }

[[noreturn]] void fail_file(const std::string& action, const std::string& path, int error) {
  throw FileError("cannot " + action + " " + in_quotes(path) + ": " + std::strerror(error));
}

std::string temporary_path_beside(const std::string& path) {
  std::random_device random;
  char suffix[32];
  std::snprintf(suffix, sizeof suffix, ".tmp-%08x%08x", random(), random());
  return path + suffix;
}

}  // namespace

std::vector<std::uint8_t> read_file(const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) fail_file("open", path, errno);
  std::vector<std::uint8_t> bytes;
  std::uint8_t buffer[1 << 16];
  std::size_t count = 0;
  while ((count = std::fread(buffer, 1, sizeof buffer, file)) > 0) {
    bytes.insert(bytes.end(), buffer, buffer + count);
  }
  const bool failed = std::ferror(file) != 0;
  const int error = errno;
  std::fclose(file);
  if (failed) fail_file("read", path, error);
  return bytes;
}

void write_file_atomically(const std::vector<std::uint8_t>& bytes, const std::string& path) {
  const std::string temporary = temporary_path_beside(path);
  std::FILE* file = std::fopen(temporary.c_str(), "wbx");
  if (file == nullptr) fail_file("create", temporary, errno);
  bool ok = std::fwrite(bytes.data(), 1, bytes.size(), file) == bytes.size();
  ok = ok && std::fflush(file) == 0;
#if defined(__unix__) || defined(__APPLE__)
  ok = ok && ::fsync(::fileno(file)) == 0;
#endif
  int error = errno;
  ok = (std::fclose(file) == 0) && ok;
  if (!ok) {
    error = error != 0 ? error : errno;
    std::remove(temporary.c_str());
    fail_file("write", temporary, error);
  }
  std::error_code rename_error;
  std::filesystem::rename(temporary, path, rename_error);
  if (rename_error) {
    std::remove(temporary.c_str());
    fail_file("rename " + in_quotes(temporary) + " to", path, rename_error.value());
  }
}

}  // namespace hapticut
