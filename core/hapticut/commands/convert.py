"""``hapticut convert SCENE OUT``: a scene file re-encoded (JSON <-> MessagePack), validated."""

from __future__ import annotations

import argparse
import sys

NAME = "convert"
HELP = "Read a scene file (validating it) and write it as .hapticut.json or .hapticut.msgpack."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", help="a .hapticut.json or .hapticut.msgpack file")
    parser.add_argument("output", help="the file to write (.json or .msgpack)")


def run(args: argparse.Namespace) -> int:
    from hapticut.scenefile import SceneError, load_scene, save_scene

    if not args.output.endswith((".json", ".msgpack")):
        print("hapticut convert: OUT must end in .json or .msgpack", file=sys.stderr)
        return 2
    try:
        save_scene(load_scene(args.scene), args.output)
    except (OSError, SceneError) as error:
        print(f"hapticut convert: {args.scene}: {error}", file=sys.stderr)
        return 1
    print(args.output)
    return 0
