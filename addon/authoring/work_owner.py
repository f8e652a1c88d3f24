"""Which .blend owns a work folder, and a folder's build and recording handed to a new folder
(a fork). No bpy: paths in, files out.

A work folder's owner is the .blend that writes into it (``owner.json``: its absolute path;
"" for a session never saved). Another file that finds the folder owned by a file still on
disk is a copy of it (a Save As before forking existed, or a copy made outside Blender): it
reads the build but forks before writing (docs/addon.md, "The work folder").
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil

OWNER_FILE = "owner.json"


def same_file(a: str, b: str) -> bool:
    return os.path.normcase(os.path.realpath(a)) == os.path.normcase(os.path.realpath(b))


def owner_of(folder: str) -> str | None:
    """The .blend that owns folder ("" for an unsaved session; None when nobody claimed it)."""
    try:
        with open(os.path.join(folder, OWNER_FILE), encoding="utf-8") as file:
            return str(json.load(file)["blend"])
    except (OSError, ValueError, KeyError, TypeError):
        return None


def claim(folder: str, blend: str) -> None:
    """folder is blend's from now on (written whole: a reader never sees half of it)."""
    os.makedirs(folder, exist_ok=True)
    staged = os.path.join(folder, OWNER_FILE + ".tmp")
    with open(staged, "w", encoding="utf-8") as file:
        json.dump({"blend": blend}, file)
    os.replace(staged, os.path.join(folder, OWNER_FILE))


def other_owner(folder: str, blend: str) -> str | None:
    """The other .blend that owns folder, when it is still on disk; None when folder is
    blend's, nobody's, an unsaved session's, or its owner's file is gone (moved: it is
    blend's to take)."""
    owner = owner_of(folder)
    if not owner or (blend and same_file(owner, blend)) or not os.path.isfile(owner):
        return None
    return owner


def share_tree(source: str, target: str) -> None:
    """A copy of the folder source at target, its files hard links where the file system
    allows (instant, no space): a build is never written in place (the toolkit renames a
    new one into place, the digest is replaced whole), so neither folder's writes reach the
    other: copy-on-write in effect. A folder at target is replaced; a partial copy is removed
    before the error is raised."""
    staged, replaced = target + ".fork-tmp", target + ".replaced-tmp"
    for leftover in (staged, replaced):
        shutil.rmtree(leftover, ignore_errors=True)
    try:
        shutil.copytree(source, staged, copy_function=_link_or_copy)
        if os.path.isdir(target):  # An older build there: set aside, so target is never half.
            os.replace(target, replaced)
        os.replace(staged, target)
    except OSError:
        shutil.rmtree(staged, ignore_errors=True)
        raise
    finally:
        shutil.rmtree(replaced, ignore_errors=True)


def _link_or_copy(source: str, target: str) -> None:
    try:
        os.link(source, target)
    except OSError:
        shutil.copy2(source, target)


def share_file(source: str, target: str) -> None:
    """A link to source at target (a copy where the file system has none): recordings are
    never rewritten in place either (a stroke removes the last one before the servo writes)."""
    os.makedirs(os.path.dirname(target), exist_ok=True)
    with contextlib.suppress(FileNotFoundError):
        os.remove(target)
    _link_or_copy(source, target)
