"""`python -m hapticut_evaluation` (`hapticut-evaluate`): baselines, accuracy, stability and
mesh economy, written to a folder as CSV files, charts and a Markdown page."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="hapticut-evaluate",
        description="Run the evaluation (tet proxy, force shading, god-object and voxel "
        "baselines) and write CSV files, charts and a Markdown page.",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("docs/evaluation"),
        help="output folder (default: docs/evaluation); its cache/ keeps the built meshes",
    )
    parser.add_argument(
        "--examples",
        type=Path,
        default=Path("examples"),
        help="the repository's examples/ folder (default: examples, from the repository's root)",
    )
    parser.add_argument(
        "--quick",
        action="store_true",
        help="reduced run: fewer models, shorter walks (what the tests run)",
    )
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    from hapticut_evaluation import economy
    from hapticut_evaluation.run import run_all

    economy.use_examples(args.examples)
    result = run_all(args.out, quick=args.quick)
    failed = [
        r for r in result["stability"] if r["family"].startswith("tet") and r["verdict"] != "pass"
    ]
    for r in failed:
        print(f"tet proxy FAILED: {r['scenario']} ({r['method']}): {r['figure']}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
