"""``hapticut serve SCENE --device ...``: run hapticut-servo, the real-time process.

Every argument after SCENE goes to the servo as it is (``hapticut serve --help-servo``
lists them); the servo's exit code is this command's.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys

NAME = "serve"
HELP = "Run hapticut-servo on a scene file (devices, safety, stream, recording)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", nargs="?", help="scene file (.hapticut.json or .hapticut.msgpack)")
    parser.add_argument(
        "servo_args",
        nargs=argparse.REMAINDER,
        help="options for hapticut-servo, e.g. --device scalpel=sim --record run.rec",
    )
    parser.add_argument(
        "--help-servo", action="store_true", help="print hapticut-servo's own --help"
    )


def run(args: argparse.Namespace) -> int:
    from hapticut import servo_path

    try:
        executable = servo_path()
    except FileNotFoundError as error:
        print(f"hapticut serve: {error}", file=sys.stderr)
        return 1
    if args.help_servo:
        return subprocess.call([executable, "--help"])
    command = [executable] + ([os.fspath(args.scene)] if args.scene else []) + args.servo_args
    process = subprocess.Popen(command)
    try:
        return process.wait()
    except KeyboardInterrupt:
        # The servo got the SIGINT too: it ramps the force down and closes its recording.
        return process.wait()
