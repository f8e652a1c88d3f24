"""The toolkit's material table (``hapticut materials --json``): read once, kept, and the
lookups the panels and the exchange make in it. No bpy here.
"""

from __future__ import annotations

from ..background import steps
from .runner import ToolkitError, json_steps

_material_table: dict | None = None


def material_table_steps(executable: str, refresh: bool = False) -> steps.Steps[dict]:
    """``hapticut materials --json``, run once and kept (refresh=True runs it again)."""
    global _material_table
    if _material_table is None or refresh:
        table = yield from json_steps(executable, "materials")
        if table.get("version") != 1 or "presets" not in table or "models" not in table:
            raise ToolkitError("hapticut materials --json: not a version 1 material table")
        _material_table = table
    return _material_table


def material_table(executable: str, refresh: bool = False) -> dict:
    """material_table_steps in one call."""
    return steps.run_to_end(material_table_steps(executable, refresh))


def cached_material_table() -> dict | None:
    """The table if it was read already (for drawing: never runs a process)."""
    return _material_table


def forget_material_table() -> None:
    global _material_table
    _material_table = None


def preset(table: dict, name: str) -> dict | None:
    return next((p for p in table["presets"] if p["name"] == name), None)


def model(table: dict, name: str) -> dict | None:
    return next((m for m in table["models"] if m["name"] == name), None)


def cuttable(model: dict | None) -> bool:
    """A blade cuts this model's materials, so they take a cut variant (the table's
    ``cuttable``; a table without it offers none)."""
    return bool(model and model.get("cuttable"))


def in_range(parameter: dict, value: float) -> bool:
    """Within the table's range (its minimum exclusive when it says so)."""
    low, high = parameter["minimum"], parameter["maximum"]
    above = value > low if parameter.get("minimum_exclusive") else value >= low
    return above and value <= high


def range_text(parameter: dict) -> str:
    """'(0, 1000] mm': the parameter's range as the table gives it."""
    opening = "(" if parameter.get("minimum_exclusive") else "["
    unit = f" {parameter['unit']}" if parameter.get("unit") else ""
    return f"{opening}{parameter['minimum']:g}, {parameter['maximum']:g}]{unit}"
