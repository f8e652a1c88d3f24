// Decoding a scene file's bytes (JSON or MessagePack) into one tree, the
// first step of the scene reader (scene_reader.cpp checks the tree); Python
// reads through the same reader (core/python/bind_scene.cpp).
//
// The decoder trusts nothing (docs/decisions.md, "Reader limits"): nesting is
// bounded (kMaxSceneNesting), objects are built in linear time, a duplicate
// key, invalid UTF-8 in a string or key, a NUL byte in JSON text and trailing
// bytes after the value are errors. Every failure throws SceneError; its
// message never echoes the offending bytes.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "hapticut/scene_io.h"

namespace hapticut {

using SceneTree = nlohmann::ordered_json;

// Arrays and objects inside each other, the root counting as level 1. A scene
// needs 4 (root, mesh, vertices, vertex); metadata may use the rest.
inline constexpr int kMaxSceneNesting = 64;

// `text` with every byte outside printable ASCII (0x20 to 0x7E) shown as \xNN,
// so that an error never carries a file's or a client's bytes into a
// terminal, a log or Python.
std::string printable(std::string_view text);

// Appends one JSON pointer step (RFC 6901: '~' becomes "~0", '/' becomes "~1").
void append_pointer_token(std::string& out, std::string_view key);

SceneTree decode_scene_tree(std::string_view bytes, SceneEncoding encoding);
SceneTree decode_scene_tree(const std::vector<std::uint8_t>& bytes, SceneEncoding encoding);

}  // namespace hapticut
