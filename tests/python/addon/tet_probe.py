"""The material model of the tet holding each point, by the engine (hapticut._core) in a child
Python, never inside bpy's process: the reference the live tests check the cut surface with.
stdin: JSON [[x, y, z], ...] in mm; stdout: JSON ["drag", "rigid", "free", "" (outside), ...]."""

import json
import sys

import numpy as np
from hapticut.engine import load_space


def main(path: str) -> None:
    scene, space = load_space(path)
    points = np.array(json.load(sys.stdin), np.float64).reshape(-1, 3)
    tets = space.locate(points)
    models = [m.model for m in scene.materials]
    print(json.dumps([models[scene.tet_materials[t]] if t >= 0 else "" for t in tets]))


if __name__ == "__main__":
    main(sys.argv[1])
