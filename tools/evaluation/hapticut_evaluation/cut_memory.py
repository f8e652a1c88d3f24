"""Cut memory (docs/decisions.md, "Cut memory"): tissue once cut stays cut.

The engine's blade, through its Python bindings, on two blocks of tissue:
- a slab of flesh (drag 4 mm) whose cut variant drags a tenth as far, crossed along a straight
  line three times by one blade: a first pass, a second pass along the same path (back in its
  own slit), then a pass 5 mm beside it;
- skin (a membrane breaking at 0.5 N) over flesh, the skin's cut variant air (an opened skin
  is a gap): pressed through at one place, pressed again at the same place (re-entry), then
  5 mm beside it.
The force's magnitude along each pass, its peak and mean, against what the materials set:
k D for a point trailing by at most D in drag, the break force for skin.
"""

from __future__ import annotations

import numpy as np
from hapticut import _core, engine

K = 0.1  # N/mm, the Space's default stiffness.
GRID_MM = 2.5
GRID_JITTER = 0.3
GRID_SEED = 5
BESIDE_MM = 5.0  # The parallel pass and the press beside, from the first.
# A blade's tip: one point at the tool's origin, the default (rigid) coupling. The force it
# feels is what the tissue sets, k |q - p| for one spring, with no edge's geometry in it.
BLADE_START_MM = (0.0, 0.0, 0.0)
BLADE_END_MM = (0.0, 0.0, 0.0)
BLADE_POINTS = 1
SPEED_MM_S = 10.0

FLESH_DRAG_MM = 4.0
FLESH_CUT_DRAG_MM = FLESH_DRAG_MM / 10
FLESH_HALF_MM = 10.0  # The slab: |x| < 10, z < 0.
# The slit stroke along x, from air to air, off the grid's planes before the jitter.
SLIT_Y_MM = 0.6
SLIT_Z_MM = -5.6
SLIT_X_MM = (-18.0, 18.0)
# Deep in the slab, where the first pass's tip trails at its full drag (it went in at
# x = -10, D = 4 mm behind the device) and short of the far face: the second pass is read
# here, away from the edges of the slit, where a tip may meet a tet its first pass grazed.
INSIDE_X_MM = (-2.0, 8.0)

SKIN_BREAK_N = 0.5
SKIN_MM = GRID_MM  # Skin for 0 > z > -2.5, flesh under it.
UNDER_SKIN_DRAG_MM = 1.0
PRESS_AT_MM = (0.9, 0.35)  # Off the grid's planes.
PRESS_Z_MM = (5.0, -8.0)  # From the air down through the skin, 5.5 mm into the flesh.

FLESH = "flesh, cut to a tenth"
SKIN = "skin over flesh, cut to air"


def _axis(lo: float, hi: float) -> list[float]:
    return np.arange(lo, hi + 1e-9, GRID_MM).tolist()


def _block(materials: list[dict], label) -> _core.Space:
    """A block on a GRID_MM grid, x in [-20, 20], y in [-10, 10], z in [-15, 10], its inner
    vertices moved by up to GRID_JITTER of a cell (so the tissue's faces are not the strokes'
    planes, as in a built scene); label: the tets' centroids to their materials' indices."""
    vertices, tets = _core.grid_mesh(
        _axis(-20, 20), _axis(-10, 10), _axis(-15, 10), GRID_JITTER, GRID_SEED
    )
    labels = np.asarray(label(vertices[tets].mean(axis=1)), dtype=np.int32)
    return _core.Space(vertices, tets, labels, materials)


def flesh_space() -> _core.Space:
    """Flesh (drag FLESH_DRAG_MM, cut to FLESH_CUT_DRAG_MM) for |x| < 10, z < 0; air round it."""
    materials = [
        {"name": "air", "model": "free"},
        {
            "name": "flesh",
            "model": "drag",
            "drag_distance_mm": FLESH_DRAG_MM,
            "cut_to": "flesh, cut",
        },
        {"name": "flesh, cut", "model": "drag", "drag_distance_mm": FLESH_CUT_DRAG_MM},
    ]
    return _block(materials, lambda c: (np.abs(c[:, 0]) < FLESH_HALF_MM) & (c[:, 2] < 0))


def skin_space() -> _core.Space:
    """Air above z = 0, skin (breaking at SKIN_BREAK_N, cut to air) for SKIN_MM, flesh
    (drag UNDER_SKIN_DRAG_MM) below."""
    materials = [
        {"name": "air", "model": "free"},
        {"name": "skin", "model": "membrane", "break_force_N": SKIN_BREAK_N, "cut_to": "air"},
        {"name": "flesh", "model": "drag", "drag_distance_mm": UNDER_SKIN_DRAG_MM},
    ]
    return _block(materials, lambda c: np.where(c[:, 2] > 0, 0, np.where(c[:, 2] > -SKIN_MM, 1, 2)))


def blade(space: _core.Space) -> _core.Blade:
    return _core.Blade(space, list(BLADE_START_MM), list(BLADE_END_MM), BLADE_POINTS)


def _run(knife: _core.Blade, poses: np.ndarray) -> np.ndarray:
    """|force| (N) at every pose of a stroke from its first pose."""
    knife.reset(poses[0])
    return np.linalg.norm(knife.run(poses, 0.001)["force_N"], axis=1)


def slit_stroke(beside_mm: float = 0.0) -> np.ndarray:
    """Poses of the slit stroke, `beside_mm` along +y from the first pass's line."""
    y = SLIT_Y_MM + beside_mm
    return engine.straight_stroke(
        [SLIT_X_MM[0], y, SLIT_Z_MM], [SLIT_X_MM[1], y, SLIT_Z_MM], SPEED_MM_S
    )


def press_stroke(beside_mm: float = 0.0) -> np.ndarray:
    """Poses of a press straight down through the skin, `beside_mm` along +x."""
    x, y = PRESS_AT_MM[0] + beside_mm, PRESS_AT_MM[1]
    return engine.straight_stroke([x, y, PRESS_Z_MM[0]], [x, y, PRESS_Z_MM[1]], SPEED_MM_S)


SLIT_PASSES = (("first", 0.0), ("second, in the slit", 0.0), ("parallel, 5 mm beside", BESIDE_MM))
SKIN_PASSES = (("first entry", 0.0), ("re-entry, same place", 0.0), ("5 mm beside", BESIDE_MM))


def _passes(space: _core.Space, passes, stroke, axis: str, column: int) -> list[dict]:
    """The passes in turn by one blade: for each, the pose's coordinate `column` as `axis`
    (mm) and |force| (N) at every tick."""
    knife = blade(space)
    out = []
    for name, beside in passes:
        poses = stroke(beside)
        out.append(
            {
                "pass": name,
                "beside_mm": beside,
                axis: poses[:, column],
                "force_N": _run(knife, poses),
                "tets_cut": len(knife.cut_tets),
            }
        )
    return out


def slit_passes() -> list[dict]:
    """The three passes through the flesh, in turn, by one blade: position x (mm) and
    |force| (N) at every tick."""
    return _passes(flesh_space(), SLIT_PASSES, slit_stroke, "x_mm", 0)


def skin_passes() -> list[dict]:
    """The three presses through the skin, in turn, by one blade: the device's height z (mm)
    and |force| (N) at every tick of the way down."""
    return _passes(skin_space(), SKIN_PASSES, press_stroke, "z_mm", 2)


def run_cut_memory(
    slits: list[dict] | None = None, presses: list[dict] | None = None
) -> list[dict]:
    """One row per pass: the peak and mean |force| where it is read (the slit: deep in the
    slab, INSIDE_X_MM; the skin: the whole way down), the whole stroke's peak, the tets the
    blade has cut so far, and what the materials set: uncut, the most a point trailing in
    the flesh feels (k D) and the skin's break force; cut, the most it feels in the cut flesh,
    and under the opened skin (air) in the flesh beneath."""
    slits = slit_passes() if slits is None else slits
    presses = skin_passes() if presses is None else presses
    rows = []
    for p in slits:
        inside = (p["x_mm"] >= INSIDE_X_MM[0]) & (p["x_mm"] <= INSIDE_X_MM[1])
        rows.append(
            _row(
                FLESH,
                p,
                p["force_N"][inside],
                f"x in [{INSIDE_X_MM[0]:g}, {INSIDE_X_MM[1]:g}] mm",
                BLADE_POINTS * K * FLESH_DRAG_MM,
                BLADE_POINTS * K * FLESH_CUT_DRAG_MM,
            )
        )
    for p in presses:
        rows.append(
            _row(
                SKIN,
                p,
                p["force_N"],
                "the way down",
                SKIN_BREAK_N,
                BLADE_POINTS * K * UNDER_SKIN_DRAG_MM,
            )
        )
    return rows


def _row(scene: str, p: dict, read: np.ndarray, where: str, uncut_N: float, cut_N: float) -> dict:
    return {
        "scene": scene,
        "pass": p["pass"],
        "beside_mm": p["beside_mm"],
        "read": where,
        "peak_N": round(float(read.max()), 4),
        "mean_N": round(float(read.mean()), 4),
        "stroke_peak_N": round(float(p["force_N"].max()), 4),
        "tets_cut": p["tets_cut"],
        "uncut_bound_N": round(uncut_N, 4),
        "cut_bound_N": round(cut_N, 4),
    }
