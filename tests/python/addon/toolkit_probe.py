"""Reads a scene file with the toolkit in a child Python (never inside bpy's process) and
prints what the tests check: materials (their cut variants, the drags), tets per material, the
material at given points."""

import json
import sys

import numpy as np
from hapticut.scenebuild.geometry import tet_signed_volumes
from hapticut.scenefile import load_scene


def material_at(scene, point) -> str:
    """The material of the tet holding point (barycentric coordinates all >= 0)."""
    corners = scene.vertices[scene.tets]  # (m, 4, 3)
    total = tet_signed_volumes(scene.vertices, scene.tets)
    weights = []
    for k in range(4):
        moved = corners.copy()
        moved[:, k] = point
        a, b, c, d = (moved[:, i] for i in range(4))
        weights.append(np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6 / total)
    inside = np.all(np.array(weights) >= -1e-9, axis=0)
    hits = np.flatnonzero(inside)
    return scene.materials[scene.tet_materials[hits[0]]].name if len(hits) else ""


def main(path: str, points_json: str) -> None:
    scene = load_scene(path)
    names = [m.name for m in scene.materials]
    counts = np.bincount(scene.tet_materials, minlength=len(names))
    print(
        json.dumps(
            {
                "materials": {m.name: m.model for m in scene.materials},
                "cut_to": {m.name: m.cut_to for m in scene.materials if m.cut_to},
                "drag_distance_mm": {
                    m.name: m.drag_distance_mm for m in scene.materials if m.model == "drag"
                },
                "tets_per_material": dict(zip(names, counts.tolist(), strict=True)),
                "at": [material_at(scene, np.array(p, float)) for p in json.loads(points_json)],
                "blades": [b.name for b in scene.blades],
                "blade_devices": scene.metadata.get("blade_devices", {}),
            }
        )
    )


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
