"""``hapticut demo-stroke``: a 50-point blade stroke through an example scene, as text.

Down onto the paper's 320-face sphere until 5 mm in, then across it, at 100 mm/s and 1 kHz;
prints the force and the points' states every 100 ticks and the transitions over the stroke.
The README's demo (examples/demo.sh) is the Blender one; this is the look without Blender.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from hapticut import engine
from hapticut.bench.blade import example_scenes

NAME = "demo-stroke"
HELP = "Run a 50-point blade stroke through an example scene and print forces and states."
DEFAULT_SCENE = "sphere320"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "scene", nargs="?", help=f"a scene file (default: the {DEFAULT_SCENE} example)"
    )


def default_scene() -> Path:
    found, where = example_scenes()
    for path in found:
        if path.name.startswith(DEFAULT_SCENE + "."):
            return path
    raise FileNotFoundError(f"the {DEFAULT_SCENE} example scene was not found ({where})")


def stroke(space) -> np.ndarray:
    """Poses (x, y, z, qw, qx, qy, qz) at 1 kHz: down through the top, then across."""
    lo, hi = space.vertices.min(axis=0), space.vertices.max(axis=0)
    centre = (lo + hi) / 2
    reach = 0.45 * (hi - lo)[1]
    down = engine.straight_stroke(centre + [0, 0, reach], centre + [0, 0, 25], 100)
    across = engine.straight_stroke(centre + [0, 0, 25], centre + [0, reach, 25], 100)
    return np.vstack([down, across[1:]])


def run(args: argparse.Namespace) -> int:
    try:
        path = Path(args.scene) if args.scene else default_scene()
        scene, space = engine.load_space(path)
    except (OSError, ValueError) as error:  # Missing, unreadable or malformed: one line.
        print(f"hapticut demo-stroke: {error}", file=sys.stderr)
        return 1
    names = [m.name for m in scene.materials]
    counts = np.bincount(space.tet_materials, minlength=len(names))
    print(f"scene {path.name}: {space.tet_count} tets, {space.vertex_count} vertices")
    print(
        "  materials: "
        + ", ".join(
            f"{n} ({m.model}) {c} tets"
            for n, m, c in zip(names, scene.materials, counts, strict=True)
        )
    )
    spec = scene.blades[0] if scene.blades else engine.BladeSpec("blade", (-50, 0, 0), (50, 0, 0))
    blade = engine.make_blade(space, spec)
    poses = stroke(space)
    blade.reset(poses[0])
    print(
        f"blade: {blade.point_count} points, k = {space.stiffness_N_per_mm} N/mm, "
        f"{len(poses)} ticks at 1 kHz\n"
    )
    print(f"{'tick':>5} {'origin (mm)':>24} {'|F| N':>7} {'F (N)':>26}  states")
    for k, pose in enumerate(poses):
        tick = blade.step(pose, 0.001)
        if k % 100 == 0 or k == len(poses) - 1:
            f = tick["force_N"]
            states = engine.state_counts(blade.state)
            shown = " ".join(f"{s}:{c}" for s, c in states.items() if c)
            origin = " ".join(f"{x:7.1f}" for x in pose[:3])
            force = " ".join(f"{x:8.3f}" for x in f)
            print(f"{k:5d} {origin:>24} {np.linalg.norm(f):7.3f} {force:>26}  {shown}")
    counters = blade.counters
    per_kind = counters["transitions"].sum(axis=(0, 3))
    print("\ntransitions over the stroke (from -> to):")
    for i, a in enumerate(engine.STATE_NAMES):
        row = ", ".join(
            f"{b} {int(per_kind[i, j])}" for j, b in enumerate(engine.STATE_NAMES) if per_kind[i, j]
        )
        if row:
            print(f"  {a:>7} -> {row}")
    print(
        f"capped ticks: {int(counters['capped_ticks'].sum())}, "
        f"most transitions in one tick: {int(counters['max_transitions_in_tick'].max())}"
    )
    return 0
