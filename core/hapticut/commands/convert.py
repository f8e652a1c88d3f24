"""``hapticut convert SCENE OUT``: a scene file re-encoded (JSON <-> MessagePack), validated;
with ``--locality-order``, its mesh renumbered as ``hapticut build`` stores it."""

from __future__ import annotations

import argparse
import sys

NAME = "convert"
HELP = "Read a scene file (validating it) and write it as .hapticut.json or .hapticut.msgpack."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", help="a .hapticut.json or .hapticut.msgpack file")
    parser.add_argument("output", help="the file to write (.json or .msgpack)")
    parser.add_argument(
        "--locality-order",
        action="store_true",
        help="also renumber the tets along a Hilbert curve and the vertices by first use, "
        "as `hapticut build` stores them (the engine walks them faster); "
        "geometry and materials are unchanged",
    )


def run(args: argparse.Namespace) -> int:
    from hapticut.scenefile import SceneError, load_scene, save_scene

    if not args.output.endswith((".json", ".msgpack")):
        print("hapticut convert: OUT must end in .json or .msgpack", file=sys.stderr)
        return 2
    try:
        scene = load_scene(args.scene)
        if args.locality_order:
            from hapticut.scenebuild.locality import scene_in_locality_order

            scene = scene_in_locality_order(scene)
        save_scene(scene, args.output)
    except (OSError, SceneError) as error:
        print(f"hapticut convert: {args.scene}: {error}", file=sys.stderr)
        return 1
    print(args.output)
    return 0
