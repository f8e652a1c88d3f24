"""Where a scene's build, servo log, stroke and recordings live: the scene's *Work directory*
when set, else a folder named by an id the scene keeps (``scene.hapticut.work_id``, set once)
under the user's data folder. The .blend's name plays no part, so *Save As* and reopening
find the same build (docs/addon.md, "The work folder").

A build on disk is the scene's when the digest written beside it at the end of the build is
the scene's ``build_hash``: a build that finished while Blender was closed, or another file's
build in a shared folder, is never taken for this scene's.
"""

from __future__ import annotations

import os
import sys
import uuid

import bpy
from bpy.app.handlers import persistent

from . import build_job, exchange

# Written into build/ by the add-on once the build is shown; a new build replaces build/
# whole (the toolkit renames it into place), so an old digest never outlives its build.
DIGEST_FILE = "addon-digest.txt"
NO_BUILD_STATUS = "no build on disk: Tetrahedralize again"


def data_root() -> str:
    """The user's data folder for builds: it outlives a reboot (unlike the temporary
    directory) and a Blender upgrade (unlike Blender's own versioned folders)."""
    if sys.platform == "win32":
        base = os.environ.get("LOCALAPPDATA") or os.path.expanduser("~/AppData/Local")
    elif sys.platform == "darwin":
        base = os.path.expanduser("~/Library/Application Support")
    else:
        base = os.environ.get("XDG_DATA_HOME") or os.path.expanduser("~/.local/share")
    return os.path.join(base, "hapticut", "builds")


def _id_shared(scene) -> bool:
    """Another scene of this file holds the same id (a Full Copy of the scene copies it)."""
    work_id = scene.hapticut.work_id
    return any(s.hapticut.work_id == work_id for s in bpy.data.scenes if s != scene)


def work_directory(scene) -> str:
    """The scene's work folder; gives the scene its id first when it has none (so call it
    where data may change: an operator, a timer, a handler; never from a panel's draw)."""
    settings = scene.hapticut
    if not settings.work_directory and (not settings.work_id or _id_shared(scene)):
        settings.work_id = uuid.uuid4().hex
    return existing_work_directory(scene)


def existing_work_directory(scene) -> str | None:
    """The scene's work folder without changing anything (None: it never had one)."""
    configured = scene.hapticut.work_directory
    if configured:
        return bpy.path.abspath(configured)
    return os.path.join(data_root(), scene.hapticut.work_id) if scene.hapticut.work_id else None


def build_folder(scene) -> str | None:
    work = existing_work_directory(scene)
    return os.path.join(work, build_job.BUILD_FOLDER) if work else None


def digest_on_disk(folder: str) -> str:
    """The digest of the build in folder ("" when there is none, or no digest with it)."""
    try:
        with open(os.path.join(folder, DIGEST_FILE), encoding="utf-8") as file:
            return file.read().strip()
    except OSError:
        return ""


def write_digest(folder: str, digest: str) -> None:
    with open(os.path.join(folder, DIGEST_FILE), "w", encoding="utf-8") as file:
        file.write(digest + "\n")


def built_folder(scene) -> str | None:
    """The build folder when it holds this scene's last build (its digest is build_hash)."""
    folder = build_folder(scene)
    digest = scene.hapticut.build_hash
    if folder is None or not digest or digest_on_disk(folder) != digest:
        return None
    return folder if os.path.isfile(os.path.join(folder, exchange.SCENE_FILE)) else None


def settle_after_load(scene) -> None:
    """What a reopened scene says: no build runs (a build is cancelled when a file loads), and
    the status is the build on disk's, not the one saved with the file."""
    settings = scene.hapticut
    settings.running, settings.progress, settings.stage = False, 0.0, ""
    if not settings.build_hash:
        settings.status = ""
        return
    if built_folder(scene) is not None:
        settings.status = "built"
        return
    folder = build_folder(scene)
    if folder is not None and not settings.work_directory and digest_on_disk(folder):
        # Another file's build (a Save As copy that built since): a new id keeps both.
        settings.work_id = uuid.uuid4().hex
    settings.build_hash, settings.report_json = "", ""
    settings.status = NO_BUILD_STATUS


@persistent
def _on_load_pre(*_args) -> None:
    # A build's result belongs to the file it started in: none may land in the next one.
    build_job.cancel_all()


@persistent
def _on_load_post(*_args) -> None:
    for scene in bpy.data.scenes:
        if scene.library is None:  # A linked scene is another file's, read-only here.
            settle_after_load(scene)


def add_handlers() -> None:
    if _on_load_pre not in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.append(_on_load_pre)
    if _on_load_post not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(_on_load_post)


def remove_handlers() -> None:
    if _on_load_pre in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(_on_load_pre)
    if _on_load_post in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(_on_load_post)
