"""The ``hapticut`` command: one sub-command per module in ``hapticut.commands``."""

from __future__ import annotations

import argparse
import importlib
import sys

from hapticut import __version__

# Each module defines NAME, HELP, add_arguments(parser) and run(args) -> int.
COMMAND_MODULES = (
    "bench",
    "mesh",
    "info",
    "materials",
    "build_request",
    "preview",
    "cut_surface",
    "convert",
    "serve",
    "paths",
    "demo_stroke",
)


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser of every command, or of ``command`` alone when it names one: a run imports
    only its own command's module (the add-on's children start sooner)."""
    parser = argparse.ArgumentParser(prog="hapticut", description=__doc__)
    parser.add_argument("--version", action="version", version=f"hapticut {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    module_name = (command or "").replace("-", "_")
    for name in (module_name,) if module_name in COMMAND_MODULES else COMMAND_MODULES:
        try:
            module = importlib.import_module(f"hapticut.commands.{name}")
        except ModuleNotFoundError as error:
            if error.name != f"hapticut.commands.{name}":
                raise
            continue
        command = sub.add_parser(module.NAME, help=module.HELP, description=module.HELP)
        module.add_arguments(command)
        command.set_defaults(run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = build_parser(argv[0] if argv else None).parse_args(argv)
    try:
        return int(args.run(args) or 0)
    except KeyboardInterrupt:
        print("hapticut: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
