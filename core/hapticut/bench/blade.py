"""``hapticut bench blade``: ns per tick of a 50-point blade stroke (the paper's set-up).

The paper ran 50 points on a 0.1 m edge at about 1 kHz on its spheres (80 and
320 faces, radius 30 mm, in a tetrahedralized cube) and a ~12k-tet mouse. Here
the same stroke runs through the example scenes (the bunny stands in for the
mouse) and through a generated ~12k-tet grid, timed per tick in C++. Then the
largest number of blade points whose median tick fits in 100 µs (10% of a 1 kHz
period on one core) is searched.
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from hapticut import _core, engine
from hapticut.bench.table import format_table

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"
BLADE_HALF_LENGTH_MM = 50.0  # The paper's 0.1 m edge.
STROKE_SPEED_MM_PER_S = 100.0
BUDGET_NS = 100_000.0


def _example(patterns: list[str]) -> Path | None:
    for pattern in patterns:
        found = sorted(EXAMPLES.glob(pattern))
        if found:
            return found[0]
    return None


def _grid_space() -> _core.Space:
    """About 12k tets: a 14 x 12 x 12-cell box (6 tets a cell), a drag ball inside."""
    xs = np.linspace(-70, 70, 15)
    ys = np.linspace(-60, 60, 13)
    zs = np.linspace(-60, 60, 13)
    vertices, tets = _core.grid_mesh(xs.tolist(), ys.tolist(), zs.tolist(), 0.3, 3)
    centres = vertices[tets].mean(axis=1)
    labels = (np.linalg.norm(centres, axis=1) < 35).astype(np.int32)
    materials = [
        {"name": "air", "model": "free"},
        {"name": "tissue", "model": "drag", "drag_distance_mm": 1.0},
    ]
    return _core.Space(vertices, tets, labels, materials)


def _as_cut(scene) -> _core.Space:
    """The scene with every non-free material made tissue (drag, D = 1 mm): the paper's cut."""
    materials = [
        m
        if m.model == "free"
        else replace(m, model="drag", drag_distance_mm=1.0, break_force_N=0.0)
        for m in scene.materials
    ]
    return engine.space_from_scene(replace(scene, materials=materials))


def scenes() -> list[tuple[str, _core.Space]]:
    """Each example twice: cut (bodies as drag tissue, the paper's use) and as authored
    (rigid bodies: every point that reaches the body is held on its surface, the costly case)."""
    out = []
    for label, patterns in (
        ("sphere 80 faces", ["sphere80*.hapticut.*"]),
        ("sphere 320 faces", ["sphere320*.hapticut.*"]),
        ("bunny (the paper's mouse)", ["mouse*.hapticut.*", "bunny*.hapticut.*"]),
    ):
        path = _example(patterns)
        if path is None:
            continue
        scene, space = engine.load_space(path)
        out.append((f"{label}, cut (drag 1 mm)", _as_cut(scene)))
        out.append((f"{label}, as authored ({_models(scene)})", space))
    out.append(("grid ~12k tets, drag ball (generated)", _grid_space()))
    return out


def _models(scene) -> str:
    return "/".join(sorted({m.model for m in scene.materials if m.model != "free"}))


def stroke_poses(space: _core.Space) -> np.ndarray:
    """The tool origin crosses the mesh's centre along y; the edge lies along x."""
    vertices = space.vertices
    centre = (vertices.min(axis=0) + vertices.max(axis=0)) / 2
    half = (vertices.max(axis=0) - vertices.min(axis=0)) / 2
    reach = 0.75 * half[1]
    return engine.straight_stroke(
        centre - [0, reach, 0], centre + [0, reach, 0], STROKE_SPEED_MM_PER_S
    )


def time_ticks(space: _core.Space, points: int, poses: np.ndarray, repeats: int = 3) -> dict:
    """Per-tick ns of a blade of `points` points along the stroke (best of repeats by median)."""
    best = None
    for _ in range(repeats):
        r = _core.time_blade(
            space, [-BLADE_HALF_LENGTH_MM, 0, 0], [BLADE_HALF_LENGTH_MM, 0, 0], points, poses
        )
        if best is None or np.median(r["tick_ns"]) < np.median(best["tick_ns"]):
            best = r
    return best


def max_points_within(space: _core.Space, poses: np.ndarray, budget_ns: float = BUDGET_NS) -> int:
    """Largest blade point count whose median tick fits the budget (bisection on counts)."""
    middle = len(poses) // 2
    short = poses[max(0, middle - 150) : middle + 150]  # where the blade is in the body
    lo, hi = 50, 50
    while np.median(time_ticks(space, hi, short, 3)["tick_ns"]) <= budget_ns and hi < 2_000_000:
        lo, hi = hi, hi * 2
    while hi - lo > max(8, lo // 50):
        mid = (lo + hi) // 2
        if np.median(time_ticks(space, mid, short, 3)["tick_ns"]) <= budget_ns:
            lo = mid
        else:
            hi = mid
    return lo


def run(find_max: bool = True, rounds: int = 3) -> str:
    """The table. Every scene is timed once per round, in turn, and keeps its best
    round (lowest median tick; most points within the budget): this machine's slow
    spells last seconds, and a scene timed inside one reads up to twice its cost."""
    cases = [(label, space, stroke_poses(space)) for label, space in scenes()]
    best: list[dict | None] = [None] * len(cases)
    most = [0] * len(cases)
    search_s = [0.0] * len(cases)
    for _ in range(max(1, rounds)):
        for k, (_, space, poses) in enumerate(cases):
            r = time_ticks(space, 50, poses)
            if best[k] is None or np.median(r["tick_ns"]) < np.median(best[k]["tick_ns"]):
                best[k] = r
            if find_max:
                started = time.perf_counter()
                most[k] = max(most[k], max_points_within(space, poses))
                search_s[k] += time.perf_counter() - started
    rows = []
    for k, (label, space, poses) in enumerate(cases):
        r = best[k]
        ticks = np.asarray(r["tick_ns"])
        row = [
            label,
            space.tet_count,
            len(poses),
            float(np.median(ticks)),
            float(np.percentile(ticks, 99)),
            float(ticks.max()),
            float(np.median(ticks) / 50),
            int(np.max(r["max_transitions"])),
            int(np.sum(r["capped_points"])),
        ]
        if find_max:
            row.append(most[k])
            row.append(f"{search_s[k]:.0f} s")
        rows.append(row)
    headers = [
        "scene",
        "tets",
        "ticks",
        "median ns/tick",
        "p99 ns",
        "max ns",
        "ns/point",
        "max transitions",
        "capped points",
    ]
    if find_max:
        headers += ["points in 100 µs", "search time"]
    paper = (
        "Paper (Pentium Pro 200 MHz): 50 points at about 1 kHz, i.e. about 1 ms per tick.\n"
        "Targets: 50-point tick on ~12k tets <= 5 µs median; >= 2000 points within 100 µs.\n"
    )
    return paper + format_table(headers, rows)
