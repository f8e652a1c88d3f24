// Reading and writing scene files in their two encodings (JSON, MessagePack):
// the one reader (core/src/scene_reader.cpp, value checks in scene_values.cpp)
// and writer (scene_writer.cpp); files go through file_io.h (scene_io.cpp).
// Every failure throws SceneError whose message starts with the field path
// (a JSON pointer such as "/mesh/tets/17/2") and states the reason.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "hapticut/scene.h"

namespace hapticut {

class SceneError : public std::runtime_error {
 public:
  SceneError(std::string field, const std::string& reason)
      : std::runtime_error(field + ": " + reason), field_(std::move(field)) {}
  const std::string& field() const { return field_; }

 private:
  std::string field_;
};

enum class SceneEncoding { Json, MessagePack };

struct ReadOptions {
  // Reject inverted tets ("/mesh/tets/N: inverted (negative volume)") instead of
  // re-orienting them (swapping their last two vertices, as TetMesh does).
  bool strict = false;
};

// What a scene file holds beyond the engine's Scene. Tools that rewrite files
// (the Python bindings) use it so that nothing the file said is lost.
struct SceneDocument {
  Scene scene;
  std::string metadata_json = "{}";  // The free-form "metadata" object, as compact JSON text.
  std::int64_t reoriented_tets = 0;  // Inverted tets the reader re-oriented (0 when strict).
};

// "free", "drag", ... -> the model; std::nullopt for any other name.
std::optional<MaterialModel> material_model_from_name(std::string_view name);

// A blade's "coupling" or "orientation" by name, for the blade named `blade`;
// any other name throws SceneError(field, "unknown coupling 'x' of blade 'b'
// (expected rigid, independent)"), as the reader says it.
BladeCoupling blade_coupling_at(std::string_view name, std::string_view blade,
                                const std::string& field);
BladeOrientation blade_orientation_at(std::string_view name, std::string_view blade,
                                      const std::string& field);

// Encoding chosen from the file name: ".msgpack" -> MessagePack, else JSON.
SceneEncoding encoding_for_path(const std::string& path);

Scene parse_scene(const std::vector<std::uint8_t>& bytes, SceneEncoding encoding);
Scene parse_scene(const std::vector<std::uint8_t>& bytes, SceneEncoding encoding,
                  const ReadOptions& options);
SceneDocument parse_scene_document(const std::vector<std::uint8_t>& bytes, SceneEncoding encoding,
                                   const ReadOptions& options = {});

// Serializing validates first: a scene the reader would reject throws SceneError
// (naming the field as it would appear in the file) and nothing is written.
std::vector<std::uint8_t> serialize_scene(const Scene& scene, SceneEncoding encoding);
std::vector<std::uint8_t> serialize_scene_document(const SceneDocument& document,
                                                   SceneEncoding encoding);

// File errors (cannot open, read, write or rename) throw SceneError with field "(file)".
Scene load_scene(const std::string& path);
Scene load_scene(const std::string& path, const ReadOptions& options);
SceneDocument load_scene_document(const std::string& path, const ReadOptions& options = {});

// Writes to a temporary file beside `path`, then renames: never a half-written file.
void save_scene(const Scene& scene, const std::string& path);
void save_scene_document(const SceneDocument& document, const std::string& path);

}  // namespace hapticut
