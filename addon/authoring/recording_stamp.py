"""Whose build a recording was made with: a stamp beside it (``<recording>.scene.json``:
the build's digest, the .blend and the scene), written when Simulate Stroke or Record
starts it, read by Bake, which bakes a recording only onto the build it was made with.

The servo's own header names the scene file's path, which every build of a work folder
shares: only the digest tells one build from another.
"""

from __future__ import annotations

import json
import os

import bpy

STAMP_SUFFIX = ".scene.json"


def stamp_path(recording: str) -> str:
    return recording + STAMP_SUFFIX


def write(recording: str, digest: str, scene_name: str) -> None:
    """The recording about to be made at recording is of the build with digest (the one the
    servo loaded), in scene_name of this file."""
    os.makedirs(os.path.dirname(recording), exist_ok=True)
    stamp = {"build_digest": digest, "blend": bpy.data.filepath, "scene": scene_name}
    staged = stamp_path(recording) + ".tmp"
    with open(staged, "w", encoding="utf-8") as file:
        json.dump(stamp, file)
    os.replace(staged, stamp_path(recording))


def read(recording: str) -> dict | None:
    """The recording's stamp; None when it has none (a file made outside the add-on)."""
    try:
        with open(stamp_path(recording), encoding="utf-8") as file:
            stamp = json.load(file)
    except (OSError, ValueError):
        return None
    return stamp if isinstance(stamp, dict) else None


def _whose(stamp: dict) -> str:
    blend = stamp.get("blend") or "an unsaved file"
    digest = str(stamp.get("build_digest", ""))[:8] or "none"
    return f"{os.path.basename(blend)}'s scene '{stamp.get('scene', '?')}' (build {digest})"


def refusal(scene, recording: str, chosen: bool) -> str:
    """Why the scene must not bake the recording ("" when it may). A stamped recording bakes
    only onto the build it was made with; one without a stamp only when the user chose the
    file (the scene's own recordings are always stamped)."""
    stamp = read(recording)
    here = f"this file's scene '{scene.name}' (build {scene.hapticut.build_hash[:8] or 'none'})"
    if stamp is None:
        if chosen:
            return ""
        return (
            f"the recording {recording} does not say which build it was made with: "
            "Simulate Stroke again, or choose the file in Bake's Recording field"
        )
    if stamp.get("build_digest") != scene.hapticut.build_hash:
        return (
            f"the recording {recording} is of {_whose(stamp)}, not of {here}: "
            "Simulate Stroke (or Record) again with this build"
        )
    return ""
