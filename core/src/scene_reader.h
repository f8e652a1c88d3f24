// The scene reader's check of a decoded tree (scene_reader.cpp), for the
// writer, which checks every tree it is about to encode. Internal to core/.
#pragma once

#include "hapticut/scene_io.h"
#include "hapticut/scene_tree.h"

namespace hapticut {

// The document the tree describes; throws SceneError at the first problem.
SceneDocument read_scene_tree(const SceneTree& root, const ReadOptions& options);

}  // namespace hapticut
