"""Write docs/benchmarks.md: page.md beside this file, filled in with the tables that
`hapticut bench` prints in this run.

    python tools/benchmarks/page.py --out docs/benchmarks.md            # the committed page
    python tools/benchmarks/page.py --quick --out /tmp/benchmarks.md    # the tests' short run

Each table is the command's own output, run as a child process, so the page shows what a
user's `hapticut bench ...` prints; the lines it prints beside its table go under it. Every
column of a table must be explained in its section of page.md (its name in backquotes): a
column added to a benchmark without its meaning stops the page, naming the column.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import re
import string
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

TEMPLATE = Path(__file__).with_name("page.md")
COMMAND = "python tools/benchmarks/page.py --out docs/benchmarks.md"
# Shown in a quick run's commands instead of its temporary directory.
SCENES_PLACEHOLDER = "DIR"
ROOT = Path(__file__).resolve().parents[2]
# An absolute path of the machine that ran the page: the page must carry none
# (tests/python/test_generated_pages.py checks every generated page).
MACHINE_PATH = re.compile(r"(?<![\w.~])/(?:root|home|tmp|usr|opt|var|work|srv|mnt)/\S*")


@dataclass(frozen=True)
class Benchmark:
    """One section of the page: its heading in page.md, and the `hapticut bench` arguments
    of the full run and of the quick one (`{scenes}`: a directory holding one small scene)."""

    key: str
    heading: str
    full: tuple[str, ...]
    quick: tuple[str, ...]


BENCHMARKS = (
    Benchmark(
        "transitions",
        "Transitions (the paper's Table 2)",
        ("transitions",),
        ("transitions", "--repeats", "2000", "--batches", "3", "--rounds", "1"),
    ),
    Benchmark(
        "blade",
        "Blade ticks",
        # Without the points-in-100-µs search: it asks for blades beyond Blade::kMaxPoints
        # (10000 points), which the engine refuses, and stops the benchmark.
        ("blade", "--no-max-points"),
        ("blade", "--no-max-points", "--rounds", "1", "--scenes", "{scenes}"),
    ),
    Benchmark(
        "servo",
        "The servo process",
        ("servo",),
        ("servo", "--duration", "0.3", "--rounds", "1", "--scenes", "{scenes}"),
    ),
)


def run_bench(args: list[str]) -> str:
    """What `hapticut bench ARGS` prints; raises RuntimeError with its error output."""
    command = [sys.executable, "-m", "hapticut.cli", "bench", *args]
    result = subprocess.run(command, capture_output=True, text=True, check=False)
    if result.returncode != 0:
        raise RuntimeError(
            f"hapticut bench {' '.join(args)} failed ({result.returncode}): {result.stderr.strip()}"
        )
    return result.stdout


def split_output(text: str) -> tuple[str, list[str]]:
    """A benchmark's printout as (its table, the other lines it printed). The first line,
    `machine: ...`, is left out: the page's header names the machine."""
    table, notes = [], []
    for line in text.splitlines():
        if line.startswith("|"):
            table.append(line)
        elif line.strip() and not line.startswith("machine:"):
            notes.append(line)
    if len(table) < 3:
        raise ValueError(f"no table with a row in the printout:\n{text}")
    return "\n".join(table), notes


def columns(table: str) -> list[str]:
    """The column names of a Markdown table (its first line)."""
    return [cell.strip() for cell in table.splitlines()[0].strip().strip("|").split("|")]


def section(text: str, heading: str) -> str:
    """The text of `## heading` up to the next `## ` heading."""
    match = re.search(rf"^## {re.escape(heading)}\n(.*?)(?=^## |\Z)", text, re.M | re.S)
    if match is None:
        raise ValueError(f"page.md has no section '## {heading}'")
    return match.group(1)


def unexplained(names: list[str], text: str) -> list[str]:
    """The names that `text` never mentions in backquotes."""
    return [name for name in names if f"`{name}`" not in text]


def without_machine_paths(line: str) -> str:
    """A printed line with the running machine's paths made neutral: the installed package's
    folder (site-packages/...) as its import path, the repository as `.`."""
    line = re.sub(r"/\S*/(?:site|dist)-packages/", "", line)
    line = line.replace(str(ROOT) + "/", "").replace(str(ROOT), ".")
    if MACHINE_PATH.search(line):
        raise ValueError(f"a machine path in a line for the page: {line}")
    return line


def notes_block(notes: list[str]) -> str:
    if not notes:
        return ""
    return "The command also printed:\n\n" + "\n".join("    " + n for n in notes) + "\n"


def machine() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return f"{line.split(':', 1)[1].strip()}, {platform.machine()}"
    except OSError:
        pass
    return platform.processor() or platform.machine()


def cores() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()


def load_average() -> str:
    return f"{os.getloadavg()[0]:.1f}" if hasattr(os, "getloadavg") else "unknown"


def build_kind() -> str:
    from hapticut import _core

    if _core.BUILT_NATIVE:
        return "for this CPU (HAPTICUT_NATIVE=ON, as the test command builds it)"
    return "portable (HAPTICUT_NATIVE=OFF, as for wheels)"


def smallest_example_scene() -> Path:
    """The smallest example scene file (MessagePack): the quick run's only scene."""
    from hapticut.bench import blade

    paths, found = blade.example_scenes()
    packed = [p for p in paths if p.name.endswith(".hapticut.msgpack")]
    if not packed:
        raise FileNotFoundError(found)
    return min(packed, key=lambda p: p.stat().st_size)


def write_page(out: Path, quick: bool) -> str:
    """Run every benchmark, fill page.md in and write it to `out`; returns the page."""
    template_text = TEMPLATE.read_text()
    started, load_start = time.monotonic(), load_average()
    values: dict[str, str] = {}
    with tempfile.TemporaryDirectory() as scenes:
        quick_note = ""
        if quick:
            scene = smallest_example_scene()
            (Path(scenes) / scene.name).symlink_to(scene)
            quick_note = (
                f"\n**A quick run** (`--quick`): fewer calls and one round a benchmark, one "
                f"scene ({SCENES_PLACEHOLDER} holds {scene.name}), no points-in-100-µs search. "
                "Its figures show the page's structure, not the engine's speed.\n"
            )
        for bench in BENCHMARKS:
            args = bench.quick if quick else bench.full
            table, notes = split_output(run_bench([a.replace("{scenes}", scenes) for a in args]))
            missing = unexplained(columns(table), section(template_text, bench.heading))
            if missing:
                raise ValueError(
                    f"page.md, '## {bench.heading}': column(s) {', '.join(missing)} printed by "
                    "the benchmark but not explained (name each in backquotes)"
                )
            shown = " ".join(a.replace("{scenes}", SCENES_PLACEHOLDER) for a in args)
            values[f"{bench.key}_command"] = f"hapticut bench {shown}"
            values[f"{bench.key}_table"] = table
            values[f"{bench.key}_notes"] = notes_block(
                [without_machine_paths(n.replace(scenes, SCENES_PLACEHOLDER)) for n in notes]
            )
    values.update(
        command=COMMAND,
        elapsed_s=f"{time.monotonic() - started:.0f}",
        date=datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        machine=machine(),
        cpus=str(cores()),
        load_start=load_start,
        load_end=load_average(),
        build_kind=build_kind(),
        quick_note=quick_note,
    )
    page = string.Template(template_text).substitute(values)
    out.write_text(page)
    return page


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True, help="the page to write")
    parser.add_argument(
        "--quick", action="store_true", help="the reduced run the tests use (seconds)"
    )
    args = parser.parse_args(argv)
    if not args.out.parent.is_dir():
        print(f"--out {args.out}: no directory {args.out.parent}", file=sys.stderr)
        return 2
    write_page(args.out, args.quick)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
