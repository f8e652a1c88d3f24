"""``hapticut cut-surface RECORDING PREVIEW --out CUTS.npz``: every blade's cut surface.

The add-on's bake runs this as a child (hapticut.cut_surface describes the computation and
the file), so Blender's UI never waits on it.
"""

from __future__ import annotations

import argparse
import sys

NAME = "cut-surface"
HELP = "Write the cut surface of each blade of a servo recording as .npz (numpy alone reads it)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("recording", help="a servo recording (.hapticut-rec)")
    parser.add_argument("preview", help="the scene's preview (.npz, from hapticut preview)")
    parser.add_argument("--out", required=True, help="the cut surfaces (.npz)")
    parser.add_argument("--fps", type=float, required=True, help="the scene's frames a second")
    parser.add_argument("--frame-start", type=int, default=1, help="the stroke's first frame")
    parser.add_argument(
        "--substeps", type=int, default=2, help="rows of the surface per frame (default 2)"
    )
    parser.add_argument(
        "--ticks", type=int, default=None, help="only the first TICKS records (default all)"
    )


def run(args: argparse.Namespace) -> int:
    from hapticut.cut_surface import preview_tets, recording_cut_surfaces, write_cut_surfaces
    from hapticut.recording import read_recording

    problem = _invalid(args)
    if problem:
        print(f"hapticut cut-surface: {problem}", file=sys.stderr)
        return 2
    try:
        recording = read_recording(args.recording)
    except (OSError, ValueError) as error:
        print(f"hapticut cut-surface: {args.recording}: {error}", file=sys.stderr)
        return 1
    try:
        tets = preview_tets(args.preview)
    except (OSError, KeyError, ValueError) as error:
        print(f"hapticut cut-surface: {args.preview}: {error}", file=sys.stderr)
        return 1
    ticks = len(recording) if args.ticks is None else min(args.ticks, len(recording))
    surfaces = recording_cut_surfaces(
        recording, tets, args.fps, args.frame_start, args.substeps, ticks
    )
    write_cut_surfaces(args.out, surfaces)
    faces = ", ".join(f"{name} {len(s.faces)}" for name, s in surfaces.items())
    print(f"{args.out}: cut faces {faces or 'none (no blade)'}")
    return 0


def _invalid(args: argparse.Namespace) -> str:
    """What is wrong with the numbers given ('' when nothing)."""
    if not args.fps > 0 or args.fps == float("inf"):
        return f"--fps must be a positive number of frames a second, not {args.fps}"
    if args.substeps < 1:
        return f"--substeps must be at least 1, not {args.substeps}"
    if args.ticks is not None and args.ticks < 2:
        return f"--ticks must be at least 2 (a surface joins rows of records), not {args.ticks}"
    return ""
