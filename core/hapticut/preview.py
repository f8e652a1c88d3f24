"""A scene's preview for Blender: the boundary surface of each material region, as ``.npz``.

The add-on reads it with numpy alone (no compiled code inside Blender). Arrays:
``vertices`` (n, 3) float64 mm; ``faces`` (f, 3) int32 into vertices, oriented out of their
material; ``face_materials`` (f,) int32 index into the names; ``material_names`` and
``material_models`` (k,) unicode. Air (material 0) has no surface of its own; a face between
two materials appears once for each, oriented out of each. The tets themselves too, for the
cut surface of a bake (hapticut.cut_surface): ``tet_vertices`` (m, 3) float64 mm, ``tets``
(t, 4) int32, ``tet_materials`` (t,) int32.
"""

from __future__ import annotations

import io
import json
import os

import numpy as np

from hapticut.atomic_file import write_atomically
from hapticut.scenebuild.geometry import interface_faces

PREVIEW_VERSION = 1


def preview_arrays(scene) -> dict[str, np.ndarray]:
    """The arrays of the module doc for a Scene."""
    faces, owners = [], []
    for index in range(1, len(scene.materials)):
        surface = interface_faces(scene.tets, scene.tet_materials == index)
        faces.append(surface)
        owners.append(np.full(len(surface), index, dtype=np.int32))
    faces = np.concatenate(faces) if faces else np.zeros((0, 3), np.int64)
    used, compact = np.unique(faces, return_inverse=True)
    return {
        "version": np.array(PREVIEW_VERSION),
        "vertices": np.asarray(scene.vertices, np.float64)[used],
        "faces": compact.reshape(-1, 3).astype(np.int32),
        "face_materials": np.concatenate(owners) if owners else np.zeros(0, np.int32),
        "material_names": np.array([m.name for m in scene.materials], dtype=str),
        "material_models": np.array([m.model for m in scene.materials], dtype=str),
        "tet_vertices": np.asarray(scene.vertices, np.float64),
        "tets": np.asarray(scene.tets, np.int32),
        "tet_materials": np.asarray(scene.tet_materials, np.int32),
    }


def write_preview(scene, path: str | os.PathLike) -> None:
    """The preview of the scene at path (.npz, written atomically), with its build report as
    ``report_json``."""
    arrays = preview_arrays(scene)
    arrays["report_json"] = np.array(json.dumps(scene_report(scene)))
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    write_atomically(path, buffer.getvalue())


def scene_report(scene) -> dict:
    """The scene's build report (from its metadata), or for a scene without one its counts,
    quality and valence."""
    from hapticut.scenebuild.quality import mesh_report

    report = scene.metadata.get("build_report")
    if report:
        return report
    names = [m.name for m in scene.materials]
    return mesh_report(scene.vertices, scene.tets, scene.tet_materials, names)
