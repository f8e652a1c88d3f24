"""The material model of the tet holding each point, by the engine (hapticut._core) in a child
Python, never inside bpy's process: the reference the live tests check the cut surface with.
stdin: JSON [[x, y, z], ...] in mm; stdout: JSON ["drag", "rigid", "free", "" (outside), ...].
With --cut, a point on a face between a cuttable tet and another (it lies in both within the
tolerance; the engine may name either) gets the cuttable one, as the cut surface's own
locator names it. With --depth, stdout is each point's depth in rigid material (mm, the distance
to the bone's surface; 0 outside it) instead."""

import json
import sys

import numpy as np
from hapticut import cut_surface
from hapticut.engine import load_space
from hapticut_evaluation.rigid_blade import bone_surface, depth_in_bone

CUTTABLE = ("drag", "viscous", "membrane")


def main(path: str, cut: bool, depth: bool) -> None:
    scene, space = load_space(path)
    points = np.array(json.load(sys.stdin), np.float64).reshape(-1, 3)
    tets = space.locate(points)
    models = [m.model for m in scene.materials]
    found = [models[scene.tet_materials[t]] if t >= 0 else "" for t in tets]
    if depth:
        rigid = np.array([models[m] == "rigid" for m in scene.tet_materials])
        surface = bone_surface(space, rigid)
        inside = zip(points, found, strict=True)
        depths = [depth_in_bone(p, surface) if m == "rigid" else 0.0 for p, m in inside]
        print(json.dumps(depths))
        return
    if cut:
        tied = [i for i, m in enumerate(found) if m not in CUTTABLE]
        own = cut_surface.TetLocator(scene.vertices, scene.tets).locate(points[tied])
        for i, t in zip(tied, own, strict=True):
            if t >= 0 and models[scene.tet_materials[t]] in CUTTABLE:
                found[i] = models[scene.tet_materials[t]]
    print(json.dumps(found))


if __name__ == "__main__":
    main(sys.argv[1], "--cut" in sys.argv[2:], "--depth" in sys.argv[2:])
