"""``hapticut mesh INPUT... -o scene.hapticut.json``: surface meshes to a labelled tet scene.

Each INPUT is a closed surface mesh (OBJ, PLY, STL, OFF); its region is named after the file
(``bone.obj`` -> ``bone``). ``--material bone=rigid`` or
``--material flesh=drag,drag_distance_mm=1`` gives a region its material (default: rigid).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
import time

NAME = "mesh"
HELP = "Build a labelled tetrahedral scene from closed surface meshes (repair, mesh, label)."
DEFAULT_MODEL = "rigid"
_BAR_WIDTH = 30


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description = __doc__
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.add_argument("inputs", nargs="+", metavar="INPUT", help="closed surface mesh files")
    parser.add_argument(
        "--material",
        action="append",
        default=[],
        metavar="REGION=MODEL[,PARAM=VALUE...]",
        help=f"the material of a region: {_models_help()}; name=NAME shares a material between "
        "regions (`hapticut materials` lists ranges and defaults)",
    )
    parser.add_argument("-o", "--output", required=True, help=".hapticut.json or .hapticut.msgpack")
    parser.add_argument("--vtu", help="also write the tet mesh with materials as .vtu (ParaView)")
    parser.add_argument(
        "--enclosure",
        choices=("box", "cube", "tetrahedron"),
        default="box",
        help="the air's outer boundary: tight box, cube (the paper's), or a bounding tetrahedron",
    )
    parser.add_argument("--margin", type=float, metavar="MM", help="gap around the regions")
    parser.add_argument(
        "--accuracy", type=float, metavar="MM", help="allowed deviation from the input surfaces"
    )
    parser.add_argument("--edge-near", type=float, metavar="MM", help="tet edge at the surfaces")
    parser.add_argument("--edge-far", type=float, metavar="MM", help="tet edge far from them")
    parser.add_argument(
        "--grading", type=float, default=0.5, help="edge growth per mm of distance in the regions"
    )
    parser.add_argument(
        "--air-grading", type=float, default=None, metavar="G",
        help="edge growth per mm of distance in the air (default 3: the air coarsens fast)",
    )  # fmt: skip
    parser.add_argument(
        "--strict-accuracy", action="store_true",
        help="fail when a surface cannot be meshed within the accuracy (default: build the best "
        "mesh and report where the accuracy was not held)",
    )  # fmt: skip
    parser.add_argument("--uniform", action="store_true", help="edge-near everywhere (no sizing)")
    parser.add_argument(
        "--no-simplify", action="store_true", help="keep every input face (no simplification)"
    )
    parser.add_argument(
        "--no-coarsen", dest="coarsen", action="store_false",
        help="no fTetWild coarsening (more tets, most of them air)",
    )  # fmt: skip
    parser.add_argument("--coarsen", action="store_true", help=argparse.SUPPRESS)  # the default
    parser.add_argument("--max-hole-edges", type=int, default=100, help="largest hole closed")
    parser.add_argument("--scale", type=float, default=1.0, help="input units to mm (e.g. 1000)")
    parser.add_argument("--threads", type=int, default=0, help="fTetWild threads (0: all)")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress bar")


def _models_help() -> str:
    """'free, drag (drag_distance_mm), rigid, ...' from the material table."""
    from hapticut.scenefile.model import MODEL_PARAMETERS

    parts = []
    for model, parameters in MODEL_PARAMETERS.items():
        parts.append(f"{model} ({', '.join(parameters)})" if parameters else model)
    return ", ".join(parts)


def parse_material(text: str):
    """REGION=MODEL[,PARAM=VALUE...][,name=NAME] -> (region, Material).

    A parameter of another model, or a value outside the table's range, is an error; a required
    parameter left out takes the table's default.
    """
    from hapticut.scenefile import Material
    from hapticut.scenefile.model import (
        MATERIAL_MODELS,
        MODEL_PARAMETERS,
        PARAMETER_RANGES,
        parameter_problem,
    )

    region, _, spec = text.partition("=")
    if not region or not spec:
        raise ValueError(f"--material {text!r}: expected REGION=MODEL[,PARAM=VALUE...]")
    model, *pairs = spec.split(",")
    if model not in MATERIAL_MODELS:
        raise ValueError(f"--material {text!r}: model {model!r} is not one of {MATERIAL_MODELS}")
    takes = MODEL_PARAMETERS[model]
    values: dict = {}
    name = region
    for pair in pairs:
        key, _, value = pair.partition("=")
        if key == "name":
            name = value
            continue
        if key not in PARAMETER_RANGES:
            raise ValueError(f"--material {text!r}: unknown parameter {key!r}")
        if key not in takes:
            accepted = ", ".join(takes) or "none"
            raise ValueError(
                f"--material {text!r}: {key} is not a parameter of model {model!r} "
                f"(it takes: {accepted})"
            )
        try:
            values[key] = float(value)
        except ValueError:
            raise ValueError(f"--material {text!r}: {key} must be a number") from None
        problem = parameter_problem(key, values[key])
        if problem:
            raise ValueError(f"--material {text!r}: {key} {problem}")
    for key, required in takes.items():
        if required:
            values.setdefault(key, PARAMETER_RANGES[key]["default"])
    return region, Material(name=name, model=model, **values)


class ProgressBar:
    """A one-line bar on stderr (a line per step when stderr is not a terminal)."""

    def __init__(self, stream=sys.stderr) -> None:
        self.stream = stream
        self.tty = stream.isatty()
        self.last_message = ""
        self.last_draw = 0.0

    def __call__(self, fraction: float, message: str) -> bool:
        now = time.monotonic()
        step = message.split(" (")[0]
        if self.tty:
            if now - self.last_draw > 0.1 or fraction >= 1.0:
                filled = int(round(fraction * _BAR_WIDTH))
                bar = "#" * filled + "." * (_BAR_WIDTH - filled)
                self.stream.write(f"\r[{bar}] {100 * fraction:3.0f}% {message[:40]:<40}")
                self.stream.flush()
                self.last_draw = now
            if fraction >= 1.0:
                self.stream.write("\n")
        elif step != self.last_message:
            self.stream.write(f"[{100 * fraction:3.0f}%] {step}\n")
            self.stream.flush()
        self.last_message = step
        return True


def run(args: argparse.Namespace) -> int:
    from hapticut.scenebuild import BuildSettings

    try:
        materials = dict(parse_material(text) for text in args.material)
    except ValueError as error:
        print(f"hapticut mesh: {error}", file=sys.stderr)
        return 2
    if not args.output.endswith((".json", ".msgpack")):
        print("hapticut mesh: -o must end in .json or .msgpack", file=sys.stderr)
        return 2
    names = [os.path.basename(path).split(".")[0] for path in args.inputs]
    unknown = sorted(set(materials) - set(names))
    if unknown:
        print(f"hapticut mesh: --material for unknown region(s) {unknown}; regions: {names}",
              file=sys.stderr)  # fmt: skip
        return 2
    settings = BuildSettings(
        enclosure=args.enclosure,
        margin_mm=args.margin,
        accuracy_mm=args.accuracy,
        edge_near_mm=args.edge_near,
        edge_far_mm=args.edge_far,
        grading=args.grading,
        adaptive=not args.uniform,
        strict_accuracy=args.strict_accuracy,
        simplify=not args.no_simplify,
        coarsen=args.coarsen,
        max_hole_edges=args.max_hole_edges,
        threads=args.threads,
        **({"air_grading": args.air_grading} if args.air_grading is not None else {}),
        in_subprocess=True,  # Keeps Ctrl-C prompt while fTetWild runs.
    )
    progress = None if args.quiet else ProgressBar()
    with _terminate_as_exit():
        return _build_and_write(args, materials, names, settings, progress)


@contextlib.contextmanager
def _terminate_as_exit():
    """SIGTERM unwinds like Ctrl-C (the fTetWild child is killed, temporary files go)."""

    def exit_on_terminate(signum, frame):
        raise SystemExit(128 + signum)

    try:
        previous = signal.signal(signal.SIGTERM, exit_on_terminate)
    except ValueError:  # Not the main thread: leave signals alone.
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _build_and_write(args, materials, names, settings, progress) -> int:
    from hapticut.scenebuild import BuildError, Region, build, units_warning
    from hapticut.scenebuild.report import accuracy_lines
    from hapticut.scenebuild.vtu import write_vtu
    from hapticut.scenefile import Material, save_scene

    from .info import format_summary, scene_summary

    try:
        regions = [
            Region.from_file(
                path, materials.get(name) or Material(name, DEFAULT_MODEL), name, args.scale
            )
            for path, name in zip(args.inputs, names, strict=True)
        ]
        # Before the build: a wrong scale is the likeliest cause of whatever follows.
        for region in regions:
            warning = units_warning(region.name, region.vertices)
            if warning:
                print(f"hapticut mesh: warning: {warning}", file=sys.stderr)
        scene = build(regions, settings=settings, progress=progress)
    except BuildError as error:
        if progress is not None and progress.tty:
            sys.stderr.write("\n")
        print(f"hapticut mesh: {error}", file=sys.stderr)
        return 1
    for line in accuracy_lines(scene.metadata["build_report"]):
        print(f"hapticut mesh: {line}", file=sys.stderr)
    save_scene(scene, args.output)
    if args.vtu:
        write_vtu(args.vtu, scene)
    print(f"{args.output}:")
    print(format_summary(scene_summary(scene)))
    return 0
