#include "client_files.h"

#include <fcntl.h>
#include <limits.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string_view>

namespace hapticut::servo {

namespace {

std::string quoted(const std::string& path) { return "'" + path + "'"; }

[[noreturn]] void refuse(const std::string& path, const std::string& reason) {
  throw FileRefused(quoted(path) + ": " + reason);
}

[[noreturn]] void refuse_errno(const std::string& path, int error) {
  refuse(path, std::strerror(error));
}

const char* kind_name(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISLNK(mode)) return "a symbolic link";
  return "not a regular file";
}

void require_regular(const std::string& path, const struct stat& info) {
  if (!S_ISREG(info.st_mode)) {
    refuse(path, std::string("not a regular file (") + kind_name(info.st_mode) + ")");
  }
}

// Closes the descriptor when it goes out of scope, unless released.
class Descriptor {
 public:
  explicit Descriptor(int fd) : fd_(fd) {}
  ~Descriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  Descriptor(const Descriptor&) = delete;
  Descriptor& operator=(const Descriptor&) = delete;
  int get() const { return fd_; }
  int release() {
    const int fd = fd_;
    fd_ = -1;
    return fd;
  }
  void reset(int fd) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = fd;
  }

 private:
  int fd_;
};

std::string size_text(std::uint64_t bytes) {
  char text[64];
  std::snprintf(text, sizeof text, "%.1f MiB", double(bytes) / double(1 << 20));
  return text;
}

// A descriptor opened with O_NONBLOCK, back to blocking for plain reads and writes.
std::FILE* blocking_stream(Descriptor& fd, const std::string& path, const char* mode) {
  const int flags = ::fcntl(fd.get(), F_GETFL);
  if (flags < 0 || ::fcntl(fd.get(), F_SETFL, flags & ~O_NONBLOCK) != 0) refuse_errno(path, errno);
  std::FILE* file = ::fdopen(fd.get(), mode);
  if (file == nullptr) refuse_errno(path, errno);
  fd.release();
  return file;
}

void make_directories(const std::string& directory) {
  std::string partial;
  std::size_t start = 0;
  while (start <= directory.size()) {
    const std::size_t end = directory.find('/', start);
    partial = directory.substr(0, end == std::string::npos ? directory.size() : end);
    if (!partial.empty() && ::mkdir(partial.c_str(), 0700) != 0 && errno != EEXIST) {
      refuse(directory,
             std::string("cannot make the recording directory: ") + std::strerror(errno));
    }
    if (end == std::string::npos) break;
    start = end + 1;
  }
}

// The steps of a path below the recording directory; refused: empty, "." and "..".
std::vector<std::string> steps_of(const std::string& relative, const std::string& requested) {
  std::vector<std::string> steps;
  std::size_t start = 0;
  while (start <= relative.size()) {
    const std::size_t end = relative.find('/', start);
    const std::string step =
        relative.substr(start, end == std::string::npos ? std::string::npos : end - start);
    if (step == "." || step == "..") {
      refuse(requested, "a recording path may not hold \".\" or \"..\"");
    }
    if (!step.empty()) steps.push_back(step);
    if (end == std::string::npos) break;
    start = end + 1;
  }
  if (steps.empty()) refuse(requested, "no file name");
  return steps;
}

// `requested` below `directory`: relative as it is, absolute when it starts
// with the directory as given or as resolved.
std::string below_directory(const std::string& directory, const std::string& resolved,
                            const std::string& requested) {
  if (requested.empty() || requested.front() != '/') return requested;
  for (const std::string& base : {directory, resolved}) {
    std::string prefix = base;
    while (prefix.size() > 1 && prefix.back() == '/') prefix.pop_back();
    if (requested.size() > prefix.size() && requested.compare(0, prefix.size(), prefix) == 0 &&
        requested[prefix.size()] == '/') {
      return requested.substr(prefix.size() + 1);
    }
  }
  refuse(requested, "outside the recording directory " + quoted(resolved) +
                        " (--record-dir); give a name relative to it");
}

// The `size` bytes of an open file (fewer when it shrank since its fstat).
std::vector<std::uint8_t> read_whole(int fd, std::uint64_t size, const std::string& path) {
  std::vector<std::uint8_t> bytes(size);
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::read(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) refuse_errno(path, errno);
    if (n == 0) break;
    done += static_cast<std::size_t>(n);
  }
  bytes.resize(done);
  return bytes;
}

}  // namespace

int open_regular_file(const std::string& path, std::uint64_t max_bytes, std::uint64_t& size,
                      const char* limit_source) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) refuse_errno(path, errno);
  require_regular(path, info);
  Descriptor fd(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC));
  if (fd.get() < 0) refuse_errno(path, errno);
  if (::fstat(fd.get(), &info) != 0) refuse_errno(path, errno);
  require_regular(path, info);
  size = static_cast<std::uint64_t>(info.st_size);
  if (size > max_bytes) {
    refuse(path, size_text(size) + " is over the limit of " + size_text(max_bytes) +
                     (limit_source != nullptr ? std::string(" (") + limit_source + ")" : ""));
  }
  return fd.release();
}

std::vector<std::uint8_t> read_regular_file(const std::string& path, std::uint64_t max_bytes,
                                            const char* limit_source) {
  std::uint64_t size = 0;
  Descriptor fd(open_regular_file(path, max_bytes, size, limit_source));
  return read_whole(fd.get(), size, path);
}

std::string default_recording_directory() {
  const char* state = std::getenv("XDG_STATE_HOME");
  if (state != nullptr && state[0] == '/') return std::string(state) + "/hapticut/recordings";
  const char* home = std::getenv("HOME");
  if (home != nullptr && home[0] == '/') {
    return std::string(home) + "/.local/state/hapticut/recordings";
  }
  return "hapticut-recordings";
}

namespace {

// The descriptor of the directory that holds the file `requested` names
// below `directory` (made when `make` is set), each step opened with
// O_NOFOLLOW from its parent; `leaf` gets the file's name, `full_path` its path.
int parent_below(const std::string& directory, const std::string& requested, bool make,
                 std::string& leaf, std::string& full_path) {
  if (requested.empty()) refuse(requested, "no file name");
  if (make) make_directories(directory);
  char resolved_text[PATH_MAX];
  if (::realpath(directory.c_str(), resolved_text) == nullptr) {
    refuse(directory, std::string("the recording directory: ") + std::strerror(errno));
  }
  const std::string resolved = resolved_text;
  const std::vector<std::string> steps =
      steps_of(below_directory(directory, resolved, requested), requested);
  Descriptor parent(::open(resolved.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (parent.get() < 0) refuse_errno(directory, errno);
  full_path = resolved;
  for (std::size_t i = 0; i + 1 < steps.size(); ++i) {
    full_path += "/" + steps[i];
    const int next =
        ::openat(parent.get(), steps[i].c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
    if (next < 0) {
      refuse(full_path, errno == ELOOP || errno == ENOTDIR
                            ? std::string("not a directory (symbolic links are not followed)")
                            : std::string(std::strerror(errno)));
    }
    parent.reset(next);
  }
  leaf = steps.back();
  full_path += "/" + leaf;
  return parent.release();
}

}  // namespace

std::FILE* create_recording_file(const std::string& directory, const std::string& requested,
                                 std::string& full_path) {
  std::string leaf;
  Descriptor parent(parent_below(directory, requested, true, leaf, full_path));
  Descriptor fd(
      ::openat(parent.get(), leaf.c_str(),
               O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_NONBLOCK | O_NOCTTY | O_CLOEXEC, 0644));
  if (fd.get() < 0) {
    refuse(full_path, errno == EEXIST ? std::string("already exists (recordings never overwrite)")
                                      : std::string(std::strerror(errno)));
  }
  return blocking_stream(fd, full_path, "wb");
}

std::vector<std::uint8_t> read_recording_directory_file(const std::string& directory,
                                                        const std::string& requested,
                                                        std::uint64_t max_bytes,
                                                        std::string& full_path) {
  std::string leaf;
  Descriptor parent(parent_below(directory, requested, false, leaf, full_path));
  Descriptor fd(::openat(parent.get(), leaf.c_str(),
                         O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_NOCTTY | O_CLOEXEC));
  if (fd.get() < 0) {
    refuse(full_path, errno == ELOOP ? std::string("a symbolic link (not followed)")
                                     : std::string(std::strerror(errno)));
  }
  struct stat info {};
  if (::fstat(fd.get(), &info) != 0) refuse_errno(full_path, errno);
  require_regular(full_path, info);
  const auto size = static_cast<std::uint64_t>(info.st_size);
  if (size > max_bytes) {
    refuse(full_path, size_text(size) + " is over the limit of " + size_text(max_bytes));
  }
  return read_whole(fd.get(), size, full_path);
}

std::FILE* open_operator_recording(const std::string& path) {
  struct stat info {};
  if (::stat(path.c_str(), &info) == 0) require_regular(path, info);
  Descriptor fd(
      ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_NONBLOCK | O_NOCTTY | O_CLOEXEC, 0644));
  if (fd.get() < 0) refuse_errno(path, errno);
  if (::fstat(fd.get(), &info) != 0) refuse_errno(path, errno);
  require_regular(path, info);
  return blocking_stream(fd, path, "wb");
}

}  // namespace hapticut::servo
