"""fTetWild through pytetwild's compiled wrapper, without pytetwild's Python package.

pytetwild 0.4 imports pyvista (and so vtk, about 565 MB) when its package is imported, although
its metadata calls pyvista optional; the Blender extension bundles our wheels and cannot carry
that. Its compiled module needs only numpy, so it is loaded here from the installed
distribution's files (docs/decisions.md, "pytetwild version").

fTetWild holds the GIL for the whole run and cannot be interrupted, so a run that must stay
cancellable (a progress bar, Ctrl-C, the add-on's UI thread) goes to a child process that is
killed on cancel. This file is also that child's program: it imports nothing from hapticut.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np

DISTRIBUTION = "pytetwild"
_WRAPPER_NAME = "PyfTetWildWrapper"
# fTetWild writes this into the current directory; every run happens in a temporary directory.
_TRACKED_SURFACE_FILE = "__tracked_surface.stl"
_POLL_INTERVAL_S = 0.05

_wrapper = None


@dataclass(frozen=True)
class TetWildParams:
    """The fTetWild settings the builder uses (absolute lengths in mm)."""

    edge_length_mm: float  # Target edge length where no sizing field covers.
    envelope_mm: float  # The output surface stays within this distance of the input.
    optimize: bool = True  # Required for a sizing field to act.
    simplify: bool = True  # Let fTetWild simplify the input surface inside the envelope.
    coarsen: bool = False  # Coarsen the output as far as quality allows.
    stop_energy: float = 10.0  # Optimization stops at this conformal AMIPS energy.
    max_opt_iterations: int = 80
    threads: int = 0  # 0: all cores.
    # fTetWild's own envelope, relative to the input's bounding-box diagonal; when set it is
    # passed as it is and envelope_mm is not used (the evaluation's meshes are made so).
    envelope_relative: float | None = None


def version() -> str:
    """The installed pytetwild version ("" when it is missing)."""
    # importlib.metadata is imported where it is used: its import is a noticeable share of
    # the start of Check Scene's child, which meshes nothing.
    import importlib.metadata

    try:
        return importlib.metadata.version(DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError:
        return ""


def load_wrapper():
    """pytetwild's compiled module, loaded from its file (cached)."""
    global _wrapper
    if _wrapper is not None:
        return _wrapper
    import importlib.metadata
    import importlib.util

    try:
        dist = importlib.metadata.distribution(DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError:
        raise ImportError(
            "scene building needs pytetwild>=0.4,<0.5: pip install 'hapticut[build]'"
        ) from None
    library = next(
        (
            f
            for f in dist.files or ()
            if _WRAPPER_NAME in str(f) and str(f).endswith((".so", ".pyd"))
        ),
        None,
    )
    if library is None:
        raise ImportError(f"pytetwild {dist.version} has no compiled {_WRAPPER_NAME} module")
    spec = importlib.util.spec_from_file_location(
        f"{DISTRIBUTION}.{_WRAPPER_NAME}", dist.locate_file(library)
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    _wrapper = module
    return module


def _empty_sizing():
    return (np.zeros((0, 3)), np.zeros((0, 4), np.int32), np.zeros(0))


class RunProgress:
    """How far a fTetWild run is, read from the lines it prints as it goes: its stages, each
    optimization pass's sub-steps with the worst tet's energy, the coarsening's rounds.

    ``fraction`` is the share of the run done. Each stage starts at a mark (STAGES: the
    shares the stages take of default builds of scans, which differ from scan to scan) and
    moves towards the next as it prints (a line is work done; how many a stage prints is not
    known, so the share approaches the next mark without reaching it) or, while optimizing,
    as the worst energy falls towards the stop energy on a log scale, whichever is further.
    Between lines it creeps a little, so that the bar moves through a quiet stage. It never
    goes back, and stays below 1 until the run ends.
    """

    # (the line that starts the stage, its name, the share of the run done when it starts,
    # the lines that take the stage about two thirds of the way to the next mark)
    STAGES = (
        ("", "preparing the surfaces", 0.0, 20),
        ("Tetrahedralization performed.", "inserting the surfaces", 0.04, 10),
        ("initializing...", "optimizing", 0.12, 200),
        ("//////////////// postprocessing", "finishing", 0.65, 300),
        ("Tetrahedralization completed.", "filtering", 0.97, 10),
    )
    # Within a stage at most this share of the way to the next mark is given.
    WITHIN = 0.95
    # Between lines the fraction creeps towards the stage's limit: a quarter of the way in
    # this time, never more than half (a line read then moves it on).
    CREEP_S = 5.0

    def __init__(self, stop_energy: float, max_passes: int) -> None:
        self.stop_energy = stop_energy
        self.max_passes = max(max_passes, 1)
        self.number = 0  # Which of STAGES runs.
        self.lines = 0  # Lines read in this stage.
        self.passes = 0
        self.first_energy: float | None = None
        self.energy_share = 0.0
        self.fraction = 0.0  # At the last line read.
        self.shown = 0.0  # The most given (at).
        self._partial = ""

    @property
    def stage(self) -> str:
        return self.STAGES[self.number][1]

    def feed(self, text: str) -> None:
        """Read what the run printed since the last call (lines may arrive in pieces)."""
        lines = (self._partial + text).split("\n")
        self._partial = lines.pop()
        for line in lines:
            self._read(line.strip())
        start, end = self._span()
        scale = self.STAGES[self.number][3]
        share = max(1 - math.exp(-self.lines / scale), self.energy_share)
        self.fraction = max(self.fraction, start + (end - start) * self.WITHIN * min(share, 1.0))

    def _span(self) -> tuple[float, float]:
        start = self.STAGES[self.number][2]
        end = self.STAGES[self.number + 1][2] if self.number + 1 < len(self.STAGES) else 1.0
        return start, end

    def _read(self, line: str) -> None:
        for number in range(self.number + 1, len(self.STAGES)):
            if line.startswith(self.STAGES[number][0]):
                self.number, self.lines, self.energy_share = number, 0, 0.0
                self.fraction = max(self.fraction, self.STAGES[number][2])
                return
        self.lines += 1
        if self.stage != "optimizing":
            return
        if line.startswith("//////////////// pass "):
            self.passes += 1
            self.energy_share = max(self.energy_share, self.passes / self.max_passes)
        elif line.startswith("max_energy = "):
            try:
                energy = float(line.split("=", 1)[1])
            except ValueError:
                return
            if self.first_energy is None:
                self.first_energy = energy
            first = self.first_energy
            if first > self.stop_energy and energy > 0:
                fallen = math.log(first / max(energy, self.stop_energy))
                self.energy_share = max(
                    self.energy_share, fallen / math.log(first / self.stop_energy)
                )

    def at(self, since_line_s: float) -> float:
        """The fraction done ``since_line_s`` after the last line read (never less than the
        last one given)."""
        start, end = self._span()
        limit = start + (end - start) * self.WITHIN
        creep = 0.5 * since_line_s / (since_line_s + self.CREEP_S)
        self.shown = max(self.shown, self.fraction + max(limit - self.fraction, 0) * creep)
        return self.shown


def _run_in_process(
    vertices, faces, params: TetWildParams, sizing, scratch: str | None = None, quiet=True
):
    """fTetWild in this process, inside a scratch directory (it writes a file into cwd):
    ``scratch``, or a temporary directory made and removed here. Not quiet, it prints its
    stages on stdout (what RunProgress reads)."""
    if scratch is None:
        with tempfile.TemporaryDirectory(prefix="hapticut-tetwild-") as scratch:
            return _run_in_process(vertices, faces, params, sizing, scratch, quiet)
    wrapper = load_wrapper()
    bg_vertices, bg_tets, bg_values = sizing if sizing is not None else _empty_sizing()
    if params.envelope_relative is not None:
        epsilon = float(params.envelope_relative)
    else:
        diagonal = float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0)))
        epsilon = float(params.envelope_mm) / diagonal  # fTetWild's epsilon is relative.
    previous = os.getcwd()
    os.chdir(scratch)
    try:
        out_vertices, out_tets = wrapper.tetrahedralize_mesh(
            np.ascontiguousarray(vertices, dtype=np.float64),
            np.ascontiguousarray(faces, dtype=np.uint32),
            params.optimize,
            not params.simplify,
            0.05,  # Relative edge length; unused, edge_length_abs wins.
            float(params.edge_length_mm),
            epsilon,
            float(params.stop_energy),
            params.coarsen,
            int(params.threads),
            int(params.max_opt_iterations),
            6,  # Log level: minimal (its stages still print unless quiet).
            bool(quiet),
            False,  # fTetWild's own tet ordering; the scene reader orients tets.
            False,  # Filtering on: only the inside of the outer surface (the enclosure).
            np.ascontiguousarray(bg_vertices, dtype=np.float64),
            np.ascontiguousarray(bg_tets, dtype=np.int32),
            np.ascontiguousarray(bg_values, dtype=np.float64),
        )
    finally:
        os.chdir(previous)
    return np.asarray(out_vertices, dtype=np.float64), np.asarray(out_tets, dtype=np.int32)


def tetrahedralize(
    vertices: np.ndarray,
    faces: np.ndarray,
    params: TetWildParams,
    sizing: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    *,
    poll: Callable[[float], None] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Tets filling the closed surfaces ``faces`` (the enclosure outermost), conforming to all.

    vertices: (n, 3) float, faces: (f, 3) int triangles; sizing: (background vertices (b, 3),
    background tets (c, 4), target edge length per background vertex (b,)) or None.
    Returns (vertices (n', 3) float64, tets (m, 4) int32).
    With ``poll``, the run happens in a child process and poll(elapsed_s, fraction, stage) is
    called about every 50 ms, with the share of the run done and the stage it is in
    (RunProgress); an exception it raises (a cancel) kills the child and propagates.
    """
    vertices = np.ascontiguousarray(vertices, dtype=np.float64)
    faces = np.ascontiguousarray(faces, dtype=np.uint32)
    if poll is None:
        return _run_in_process(vertices, faces, params, sizing)
    return _run_in_child(vertices, faces, params, sizing, poll)


def _run_in_child(vertices, faces, params, sizing, poll):
    bg_vertices, bg_tets, bg_values = sizing if sizing is not None else _empty_sizing()
    with tempfile.TemporaryDirectory(prefix="hapticut-tetwild-") as scratch:
        request = os.path.join(scratch, "request.npz")
        result = os.path.join(scratch, "result.npz")
        log = os.path.join(scratch, "child.log")
        np.savez(
            request,
            vertices=vertices,
            faces=faces,
            bg_vertices=bg_vertices,
            bg_tets=bg_tets,
            bg_values=bg_values,
            params=np.array(json.dumps(asdict(params))),
        )
        start = time.perf_counter()
        progress = RunProgress(params.stop_energy, params.max_opt_iterations)
        with open(log, "wb") as log_file, open(log, "rb") as printed:
            child = subprocess.Popen(
                [sys.executable, os.path.abspath(__file__), request, result],
                cwd=scratch,
                stdin=subprocess.DEVNULL,
                stdout=log_file,
                stderr=subprocess.STDOUT,
            )
            last_line = start
            try:
                while child.poll() is None:
                    now = time.perf_counter()
                    text = printed.read()
                    if text:
                        progress.feed(text.decode("utf-8", "replace"))
                        last_line = now
                    poll(now - start, progress.at(now - last_line), progress.stage)
                    with contextlib.suppress(subprocess.TimeoutExpired):
                        child.wait(_POLL_INTERVAL_S)
            finally:
                if child.poll() is None:
                    child.kill()
                    child.wait()
        if child.returncode != 0 or not os.path.exists(result):
            with open(log, "rb") as log_file:
                tail = log_file.read()[-2000:].decode("utf-8", "replace").strip()
            raise RuntimeError(f"fTetWild failed (exit code {child.returncode}): {tail}")
        with np.load(result) as data:
            return data["vertices"].astype(np.float64), data["tets"].astype(np.int32)


def _die_with_parent() -> None:
    """Linux: have the kernel kill this child when the parent dies (best effort)."""
    if not sys.platform.startswith("linux"):
        return
    with contextlib.suppress(OSError, AttributeError):
        import ctypes
        import signal

        pr_set_pdeathsig = 1
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(pr_set_pdeathsig, signal.SIGKILL)


def _child_main(request: str, result: str) -> int:
    _die_with_parent()
    with np.load(request) as data:
        params = TetWildParams(**json.loads(str(data["params"])))
        sizing = (data["bg_vertices"], data["bg_tets"], data["bg_values"])
        # The parent made this directory the child's cwd and removes it, even after a kill.
        out_vertices, out_tets = _run_in_process(
            data["vertices"], data["faces"], params, sizing, os.getcwd(), quiet=False
        )
    partial = result + ".partial.npz"
    np.savez(partial, vertices=out_vertices, tets=out_tets)
    os.replace(partial, result)
    return 0


if __name__ == "__main__":
    sys.exit(_child_main(sys.argv[1], sys.argv[2]))
