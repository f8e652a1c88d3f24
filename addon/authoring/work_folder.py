"""Where a scene's build, servo log, stroke and recordings live: the scene's *Work directory*
when set, else a folder named by an id the scene keeps (``scene.hapticut.work_id``) under the
user's data folder. A folder is one .blend's (work_owner): *Save As* to a new path forks it
(file_handlers), and a file that finds its folder owned by another forks before it writes
(docs/addon.md, "The work folder").

A build on disk is the scene's when the digest written beside it at the end of the build is
the scene's ``build_hash``: a build that finished while Blender was closed, or another file's
build in a shared folder, is never taken for this scene's.
"""

from __future__ import annotations

import os
import sys
import uuid

import bpy

from . import build_job, exchange, recording_stamp, work_owner

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
    """The scene's work folder, to write into: gives the scene its id first when it has none,
    and forks a folder another .blend owns (so call it where data may change: an operator, a
    timer, a handler; never from a panel's draw)."""
    settings = scene.hapticut
    if not settings.work_directory and (not settings.work_id or _id_shared(scene)):
        settings.work_id = uuid.uuid4().hex
    work = existing_work_directory(scene)
    if settings.work_directory:
        return work  # The folder the user chose is theirs: nothing of ours is written into it.
    if work_owner.other_owner(work, bpy.data.filepath) is not None:
        return fork(scene, bpy.data.filepath)
    if work_owner.owner_of(work) != bpy.data.filepath:
        work_owner.claim(work, bpy.data.filepath)
    return work


def shared_with(scene) -> str | None:
    """The other .blend that owns the scene's work folder (None: the folder is this file's,
    or one the user chose, whose sharing is theirs)."""
    work = existing_work_directory(scene)
    if not work or scene.hapticut.work_directory:
        return None
    return work_owner.other_owner(work, bpy.data.filepath)


def fork(scene, blend: str) -> str:
    """Give the scene a work folder of its own, owned by blend: a new id, this scene's build
    and its last recording shared into it (work_owner: links, else copies), the recording
    and preview paths moved along. What cannot be shared stays behind: the status says to
    build again."""
    settings, live = scene.hapticut, scene.hapticut_live
    old_work, old_build = existing_work_directory(scene), build_folder(scene)
    settings.work_directory, settings.work_id = "", uuid.uuid4().hex
    work = existing_work_directory(scene)
    work_owner.claim(work, blend)
    if old_work is None:
        return work
    try:
        if settings.build_hash and digest_on_disk(old_build) == settings.build_hash:
            work_owner.share_tree(old_build, os.path.join(work, build_job.BUILD_FOLDER))
        for field in ("recording_path", "preview_path"):
            moved = _moved(getattr(live, field), old_work, work)
            if moved is not None:
                if field == "recording_path":
                    _share_recording(bpy.path.abspath(getattr(live, field)), moved)
                setattr(live, field, moved)
    except OSError as error:
        settings.status = f"forked without the build ({error}): Tetrahedralize again"
    return work


def _moved(path: str, old_work: str, work: str) -> str | None:
    """path's place in work when it lies in old_work (None when it lies elsewhere)."""
    if not path:
        return None
    try:
        inside = os.path.relpath(bpy.path.abspath(path), old_work)
    except ValueError:  # Another drive (Windows): not inside.
        return None
    if inside.startswith(os.pardir) or os.path.isabs(inside):
        return None
    return os.path.join(work, inside)


def _share_recording(source: str, target: str) -> None:
    if not os.path.isfile(source):
        return
    work_owner.share_file(source, target)
    stamp = recording_stamp.stamp_path(source)
    if os.path.isfile(stamp):
        work_owner.share_file(stamp, recording_stamp.stamp_path(target))


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
    """Replaced whole, never written in place: a forked folder may share the file (a link)."""
    staged = os.path.join(folder, DIGEST_FILE + ".tmp")
    with open(staged, "w", encoding="utf-8") as file:
        file.write(digest + "\n")
    os.replace(staged, os.path.join(folder, DIGEST_FILE))


def built_folder(scene) -> str | None:
    """The build folder when it holds this scene's last build (its digest is build_hash)."""
    folder = build_folder(scene)
    digest = scene.hapticut.build_hash
    if folder is None or not digest or digest_on_disk(folder) != digest:
        return None
    return folder if os.path.isfile(os.path.join(folder, exchange.SCENE_FILE)) else None


def no_build_reason(scene) -> str:
    """Why the scene has no build to use (built_folder is None), with the remedy."""
    digest = scene.hapticut.build_hash
    if not digest:
        return "no scene built yet: Tetrahedralize first"
    return (
        f"no scene built yet: this scene's build ({digest[:8]}) is not the one on disk (an "
        "undo brought back an older one, or the folder was removed or rebuilt by another "
        "file): Tetrahedralize shows the build on disk or rebuilds"
    )


def settle_after_load(scene) -> None:
    """What a reopened scene says: no build runs (a build is cancelled when a file loads), the
    status is the build on disk's, not the one saved with the file, and a work folder another
    .blend owns is named, with the remedy."""
    settings = scene.hapticut
    settings.running, settings.progress, settings.stage = False, 0.0, ""
    settings.status = _status_on_disk(scene)
    other = shared_with(scene)
    if other is not None:
        settings.status = (
            f"{settings.status or 'not built'}; the work folder is also {other}'s: "
            f"Fork Work Folder (else it forks before this file writes)"
        )


def _status_on_disk(scene) -> str:
    settings = scene.hapticut
    if not settings.build_hash:
        return ""
    if built_folder(scene) is not None:
        return "built"
    folder = build_folder(scene)
    if folder is not None and not settings.work_directory and digest_on_disk(folder):
        # Another file's build (a copy that built since): a new id keeps both.
        settings.work_id = uuid.uuid4().hex
    settings.build_hash, settings.report_json = "", ""
    return NO_BUILD_STATUS
