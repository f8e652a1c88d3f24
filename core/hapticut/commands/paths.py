"""``hapticut paths --json``: where this toolkit lives, for the Blender add-on.

The add-on (pure Python, another interpreter) loads the toolkit's numpy-only modules
(``servo_client``, ``recording``, ``servo_layout``, ``cut_surface`` with ``cut_clip``) from
``package`` and starts the servo at ``servo``: one source for the client, and always the
client of the installed servo (docs/addon.md).
"""

from __future__ import annotations

import argparse
import json
import os

import hapticut

NAME = "paths"
HELP = "Print where the package and the servo are (for the Blender add-on)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--json", action="store_true", help="print them as JSON")


def paths() -> dict:
    try:
        servo, servo_error = hapticut.servo_path(), ""
    except FileNotFoundError as error:
        servo, servo_error = "", str(error)
    return {
        "version": hapticut.__version__,
        "package": os.path.dirname(os.path.abspath(hapticut.__file__)),
        "servo": servo,
        "servo_error": servo_error,
    }


def run(args: argparse.Namespace) -> int:
    found = paths()
    if args.json:
        print(json.dumps(found))
    else:
        for key, value in found.items():
            print(f"{key}: {value}")
    return 0
