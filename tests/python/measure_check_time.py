"""Prints how long Check Scene's child (``hapticut build-request --check``) takes on a scan,
and how its progress moves: the scan is pymeshlab's sample bunny (56,172 faces, closed)
scaled to 100 mm across, the request as the add-on writes it (one region, a knife, default
settings: the accuracy 1% of the size). A measurement, not a test: nothing is asserted.

    python tests/python/measure_check_time.py [--runs 5] [--mesh FILE] [--size-mm 100]
        [--core DIR ...]

Each run starts the child as the add-on does (stdout to a file read as it grows) and prints
its wall time, its CPU time (user + system: less changed by other processes on a loaded
machine; on Linux also the CPU time the rest of the machine used meanwhile, "others": near 0
at rest), the face count kept, and its progress records: how many, the longest wait
between two of them (or the start and the first, or the last and the end) and the largest
step of the fraction. A first run of each toolkit, which compiles its modules, is not
counted. The toolkit is this checkout's (``core`` first on PYTHONPATH); with several --core
folders (another checkout's ``core``) their runs alternate, so that a machine's load weighs
on each alike.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

CORE = Path(__file__).resolve().parents[2] / "core"
CHILD = "import sys; from hapticut.cli import main; sys.exit(main())"


def sample_mesh() -> Path:
    import pymeshlab

    return Path(pymeshlab.__file__).parent / "tests" / "sample_meshes" / "bunny.obj"


def write_request(folder: Path, mesh: Path, size_mm: float) -> Path:
    import pymeshlab

    meshes = pymeshlab.MeshSet()
    meshes.load_new_mesh(str(mesh))
    vertices = meshes.current_mesh().vertex_matrix().astype(np.float64)
    faces = meshes.current_mesh().face_matrix().astype(np.int32)
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    vertices = (vertices - (low + high) / 2) * (size_mm / float((high - low).max()))
    np.savez(folder / "scan.npz", vertices=vertices, faces=faces)
    request = {
        "format": "hapticut.build-request",
        "version": 1,
        "regions": [{"name": "Scan", "mesh": "scan.npz",
                     "material": {"name": "bone", "model": "rigid"}}],
        "blades": [{"name": "Knife", "start_mm": [-60.0, 0.0, 0.0], "end_mm": [-60.0, 0.0, 30.0]}],
        "settings": {"enclosure": "box", "coarsen": False},
        "scene_file": "scene.hapticut.msgpack",
    }  # fmt: skip
    path = folder / "request.json"
    path.write_text(json.dumps(request, indent=1))
    return path


def run_check(request: Path, folder: Path, core: Path) -> dict:
    """One child run: wall and CPU seconds, the progress records (seconds, fraction) as read
    while it ran (every 10 ms), the faces kept and its last line. Its modules are compiled
    once, into a cache in ``folder``, as an installed toolkit's are."""
    path = os.pathsep.join(p for p in (str(core), os.environ.get("PYTHONPATH", "")) if p)
    env = dict(os.environ, PYTHONPATH=path, PYTHONUNBUFFERED="1")
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env["PYTHONPYCACHEPREFIX"] = str(folder / "pycache")
    log = folder / "progress.jsonl"
    records: list[tuple[float, float]] = []
    busy = machine_cpu()
    with open(log, "wb") as stdout:
        started = time.perf_counter()
        process = subprocess.Popen(
            [sys.executable, "-c", CHILD, "build-request", str(request), "--check",
             "--progress", "jsonl"],
            stdout=stdout, stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL, env=env,
        )  # fmt: skip
        offset, last, kept, cpu = 0, "", "", None
        while True:
            waited = os.wait4(process.pid, os.WNOHANG)
            if waited[0]:
                cpu = waited[2].ru_utime + waited[2].ru_stime
                process.returncode = os.waitstatus_to_exitcode(waited[1])
            done = cpu is not None
            elapsed = time.perf_counter() - started
            with open(log, "rb") as file:
                file.seek(offset)
                chunk = file.read()
            whole = chunk[: chunk.rfind(b"\n") + 1]
            offset += len(whole)
            for line in whole.decode().splitlines():
                event = json.loads(line)
                last = line
                if event.get("event") == "progress":
                    records.append((elapsed, float(event["fraction"])))
                    if event["message"].startswith("simplified"):
                        kept = event["message"]
            if done:
                break
            time.sleep(0.01)
    seconds = time.perf_counter() - started
    others = None if busy is None else machine_cpu() - busy - cpu
    return {"seconds": seconds, "cpu": cpu, "records": records, "last": last, "kept": kept,
            "others": others}  # fmt: skip


def machine_cpu() -> float | None:
    """CPU seconds the whole machine has been busy (Linux's /proc/stat; None elsewhere)."""
    try:
        with open("/proc/stat") as file:
            ticks = [int(word) for word in file.readline().split()[1:]]
    except OSError:
        return None
    return (sum(ticks) - ticks[3] - ticks[4]) / os.sysconf("SC_CLK_TCK")  # Not idle or iowait.


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--mesh", type=Path, default=None)
    parser.add_argument("--size-mm", type=float, default=100.0)
    parser.add_argument("--core", type=Path, action="append", help="a toolkit's core folder")
    args = parser.parse_args(argv)
    cores = args.core or [CORE]
    with tempfile.TemporaryDirectory(prefix="hapticut-check-time-") as work:
        folder = Path(work)
        request = write_request(folder, args.mesh or sample_mesh(), args.size_mm)
        runs: dict[Path, list[dict]] = {core: [] for core in cores}
        for core in cores:  # Compiles its modules: not counted.
            run_check(request, folder, core)
        for i in range(args.runs):
            for core in cores:
                run = run_check(request, folder, core)
                runs[core].append(run)
                stamps = [0.0] + [t for t, _ in run["records"]] + [run["seconds"]]
                fractions = [0.0] + [f for _, f in run["records"]]
                others = "" if run["others"] is None else f", others {run['others']:.2f} s"
                print(
                    f"{core} run {i + 1}: {run['seconds']:.2f} s (CPU {run['cpu']:.2f} s{others}), "
                    f"{len(run['records'])} progress records, longest gap "
                    f"{max(np.diff(stamps)):.2f} s, largest step "
                    f"{max(np.diff(fractions), default=0.0):.2f}; {run['kept']}; {run['last']}"
                )
        for core, made in runs.items():
            wall = [run["seconds"] for run in made]
            cpu = [run["cpu"] for run in made]
            print(f"{core}: median of {len(made)}: {statistics.median(wall):.2f} s "
                  f"(min {min(wall):.2f}, max {max(wall):.2f}), "
                  f"CPU {statistics.median(cpu):.2f} s")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
