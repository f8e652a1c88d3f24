"""Shared by the scene-building tests: small meshes, a point-to-material lookup and the
`hapticut` command run as a child."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
from hapticut.shapes import icosphere  # noqa: F401 (the tests import it from here)

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "examples"


def bunny_path() -> Path:
    import pymeshlab

    return Path(pymeshlab.__file__).parent / "tests" / "sample_meshes" / "bunny10k_textured.obj"


def run_cli(*args, cwd=None) -> subprocess.CompletedProcess:
    """`hapticut ARGS` as a child (``python -m hapticut.cli``): exit code and text output."""
    return subprocess.run(
        [sys.executable, "-m", "hapticut.cli", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=cwd,
    )


def write_obj(path: Path, vertices, faces) -> Path:
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in np.asarray(vertices, dtype=float)]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in np.asarray(faces)]
    path.write_text("\n".join(lines) + "\n")
    return path


def containing_tets(vertices, tets, points, tolerance=1e-9) -> np.ndarray:
    """(p,) index of a tet holding each point (barycentric test, brute force), -1 if none."""
    vertices, tets, points = (np.asarray(a, dtype=float) for a in (vertices, tets, points))
    tets = tets.astype(int)
    a = vertices[tets[:, 0]]
    frame = np.stack([vertices[tets[:, i]] - a for i in (1, 2, 3)], axis=2)  # (m, 3, 3)
    inverse = np.linalg.inv(frame)
    found = np.full(len(points), -1)
    for i, point in enumerate(points):
        local = np.einsum("mij,mj->mi", inverse, point - a)
        inside = np.all(local >= -tolerance, axis=1) & (local.sum(axis=1) <= 1 + tolerance)
        hits = np.flatnonzero(inside)
        if len(hits):
            found[i] = hits[0]
    return found


def materials_at(scene, points) -> list[str]:
    """The material name at each point ("outside" beyond the mesh)."""
    tets = containing_tets(scene.vertices, scene.tets, points)
    names = [m.name for m in scene.materials]
    return [names[scene.tet_materials[t]] if t >= 0 else "outside" for t in tets]
