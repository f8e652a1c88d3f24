"""Scene-building benchmark: build time per example, the paper's Table 3 beside ours, and
uniform against adaptive sizing on the mouse (bunny) and the layered finger.

    python examples/benchmark_build.py [--repeats N]

Prints Markdown tables (recorded in docs/scene-building.md). Nothing is written to disk.
fTetWild's output differs between runs, so counts move by a few percent from run to run.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import build_examples  # noqa: E402  (the examples' own recipes)

PAPER_TABLE3 = {  # Tanaka, Hirota and Kaneko, Table 3.
    "sphere80": (394, 234, 160, 82),
    "sphere320": (1917, 637, 1280, 353),
    "mouse": (11831, 5519, 6312, 2099),
}


def counts(scene) -> tuple[int, int, int, int]:
    """(tets, air tets, body tets, vertices)."""
    air = int((scene.tet_materials == 0).sum())
    return len(scene.tets), air, len(scene.tets) - air, len(np.unique(scene.tets))


def build_times(repeats: int) -> dict:
    rows = {}
    print("## Build time per example\n")
    print("| example | regions | faces in | faces meshed | tets | vertices | tets per material "
          "| min dihedral | max tets/edge | max tets/vertex | build s (median) |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in build_examples.EXAMPLES:
        runs = [build_examples.build_example(name) for _ in range(repeats)]
        scene, _ = runs[-1]
        seconds = float(np.median([s for _, s in runs]))
        report = scene.metadata["build_report"]
        faces_in = sum(s["faces_in"] for s in report["surfaces"].values())
        faces_meshed = sum(s["faces_meshed"] for s in report["surfaces"].values())
        per_material = ", ".join(f"{k} {v}" for k, v in report["tets_per_material"].items())
        print(
            f"| {name} | {len(report['surfaces'])} | {faces_in} | {faces_meshed} | "
            f"{report['tets']} | {report['used_vertices']} | {per_material} | "
            f"{report['quality']['min_dihedral_deg']:.1f} | "
            f"{report['valence']['max_tets_per_edge']} | "
            f"{report['valence']['max_tets_per_vertex']} | {seconds:.2f} |"
        )
        rows[name] = scene
    return rows


def table3(scenes: dict) -> None:
    print("\n## Table 3: the paper's models beside ours\n")
    print("| model | paper tets | ours | paper air | ours | paper body | ours "
          "| paper vertices | ours |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|")
    for name, paper in PAPER_TABLE3.items():
        ours = counts(scenes[name])
        cells = " | ".join(f"{p} | {o}" for p, o in zip(paper, ours, strict=True))
        print(f"| {name} | {cells} |")


def uniform_against_adaptive() -> None:
    print("\n## Uniform against adaptive sizing\n")
    print("Uniform: the adaptive build's near-surface edge length everywhere. Deviation: "
          "symmetric Hausdorff distance (pymeshlab) between each input surface and the "
          "meshed one, the largest over the regions.\n")  # fmt: skip
    print("| example | sizing | edge near / far mm | tets | build s | deviation mm |")
    print("|---|---|---|---|---|---|")
    for name in ("mouse", "finger"):
        adaptive, adaptive_s = build_examples.build_example(name)
        near = adaptive.metadata["build_report"]["settings"]["edge_near_mm"]
        uniform, uniform_s = build_examples.build_example(
            name, {"adaptive": False, "edge_near_mm": near}
        )
        for label, scene, seconds in (("uniform", uniform, uniform_s),
                                      ("adaptive", adaptive, adaptive_s)):  # fmt: skip
            report = scene.metadata["build_report"]
            settings = report["settings"]
            deviation = max(report["deviation_mm"].values())
            print(
                f"| {name} | {label} | {settings['edge_near_mm']:.2f} / "
                f"{settings['edge_far_mm']:.2f} | {report['tets']} | {seconds:.2f} | "
                f"{deviation:.3f} |"
            )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=1, help="builds per example (median)")
    args = parser.parse_args()
    print(f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}\n")  # fmt: skip
    scenes = build_times(args.repeats)
    table3(scenes)
    uniform_against_adaptive()
    return 0


if __name__ == "__main__":
    sys.exit(main())
