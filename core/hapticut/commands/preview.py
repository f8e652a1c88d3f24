"""``hapticut preview SCENE --out PREVIEW.npz``: a scene's region surfaces for Blender.

The add-on imports scenes through this (a MessagePack scene needs compiled code to read,
a preview only numpy): hapticut.preview describes the arrays.
"""

from __future__ import annotations

import argparse
import sys

NAME = "preview"
HELP = "Write a scene's material-region surfaces and report as .npz (numpy alone reads it)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", help="a .hapticut.json or .hapticut.msgpack file")
    parser.add_argument("--out", required=True, help="the preview file (.npz)")


def run(args: argparse.Namespace) -> int:
    from hapticut.preview import write_preview
    from hapticut.scenefile import SceneError, load_scene

    try:
        scene = load_scene(args.scene)
    except (OSError, SceneError) as error:
        print(f"hapticut preview: {args.scene}: {error}", file=sys.stderr)
        return 1
    write_preview(scene, args.out)
    print(f"{args.out}: {len(scene.materials) - 1} material regions")
    return 0
