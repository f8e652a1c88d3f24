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
        default=None,
        help="time every row this many times in turn; each keeps its best round "
        "(default: transitions 5, blade 5, servo 3)",
    )
    parser.add_argument(
        "--duration", type=float, default=1.5, help="servo: seconds per row (16 rows a round)"
    )
    parser.add_argument(
        "--no-max-points", action="store_true", help="blade: skip the points-in-100-µs search"
    )
    parser.add_argument(
        "--points",
        type=int,
        default=50,
        help="stability: the blade's points (default 50, the example scenes' scalpel)",
    )
    parser.add_argument(
        "--coupling",
        choices=["rigid", "independent"],
        default="rigid",
        help="stability: the blade's coupling; a rigid blade renders points x k in contact",
    )
    parser.add_argument(
        "--stiffness",
        type=_stiffness_list,
        default=None,
        help="stability: point stiffnesses k, N/mm, comma-separated (as in a scene file); "
        "only the second table, at what the blade renders with them",
    )
    parser.add_argument(
        "--profile", type=Path, default=None, help="stability: a device profile's limits"
    )
    parser.add_argument(
        "--scenes",
        type=Path,
        default=None,
        help="blade, servo: directory of scenes (default: the examples shipped in the package)",
    )


def _stiffness_list(text: str) -> list[float]:
    try:
        values = [float(item) for item in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a comma-separated list") from None
    if any(not value > 0 for value in values):
        raise argparse.ArgumentTypeError(f"stiffnesses must be > 0 N/mm, got {text!r}")
    return values


def _rounds(args: argparse.Namespace, default: int) -> int:
    return default if args.rounds is None else args.rounds


def run(args: argparse.Namespace) -> int:
    print(
        f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}"
    )
    if args.which == "transitions":
        from hapticut.bench import transitions

        print(transitions.run(args.repeats, args.batches, _rounds(args, 5)))
    elif args.which == "servo":
        from hapticut.bench import servo

        scenes = sorted(args.scenes.glob("*.hapticut.msgpack")) if args.scenes else None
        print(servo.run(duration_s=args.duration, scenes=scenes, rounds=_rounds(args, 3)))
    elif args.which == "stability":
        from hapticut.bench import stability

        if args.points < 1:
            print("hapticut bench stability: --points must be >= 1", file=sys.stderr)
            return 2
        extra = ["--profile", str(args.profile)] if args.profile else []
        print(
            stability.run(
                extra,
                points=args.points,
                coupling=args.coupling,
                point_stiffness=args.stiffness,
            )
        )
    else:
        from hapticut.bench import blade

        try:
            print(blade.run(not args.no_max_points, _rounds(args, 5), args.scenes))
        except FileNotFoundError as error:
            print(f"hapticut bench blade: {error}", file=sys.stderr)
            return 2
    return 0
