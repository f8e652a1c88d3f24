"""``hapticut bench blade``: ns per tick of a 50-point blade stroke (the paper's set-up).

The paper ran 50 points on a 0.1 m edge at about 1 kHz on its spheres (80 and
320 faces, radius 30 mm, in a tetrahedralized cube) and a ~12k-tet mouse. Here
the same stroke runs through every example scene (the bunny, ``mouse``, stands
in for the paper's mouse), through a generated ~12k-tet grid and along a generated
90° crease of bone (pressed 1 mm in and slid 20 mm along it), timed per tick
in C++, with the scene's own settings per tick (work budget included), once
with a rigid blade (the default: one ideal pose for the edge, its rounds of
walks and fits) and once with the paper's independent points. The table shows
each scene's worst tick (time, transitions of all points, a rigid blade's most
rounds) and its capped points, and the ticks in contact (the rigid blade resting on
rigid material): their median and p99 for both couplings, and the rigid blade's cost
there against the independent points'. The cost of cut memory (docs/decisions.md, "Cut
memory"): every stroke is timed again by a blade without it, which reads and cuts no tet
(``cut_memory=False``), and the table gives the tets the stroke cut and the extra median and
p99 per tick. Then the largest number of blade points whose median tick fits in 100 µs (10%
of a 1 kHz period on one core) is searched.

The example scenes ship in the package (``hapticut/examples``); the working directory's
``examples/`` (a source checkout's) is used when the package has none, and ``--scenes DIR``
names another directory. When none is found the table says so instead of dropping them.
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import numpy as np

import hapticut
from hapticut import _core, engine
from hapticut.bench.table import format_table
from hapticut.scenefile import Material

# Where the example scenes are looked for, in this order (see the module docstring).
PACKAGED_EXAMPLES = Path(hapticut.__file__).resolve().parent / "examples"
SCENE_PATTERN = "*.hapticut.*"
BLADE_HALF_LENGTH_MM = 50.0  # The paper's 0.1 m edge.
STROKE_SPEED_MM_PER_S = 100.0
BUDGET_NS = 100_000.0
TARGET_P99_NS = 5_000.0  # No tick over 5 µs p99 for a 50-point blade.
# The tissue a stroke cuts acts as this drag from then on (its cut variant, cut_to): a tenth,
# so the memory's reads and cuts run as a scene with cut memory runs them.
CUT_DRAG_MM = 0.1
CUT_TISSUE = {"name": "tissue, cut", "model": "drag", "drag_distance_mm": CUT_DRAG_MM}
# The paper's names for the examples; any other scene is labelled by its file name.
LABELS = {
    "sphere80": "sphere 80 faces",
    "sphere320": "sphere 320 faces",
    "mouse": "bunny (the paper's mouse)",
}


def example_scenes(scenes_dir: Path | None = None) -> tuple[list[Path], str]:
    """The example scene files and a line saying where they came from (or that none was found).

    Raises FileNotFoundError when an explicit scenes_dir does not exist."""
    if scenes_dir is not None:
        scenes_dir = Path(scenes_dir)
        if not scenes_dir.is_dir():
            raise FileNotFoundError(f"--scenes {scenes_dir}: no such directory")
        candidates = [scenes_dir]
    else:
        candidates = [PACKAGED_EXAMPLES, Path.cwd() / "examples"]
    for directory in candidates:
        found = sorted(directory.glob(SCENE_PATTERN)) if directory.is_dir() else []
        if found:
            return found, f"example scenes: {len(found)} in {directory}"
    where = " or ".join(str(d) for d in candidates)
    return [], f"NO EXAMPLE SCENES FOUND (looked in {where}); pass --scenes DIR"


def _label(path: Path) -> str:
    stem = path.name.split(".hapticut.")[0]
    return LABELS.get(stem, stem)


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
        {"name": "tissue", "model": "drag", "drag_distance_mm": 1.0, "cut_to": CUT_TISSUE["name"]},
        CUT_TISSUE,
    ]
    return _core.Space(vertices, tets, labels, materials)


CREASE_LABEL = "90° V-groove of bone along the blade (generated)"
CREASE_SLOPE = 1.0  # The groove's angle is 2 atan(1 / slope).


def crease_space() -> _core.Space:
    """A V-groove of bone running along x, the blade's direction (issue #38's crease): a
    grid with every vertex lifted by CREASE_SLOPE |y|, bone under the lifted z = 0."""
    xs = np.linspace(-80, 80, 41)
    ys = np.linspace(-10, 10, 11)
    zs = np.linspace(-10, 10, 11)
    vertices, tets = _core.grid_mesh(xs.tolist(), ys.tolist(), zs.tolist(), 0.0, 0)
    labels = (vertices[tets][:, :, 2].mean(axis=1) < 0).astype(np.int32)
    vertices = vertices.copy()
    vertices[:, 2] += CREASE_SLOPE * np.abs(vertices[:, 1])
    materials = [{"name": "air", "model": "free"}, {"name": "bone", "model": "rigid"}]
    return _core.Space(vertices, tets, labels, materials)


def crease_poses() -> np.ndarray:
    """Pressed 1 mm into the groove at 10 mm/s, then 20 mm along it at the stroke speed."""
    press = engine.straight_stroke([0, 0, 2], [0, 0, -1], 10.0)
    slide = engine.straight_stroke([0, 0, -1], [20, 0, -1], STROKE_SPEED_MM_PER_S)
    return np.concatenate([press, slide[1:]])


def _as_cut(scene) -> _core.Space:
    """The scene with every non-free material made tissue (drag, D = 1 mm): the paper's cut;
    once cut, the tissue acts as CUT_TISSUE."""
    materials = [
        m
        if m.model == "free"
        else replace(
            m, model="drag", drag_distance_mm=1.0, break_force_N=0.0, cut_to=CUT_TISSUE["name"]
        )
        for m in scene.materials
    ]
    materials.append(Material(**CUT_TISSUE))
    return engine.space_from_scene(replace(scene, materials=materials))


def scenes(paths: list[Path] | None = None) -> list[tuple[str, _core.Space]]:
    """Each example twice: cut (bodies as drag tissue, the paper's use) and as authored
    (rigid bodies: every point that reaches the body is held on its surface, the costly case);
    then the generated grid. paths: the example scene files (default: example_scenes())."""
    if paths is None:
        paths, _ = example_scenes()
    out = []
    for path in paths:
        scene, space = engine.load_space(path)
        label = _label(path)
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


COUPLINGS = ("rigid", "independent")


def _faster(best: dict | None, r: dict) -> dict:
    """The round of lower median tick."""
    return r if best is None or np.median(r["tick_ns"]) < np.median(best["tick_ns"]) else best


def time_ticks(
    space: _core.Space,
    points: int,
    poses: np.ndarray,
    repeats: int = 3,
    coupling: str = "rigid",
    cut_memory: bool = True,
) -> dict:
    """Per-tick ns of a blade of `points` points along the stroke (best of repeats by median),
    each repeat from uncut tissue; cut_memory=False: a blade that reads and cuts no tet."""
    best = None
    for _ in range(repeats):
        r = _core.time_blade(
            space,
            [-BLADE_HALF_LENGTH_MM, 0, 0],
            [BLADE_HALF_LENGTH_MM, 0, 0],
            points,
            poses,
            coupling=coupling,
            cut_memory=cut_memory,
        )
        best = _faster(best, r)
    return best


def max_points_within(
    space: _core.Space, poses: np.ndarray, budget_ns: float = BUDGET_NS, coupling: str = "rigid"
) -> int:
    """Largest blade point count whose median tick fits the budget (bisection on counts), at
    most the most a blade takes."""
    middle = len(poses) // 2
    short = poses[max(0, middle - 150) : middle + 150]  # where the blade is in the body

    def fits(points: int) -> bool:
        ticks = time_ticks(space, points, short, 3, coupling)["tick_ns"]
        return bool(np.median(ticks) <= budget_ns)

    most = _core.BLADE_MAX_POINTS  # A blade refuses more.
    lo, hi = 50, 50
    while fits(hi):
        if hi == most:
            return most
        lo, hi = hi, min(hi * 2, most)
    while hi - lo > max(8, lo // 50):
        mid = (lo + hi) // 2
        if fits(mid):
            lo = mid
        else:
            hi = mid
    return lo


CUT_MEMORY_HEADERS = [
    "tets cut",
    "median ns/tick without cut memory",
    "p99 ns without cut memory",
    "cut memory +median ns",
    "cut memory +median %",
    "cut memory +p99 ns",
]


def cut_memory_figures(with_memory: dict, without: dict) -> list:
    """The CUT_MEMORY_HEADERS columns of one row: the tets the stroke cut, the blade
    without cut memory's median and p99 per tick, and what the memory adds to them."""
    ticks = np.asarray(with_memory["tick_ns"])
    plain = np.asarray(without["tick_ns"])
    median, plain_median = float(np.median(ticks)), float(np.median(plain))
    p99, plain_p99 = float(np.percentile(ticks, 99)), float(np.percentile(plain, 99))
    return [
        int(with_memory["cut_tets"]),
        plain_median,
        plain_p99,
        median - plain_median,
        100.0 * (median - plain_median) / plain_median,
        p99 - plain_p99,
    ]


def run(find_max: bool = True, rounds: int = 3, scenes_dir: Path | None = None) -> str:
    """The table. Every scene is timed once per round, in turn, with and without cut
    memory, and keeps its best round of each (lowest median tick; most points within the
    budget): this machine's slow spells last seconds, and a scene timed inside one reads up
    to twice its cost. The capped points and the worst tick's transitions are those of the
    best round."""
    paths, found = example_scenes(scenes_dir)
    strokes = [(label, space, stroke_poses(space)) for label, space in scenes(paths)]
    strokes.append((CREASE_LABEL, crease_space(), crease_poses()))
    cases = [
        (label, space, poses, coupling) for label, space, poses in strokes for coupling in COUPLINGS
    ]
    best: list[dict | None] = [None] * len(cases)
    best_without: list[dict | None] = [None] * len(cases)  # The blade without cut memory.
    most = [0] * len(cases)
    search_s = [0.0] * len(cases)
    for _ in range(max(1, rounds)):
        for k, (_, space, poses, coupling) in enumerate(cases):
            r = time_ticks(space, 50, poses, coupling=coupling)
            best[k] = _faster(best[k], r)
            r = time_ticks(space, 50, poses, coupling=coupling, cut_memory=False)
            best_without[k] = _faster(best_without[k], r)
            if find_max:
                started = time.perf_counter()
                most[k] = max(most[k], max_points_within(space, poses, coupling=coupling))
                search_s[k] += time.perf_counter() - started
    # In contact: the ticks where the rigid blade rests on rigid material, the same
    # device poses for both couplings of a scene.
    contact = {
        label: np.asarray(best[k]["contacts"]) > 0
        for k, (label, _, _, coupling) in enumerate(cases)
        if coupling == "rigid"
    }
    in_contact = {
        (label, coupling): np.asarray(best[k]["tick_ns"])[contact[label]]
        for k, (label, _, _, coupling) in enumerate(cases)
    }

    def contact_figures(label: str, coupling: str) -> list:
        ticks = in_contact[(label, coupling)]
        if ticks.size == 0:
            return [0, "-", "-", "-"]
        ratio = "-"
        if coupling == "rigid" and in_contact[(label, "independent")].size:
            ratio = f"{np.median(ticks) / np.median(in_contact[(label, 'independent')]):.1f}x"
        return [int(ticks.size), float(np.median(ticks)), float(np.percentile(ticks, 99)), ratio]

    rows = []
    for k, (label, space, poses, coupling) in enumerate(cases):
        r = best[k]
        ticks = np.asarray(r["tick_ns"])
        row = [
            label,
            coupling,
            space.tet_count,
            len(poses),
            float(np.median(ticks)),
            float(np.percentile(ticks, 99)),
            float(ticks.max()),
            float(np.median(ticks) / 50),
            int(np.max(r["max_transitions"])),
            int(np.max(r["tick_transitions"])),
            int(np.max(r["rigid_rounds"])) if coupling == "rigid" else "-",
            *contact_figures(label, coupling),
            int(np.sum(r["unresolved"])) if coupling == "rigid" else "-",
            int(r["budget"]),
            int(np.sum(r["capped_points"])),
            "yes"
            if np.percentile(ticks, 99) <= TARGET_P99_NS and not np.any(r["capped_points"])
            else "NO",
            *cut_memory_figures(r, best_without[k]),
        ]
        if find_max:
            row.append(most[k])
            row.append(f"{search_s[k]:.0f} s")
        rows.append(row)
    headers = [
        "scene",
        "coupling",
        "tets",
        "ticks",
        "median ns/tick",
        "p99 ns",
        "max ns",
        "ns/point",
        "max transitions (point)",
        "worst tick transitions",
        "max rounds",
        "contact ticks",
        "median in contact ns",
        "p99 in contact ns",
        "rigid / independent in contact",
        "unresolved",
        "budget",
        "capped points",
        "target met",
        *CUT_MEMORY_HEADERS,
    ]
    if find_max:
        headers += ["points in 100 µs", "search time"]
    paper = (
        "Paper (Pentium Pro 200 MHz): 50 points at about 1 kHz, i.e. about 1 ms per tick.\n"
        "Targets: 50-point tick on ~12k tets <= 5 µs median; >= 2000 points within 100 µs;\n"
        'every example scene: no capped point and p99 <= 5 µs ("target met").\n'
        "Worst tick: max ns, and the transitions of all points in the busiest tick (budget:\n"
        "the blade's work budget per tick; a point it does not reach is capped). A rigid\n"
        f"blade's tick also walks and fits its pose in rounds (max rounds, at most "
        f"{_core.BLADE_MAX_RIGID_ROUNDS}); where\n"
        "the device goes on through a rigid body, its held blade's points walk round it.\n"
        "In contact: the ticks where the rigid blade rests on rigid material (the same poses\n"
        "for both couplings); goal: a rigid tick in contact within 3x the independent one.\n"
        "Cut memory: the same stroke by a blade without it (reads and cuts no tet); the extra\n"
        "median and p99 per tick are the best rounds' with it less without it (noise either\n"
        f"way); cut tissue acts as drag {CUT_DRAG_MM:g} mm. Goal: no allocation per tick.\n"
    )
    return paper + found + "\n" + format_table(headers, rows)
