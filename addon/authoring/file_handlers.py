"""What happens to a scene's work when its .blend is loaded or saved (docs/addon.md, "The
work folder"):
- load: running builds are cancelled (their result belongs to the file they started in) and
  every scene's status becomes what is on disk (work_folder.settle_after_load);
- Save As to a new path forks every scene's work folder (work_folder.fork) before the file
  is written, so the new file and the old never write into one folder. *Save Copy* writes the
  forked ids into the copy only: the open file keeps its own;
- every save claims the folders for the file saved (work_owner.claim).
"""

from __future__ import annotations

import os

import bpy
from bpy.app.handlers import persistent

from . import build_job, work_folder, work_owner

# Scenes forked by the save under way: name -> (work id, recording path, preview path) before.
_forked: dict[str, tuple[str, str, str]] = {}


def _local_scenes():
    return [scene for scene in bpy.data.scenes if scene.library is None]


@persistent
def _on_load_pre(*_args) -> None:
    build_job.cancel_all()


@persistent
def _on_load_post(*_args) -> None:
    for scene in _local_scenes():
        work_folder.settle_after_load(scene)


@persistent
def _on_save_pre(filepath: str = "", *_args) -> None:
    _forked.clear()
    current = bpy.data.filepath
    if not current or not filepath or work_owner.same_file(current, filepath):
        return  # A first save or a save in place: the folders stay this file's.
    for scene in _local_scenes():
        settings, live = scene.hapticut, scene.hapticut_live
        if settings.work_directory or not settings.work_id:
            continue  # A folder the user chose stays theirs to share; none yet: nothing to fork.
        _forked[scene.name] = (settings.work_id, live.recording_path, live.preview_path)
        work_folder.fork(scene, filepath)


@persistent
def _on_save_post(filepath: str = "", *_args) -> None:
    saved_as = bool(filepath) and work_owner.same_file(bpy.data.filepath or "", filepath)
    if _forked and not saved_as:  # Save Copy: the copy has the forks, this file its own.
        for name, (work_id, recording, preview) in _forked.items():
            scene = bpy.data.scenes.get(name)
            if scene is not None:
                scene.hapticut.work_id = work_id
                scene.hapticut_live.recording_path = recording
                scene.hapticut_live.preview_path = preview
    _forked.clear()
    for scene in _local_scenes():
        work = work_folder.existing_work_directory(scene)
        if _claimable(scene, work) and work_owner.owner_of(work) != bpy.data.filepath:
            work_owner.claim(work, bpy.data.filepath)


def _claimable(scene, work: str | None) -> bool:
    """The scene's id folder exists and no other file owns it (a folder the user chose is
    claimed by a build or a stroke, not by saving)."""
    if not work or scene.hapticut.work_directory or not os.path.isdir(work):
        return False
    return work_folder.shared_with(scene) is None


_HANDLERS = (
    ("load_pre", _on_load_pre),
    ("load_post", _on_load_post),
    ("save_pre", _on_save_pre),
    ("save_post", _on_save_post),
)


def add_handlers() -> None:
    for name, handler in _HANDLERS:
        if handler not in getattr(bpy.app.handlers, name):
            getattr(bpy.app.handlers, name).append(handler)


def remove_handlers() -> None:
    for name, handler in _HANDLERS:
        if handler in getattr(bpy.app.handlers, name):
            getattr(bpy.app.handlers, name).remove(handler)
