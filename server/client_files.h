// The files a control client names (docs/servo.md, "Files"): nothing a client
// sends may block the thread that opens the file, fill the servo's memory, or
// write outside the recording directory, and no error says more about a file
// than its path and why it was refused.
#pragma once

#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace hapticut::servo {

// The path and the reason ("'/tmp/f': not a regular file (a FIFO)").
class FileRefused : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline constexpr std::uint64_t kDefaultMaxSceneBytes = 256ULL << 20;

// The whole of a regular file of at most max_bytes. Its kind is checked before
// it is opened (a FIFO, a device, a socket or a directory is refused without
// opening it), it is opened with O_NONBLOCK so that opening never waits, and
// checked again on the open descriptor (the name may have changed between).
// A refusal on size names `limit_source` (the option that sets the limit) when given.
std::vector<std::uint8_t> read_regular_file(const std::string& path, std::uint64_t max_bytes,
                                            const char* limit_source = nullptr);

// The same rules, for a file read a part at a time: the descriptor (the caller
// closes it) and, in `size`, the file's size (at most max_bytes).
int open_regular_file(const std::string& path, std::uint64_t max_bytes, std::uint64_t& size,
                      const char* limit_source = nullptr);

// $XDG_STATE_HOME/hapticut/recordings, else $HOME/.local/state/hapticut/recordings.
std::string default_recording_directory();

// A new recording inside `directory` (made, mode 0700, when missing): `requested`
// is a name relative to it or an absolute path inside it. Refused: "." or ".."
// components, a symbolic link on the way (each step is opened with O_NOFOLLOW
// from its parent's descriptor), a missing subdirectory, an existing file
// (O_EXCL: never overwritten). `full_path` gets the file's path.
std::FILE* create_recording_file(const std::string& directory, const std::string& requested,
                                 std::string& full_path);

// The whole of a regular file of at most max_bytes that `requested` names in
// `directory`, by the same rules as create_recording_file (no "." or "..", no
// symbolic link on the way or at the end, never waits to open); `full_path`
// gets its path.
std::vector<std::uint8_t> read_recording_directory_file(const std::string& directory,
                                                        const std::string& requested,
                                                        std::uint64_t max_bytes,
                                                        std::string& full_path);

// The operator's own --record FILE (any path, truncated when it exists), but a
// regular file only, opened without waiting (O_NONBLOCK: a FIFO is refused).
std::FILE* open_operator_recording(const std::string& path);

}  // namespace hapticut::servo
