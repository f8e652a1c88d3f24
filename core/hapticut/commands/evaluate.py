"""`hapticut evaluate`: baselines, accuracy, stability and mesh economy."""

from __future__ import annotations

import argparse
from pathlib import Path

NAME = "evaluate"
HELP = (
    "Run the evaluation (tet proxy, force shading, god-object and voxel baselines) and "
    "write CSV files, a chart and a markdown page."
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("docs/evaluation"),
        help="output folder (default: docs/evaluation)",
    )
    parser.add_argument(
        "--quick",
        action="store_true",
        help="reduced run: fewer models, shorter walks (what the tests run)",
    )


def run(args: argparse.Namespace) -> int:
    from hapticut.evaluation.run import run_all

    result = run_all(args.out, quick=args.quick)
    failed = [
        r for r in result["stability"] if r["family"].startswith("tet") and r["verdict"] != "pass"
    ]
    for r in failed:
        print(f"tet proxy FAILED: {r['scenario']} ({r['method']}): {r['figure']}")
    return 1 if failed else 0
