"""``hapticut bench stability``: the passivity controller's table (docs/stability.md).

The bench itself is C++ (server/bench/stability.cpp): a virtual hand presses
on bone through the engine at servo rates of 250 Hz to 1 kHz and link delays of
0 to 5 ms, without and with the passivity controller: first at the stiffnesses
the servo allows a device at each rate (its stiffness limit), then a stress
test beyond them. This runs the installed ``hapticut-stability`` and returns
its tables.

The bench's stiffness is what the loop renders in contact. For a blade that is its point
stiffness k times the points acting together: n k for a rigid blade of n points, k for
independent points (hapticut.stiffness). The tables here are for one blade (the default: the
example scenes' rigid 50-point scalpel): the C++ bench runs the rendered stiffness, which the
servo's limit bounds, and a last column gives the point stiffness k a scene asks for to render
it; ``point_stiffness`` asks for rows by that k.
"""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import hapticut
from hapticut.stiffness import rendered_stiffness_N_per_mm


def stability_path() -> Path:
    """The hapticut-stability executable: $HAPTICUT_STABILITY, else the one in the package."""
    override = os.environ.get("HAPTICUT_STABILITY")
    if override:
        return Path(override)
    return Path(hapticut.__file__).resolve().parent / "bin" / "hapticut-stability"


def run(
    extra_args: list[str] | None = None,
    *,
    points: int = 50,
    coupling: str = "rigid",
    point_stiffness: list[float] | None = None,
) -> str:
    """The tables for a blade of ``points`` points and ``coupling``: the C++ bench at the
    stiffness the blade renders, each row with the point stiffness behind it. With
    ``point_stiffness`` (N/mm per point, as in a scene file) only the second table, at the
    stiffness those render."""
    per_point = rendered_stiffness_N_per_mm(1.0, points, coupling)
    args = list(extra_args or [])
    if point_stiffness is not None:
        if not point_stiffness or any(not k > 0 for k in point_stiffness):
            raise ValueError(f"point stiffness must be > 0 N/mm, got {point_stiffness}")
        rendered = [rendered_stiffness_N_per_mm(k, points, coupling) for k in point_stiffness]
        args += ["--stiffness", ",".join(repr(k) for k in rendered)]
    blade = f"Blade: {coupling}, {points} points"
    if coupling == "rigid":
        blade += (
            f": in contact it renders {points} x its point stiffness k (the k N/mm column, "
            "which the servo's limit bounds); the last column is that k."
        )
    else:
        blade += ": each point renders its own k (the k N/mm column)."
    args += ["--points", str(points), "--coupling", coupling]
    return blade + "\n\n" + with_point_column(_run_bench(args), per_point)


def with_point_column(tables: str, points_per_spring: float) -> str:
    """The bench's tables with a last column "k/point N/mm": each row's k over the springs
    acting together."""
    lines = []
    for line in tables.splitlines():
        if line.startswith("| rate Hz"):
            line += " k/point N/mm |"
        elif line.startswith("|--"):
            line += "-------------:|"
        elif re.match(r"\|\s+\d", line):
            rendered = float(line.split("|")[3])
            line += f" {rendered / points_per_spring:12.6g} |"
        lines.append(line)
    return "\n".join(lines) + ("\n" if tables.endswith("\n") else "")


def _run_bench(extra_args: list[str]) -> str:
    executable = stability_path()
    if not executable.is_file():
        raise FileNotFoundError(
            f"{executable}: hapticut-stability is not installed (pip install . builds it "
            "with HAPTICUT_BUILD_DEVICES on)"
        )
    result = subprocess.run(
        [str(executable), *extra_args], capture_output=True, text=True, check=False
    )
    if result.returncode != 0:
        raise RuntimeError(f"{executable} failed ({result.returncode}): {result.stderr.strip()}")
    return result.stdout
