// Scene files on disk: the encoding from the name, then the reader
// (scene_reader.cpp) or the writer (scene_writer.cpp) over the file I/O of
// file_io.h, whose errors become SceneError with field "(file)".
#include "hapticut/scene_io.h"

#include <string_view>

#include "hapticut/file_io.h"

namespace hapticut {

namespace {

std::vector<std::uint8_t> read_scene_file_bytes(const std::string& path) {
  try {
    return read_file(path);
  } catch (const FileError& error) {
    throw SceneError("(file)", error.what());
  }
}

void write_scene_file_bytes(const std::vector<std::uint8_t>& bytes, const std::string& path) {
  try {
    write_file_atomically(bytes, path);
  } catch (const FileError& error) {
    throw SceneError("(file)", error.what());
  }
}

}  // namespace

SceneEncoding encoding_for_path(const std::string& path) {
  constexpr std::string_view kSuffix = ".msgpack";
  const bool msgpack = path.size() >= kSuffix.size() &&
                       path.compare(path.size() - kSuffix.size(), kSuffix.size(), kSuffix) == 0;
  return msgpack ? SceneEncoding::MessagePack : SceneEncoding::Json;
}

SceneDocument load_scene_document(const std::string& path, const ReadOptions& options) {
  return parse_scene_document(read_scene_file_bytes(path), encoding_for_path(path), options);
}

Scene load_scene(const std::string& path, const ReadOptions& options) {
  return load_scene_document(path, options).scene;
}

Scene load_scene(const std::string& path) { return load_scene(path, ReadOptions{}); }

void save_scene_document(const SceneDocument& document, const std::string& path) {
  write_scene_file_bytes(serialize_scene_document(document, encoding_for_path(path)), path);
}

void save_scene(const Scene& scene, const std::string& path) {
  write_scene_file_bytes(serialize_scene(scene, encoding_for_path(path)), path);
}

}  // namespace hapticut
