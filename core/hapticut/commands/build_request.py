"""``hapticut build-request REQUEST.json --out DIR``: the add-on's build (docs/addon.md).

Reads a build request (hapticut.build_request), checks its regions, builds the scene with
hapticut.scenebuild and writes into DIR: the scene file, ``preview.npz``
(hapticut.preview) and ``report.json``. DIR appears whole or not at all: everything is
written into a temporary directory beside it, renamed to DIR at the end (an existing DIR is
replaced). ``--progress jsonl`` prints one JSON object per line on stdout:
``{"event": "progress", "stage": "repair", "fraction": 0.03, "message": "..."}`` (the
builder's step; when it meshes again also ``"meshing": 2, "meshings": 3``), then
``{"event": "done", ...}`` or ``{"event": "error", "object": NAME, "problem": TEXT}``
(also the last line on stderr). ``--check`` runs the build's checks without meshing
(hapticut.scenebuild.check_layout: each region open, self-intersecting or without volume;
regions crossing, touching or lying on one another), with the same progress lines, then
``{"event": "problem", "object": NAME, "problem": TEXT}`` for each problem and
``{"event": "checked", "problems": N}``.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import shutil
import sys
import tempfile
import time

NAME = "build-request"
HELP = "Build a scene from an add-on's build request (progress as JSON lines, preview, report)."
# At most this many progress lines a second (the add-on polls a few times a second).
PROGRESS_LINES_PER_S = 20


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description = __doc__
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.add_argument("request", help="the build request (.json) beside its region meshes")
    parser.add_argument("--out", help="the output directory (replaced when it exists)")
    parser.add_argument("--progress", choices=("jsonl", "none"), default="jsonl")
    parser.add_argument("--check", action="store_true", help="only check the regions")


class JsonLines:
    """Events as JSON lines on a stream. Progress names the builder's step and, when it
    meshes again, which meshing; a line whose step or message is new is always written (it
    says what the next long stretch is), repeats at most PROGRESS_LINES_PER_S."""

    def __init__(self, stream, enabled: bool = True) -> None:
        self.stream = stream
        self.enabled = enabled
        self.stage = "starting"
        self.meshing, self.meshings = 1, 1
        self.last_line = ("", "")
        self.last_time = 0.0

    def emit(self, event: str, **values) -> None:
        if self.enabled or event != "progress":
            self.stream.write(json.dumps({"event": event, **values}) + "\n")
            self.stream.flush()

    def on_step(self, step: str, meshing: int, meshings: int) -> None:
        """The builder begins a step (hapticut.scenebuild.ProgressCallback)."""
        self.stage, self.meshing, self.meshings = step, meshing, meshings

    def __call__(self, fraction: float, message: str) -> bool:
        now = time.monotonic()
        line = (self.stage, message)
        if line != self.last_line or now - self.last_time >= 1.0 / PROGRESS_LINES_PER_S:
            again = {"meshing": self.meshing, "meshings": self.meshings} if self.meshing > 1 else {}
            self.emit(
                "progress", stage=self.stage, fraction=round(fraction, 4), message=message, **again
            )
            self.last_line, self.last_time = line, now
        return True


def _fail(events: JsonLines, name: str, problem: str, code: int = 1) -> int:
    events.emit("error", object=name, problem=problem)
    print(f"hapticut build-request: {f'{name}: ' if name else ''}{problem}", file=sys.stderr)
    return code


def run(args: argparse.Namespace) -> int:
    from hapticut.build_request import InputCheck, RequestError, read_request
    from hapticut.scenebuild import forked

    from .mesh import _terminate_as_exit

    forked.allow()  # This process runs nothing but the build (forked.py).
    events = JsonLines(sys.stdout, args.progress == "jsonl")
    if not args.check and not args.out:
        return _fail(events, "", "--out DIR is required (or --check)", 2)
    try:
        request = read_request(args.request)
    except RequestError as error:
        return _fail(events, "", f"request {error}", 2)
    events.emit("progress", stage="validate", fraction=0.0, message="checking regions")
    with InputCheck(
        request.regions,
        lambda fraction, message: events.emit(
            "progress", stage="validate", fraction=0.0, message=message
        ),
        beside=args.check,  # A build waits for the check: nothing to do beside it.
    ) as check:
        if args.check:
            return _check(request, check, events)
        problems = check.problems()
    if not request.regions:
        problems.append(("", "no regions to build a scene from"))
    if problems:
        return _fail(events, *problems[0])
    with _terminate_as_exit():
        return _build(request, os.path.abspath(args.out), events)


def _check(request, check, events: JsonLines) -> int:
    """The regions' own problems; when there are none, the build's checks before meshing.
    These begin while the input check (InputCheck) may still look for crossing faces, and
    stop once it found some: its problems come first."""
    from hapticut.scenebuild import BuildCancelled, BuildError, check_layout

    layout: list[tuple[str, str]] = []
    if request.regions and not check.failed():
        try:
            check_layout(request.regions, request.settings, progress=_Until(events, check.failed))
        except BuildError as error:
            layout = [(error.region, error.problem)]
        except BuildCancelled:
            pass
    problems = check.problems() or layout
    if not request.regions:
        problems.append(("", "no regions to build a scene from"))
    for name, problem in problems:
        events.emit("problem", object=name, problem=problem)
    events.emit("checked", problems=len(problems))
    return 1 if problems else 0


class _Until:
    """The events as a progress callback that cancels once stop() is true."""

    def __init__(self, events: JsonLines, stop) -> None:
        self.events, self.stop = events, stop
        self.on_step = events.on_step

    def __call__(self, fraction: float, message: str) -> bool:
        return self.events(fraction, message) and not self.stop()


def _build(request, out: str, events: JsonLines) -> int:
    from dataclasses import replace

    from hapticut.preview import scene_report, write_preview
    from hapticut.scenebuild import BuildError, build
    from hapticut.scenefile import save_scene

    start = time.perf_counter()
    settings = replace(request.settings, in_subprocess=True)
    try:
        scene = build(request.regions, request.blades, settings, progress=events)
    except BuildError as error:
        return _fail(events, error.region, error.problem)
    if request.blade_devices:
        scene.metadata["blade_devices"] = dict(request.blade_devices)
    parent = os.path.dirname(out) or "."
    os.makedirs(parent, exist_ok=True)
    staging = tempfile.mkdtemp(prefix=f".{os.path.basename(out)}.tmp-", dir=parent)
    try:
        events.emit("progress", stage="write", fraction=1.0, message="writing the scene")
        save_scene(scene, os.path.join(staging, request.scene_file))
        write_preview(scene, os.path.join(staging, "preview.npz"))
        with open(os.path.join(staging, "report.json"), "w", encoding="utf-8") as file:
            json.dump(scene_report(scene), file, indent=1)
        if os.path.isdir(out):
            shutil.rmtree(out)
        os.replace(staging, out)
    except BaseException:
        with contextlib.suppress(OSError):
            shutil.rmtree(staging)
        raise
    seconds = round(time.perf_counter() - start, 3)
    events.emit(
        "done", out=out, scene=request.scene_file, tets=int(len(scene.tets)), seconds=seconds
    )
    return 0
