// Whole-file reading and atomic writing, for scene files (scene_io.h) and any
// other file the product writes (the servo's recordings): a reader sees the old
// file or the new one, never a prefix of the new one.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace hapticut {

// "cannot open 'a.json': No such file or directory" (also create, read, write, rename).
class FileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

std::vector<std::uint8_t> read_file(const std::string& path);

// Writes to a new temporary file beside `path`, flushes it to disk, then renames
// it over `path`; on failure the temporary is removed and `path` is untouched.
void write_file_atomically(const std::vector<std::uint8_t>& bytes, const std::string& path);

}  // namespace hapticut
