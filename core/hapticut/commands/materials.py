"""``hapticut materials [--json]``: the material models, their parameters and the presets.

Everything printed comes from the engine's one material table (core/src/material_table.cpp),
and which models a blade cuts from hapticut.cut_surface.
"""

from __future__ import annotations

import argparse
import json

NAME = "materials"
HELP = "List the material models with their parameters (unit, range, default) and the presets."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--json", action="store_true", help="print the table as JSON")


def range_text(parameter: dict) -> str:
    """'(0, 1000] mm' for an exclusive minimum, '[0, 60] s' for an inclusive one."""
    opening = "(" if parameter["minimum_exclusive"] else "["
    unit = f" {parameter['unit']}" if parameter["unit"] else ""
    return f"{opening}{parameter['minimum']:g}, {parameter['maximum']:g}]{unit}"


def format_table(table: dict) -> str:
    lines = ["Material models:"]
    for model in table["models"]:
        cut = ", cut by a blade" if model["cuttable"] else ""
        lines.append(f"  {model['name']:<10}{model['summary']}{cut}")
        for parameter in model["parameters"]:
            needed = "" if parameter["required"] else ", optional"
            lines.append(
                f"    {parameter['name']:<22}{range_text(parameter):<22}"
                f"default {parameter['default']:g}{needed}: {parameter['summary']}"
            )
    lines.append("Presets:")
    for preset in table["presets"]:
        values = ", ".join(f"{key}={value:g}" for key, value in preset["parameters"].items())
        suffix = f" ({values})" if values else ""
        lines.append(f"  {preset['name']:<13}{preset['label']:<14}{preset['model']}{suffix}")
    return "\n".join(lines)


def material_table() -> dict:
    """The engine's table, each model marked ``cuttable``: whether a blade cuts it, so that
    its material takes a cut variant (the add-on offers one only then)."""
    from hapticut import _core
    from hapticut.cut_surface import CUTTABLE_MODELS

    table = _core.material_table()
    for model in table["models"]:
        model["cuttable"] = model["name"] in CUTTABLE_MODELS
    return table


def run(args: argparse.Namespace) -> int:
    table = material_table()
    print(json.dumps(table) if args.json else format_table(table))
    return 0
