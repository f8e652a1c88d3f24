"""The cut region, live: the faces round the tets the servo's blades have cut so far (the
stream's cut set, ``live_session.follow_cuts``), as a mesh object the live timer brings up
to date when the set changes. A mesh rather than a draw handler's lines: it shows in every
view and shading mode, an artist can hide or select it, and it reads the same headless. Left
out of renders (the bake's cut surface is what renders). Its tets are the build's preview's,
the servo's scene's own (the servo cuts the tets of the scene it loaded from that build)."""

from __future__ import annotations

import time

import bpy
import numpy as np

from ..toolkit.units import mm_per_unit

OBJECT = "Hapticut Live Cut"
COLLECTION = "Hapticut Live"
COLOUR = (0.85, 0.12, 0.1, 0.6)
# At most this often a mesh rebuilt (the set grows every frame while a blade cuts).
MIN_INTERVAL_S = 0.2
# A tet's faces, by its local vertices.
TET_FACES = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])

_shown: dict[str, tuple] = {}  # Scene name -> ((generation, count), when)
_preview: dict[str, dict] = {}  # Preview path -> its tets (preview_tets)


def boundary_faces(tets: np.ndarray, cut) -> np.ndarray:
    """(F, 3) the faces of the cut tets that only one of them has: the cut region's skin."""
    cut = np.asarray(cut, np.int64)
    if not len(cut):
        return np.zeros((0, 3), np.int64)
    faces = np.asarray(tets, np.int64)[cut][:, TET_FACES].reshape(-1, 3)
    _, first, counts = np.unique(
        np.sort(faces, axis=1), axis=0, return_index=True, return_counts=True
    )
    return faces[np.sort(first[counts == 1])]


def update(scene, session, force: bool = False) -> bool:
    """Brings the scene's live cut object up to the session's cut set (at most every
    MIN_INTERVAL_S unless ``force``); True when it changed."""
    cuts = session.cut_set
    if cuts is None or not session.preview_path or cuts.generation is None:
        return False
    key = (cuts.generation, len(cuts.order))
    shown = _shown.get(scene.name)
    now = time.monotonic()
    if shown is not None and (shown[0] == key or (not force and now - shown[1] < MIN_INTERVAL_S)):
        return False
    path = session.preview_path
    if path not in _preview:
        _preview[path] = session.link.preview_tets(path)
    tets = _preview[path]
    faces = boundary_faces(tets["tets"], cuts.order)
    used, compact = np.unique(faces, return_inverse=True)
    vertices = np.asarray(tets["vertices"], np.float64)[used] / mm_per_unit(scene)
    _replace_mesh(scene, vertices, compact.reshape(-1, 3))
    _shown[scene.name] = (key, now)
    return True


def _replace_mesh(scene, vertices: np.ndarray, faces: np.ndarray) -> None:
    mesh = bpy.data.meshes.new(OBJECT)
    mesh.from_pydata(vertices.tolist(), [], faces.tolist())
    mesh.materials.append(_material())
    obj = bpy.data.objects.get(OBJECT)
    if obj is None:
        obj = bpy.data.objects.new(OBJECT, mesh)
        obj.hide_render = True
        obj.display_type = "SOLID"
    else:
        old, obj.data = obj.data, mesh
        if old.users == 0:
            bpy.data.meshes.remove(old)
    collection = bpy.data.collections.get(COLLECTION) or bpy.data.collections.new(COLLECTION)
    if collection.name not in scene.collection.children:
        scene.collection.children.link(collection)
    if obj.name not in collection.objects:
        collection.objects.link(obj)


def _material():
    material = bpy.data.materials.get(OBJECT) or bpy.data.materials.new(OBJECT)
    material.diffuse_color = COLOUR
    return material


def face_count() -> int:
    """Faces of the live cut object (0: none)."""
    obj = bpy.data.objects.get(OBJECT)
    return len(obj.data.polygons) if obj is not None else 0
