"""``hapticut bench transitions|blade|stability``: benchmarks, beside their anchors."""

from __future__ import annotations

import argparse
import platform
import sys
from pathlib import Path

NAME = "bench"
HELP = (
    "Print the benchmark tables (Table 2 transitions, blade ticks, the servo process, "
    "loop stability)."
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "which", choices=["transitions", "blade", "servo", "stability"], help="which benchmark"
    )
    parser.add_argument("--repeats", type=int, default=20000, help="calls per timed batch")
    parser.add_argument("--batches", type=int, default=15, help="batches (the median is shown)")
    parser.add_argument(
        "--rounds",
        type=int,
        default=5,
        help="time every row this many times in turn; each keeps its best round",
    )
    parser.add_argument(
        "--duration", type=float, default=1.5, help="servo: seconds per row (16 rows)"
    )
    parser.add_argument(
        "--no-max-points", action="store_true", help="blade: skip the points-in-100-µs search"
    )
    parser.add_argument(
        "--scenes",
        type=Path,
        default=None,
        help="blade: directory of example scenes (default: those shipped in the package)",
    )


def run(args: argparse.Namespace) -> int:
    print(
        f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}"
    )
    if args.which == "transitions":
        from hapticut.bench import transitions

        print(transitions.run(args.repeats, args.batches, args.rounds))
    elif args.which == "servo":
        from hapticut.bench import servo

        print(servo.run(duration_s=args.duration))
    elif args.which == "stability":
        from hapticut.bench import stability

        print(stability.run())
    else:
        from hapticut.bench import blade

        try:
            print(blade.run(not args.no_max_points, args.rounds, args.scenes))
        except FileNotFoundError as error:
            print(f"hapticut bench blade: {error}", file=sys.stderr)
            return 2
    return 0
