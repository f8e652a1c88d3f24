"""The add-on's rooms import one way (docs/addon.md, "Layout"): each room imports only the
rooms below it. Read from the source (no bpy needed)."""

import ast
from pathlib import Path

ADDON = Path(__file__).resolve().parents[2] / "addon"
# Top to bottom; a module imports only from its own room or from rooms further down.
ORDER = ["operators", "ui", "above", "bake", "live", "authoring", "toolkit", "background"]
ABOVE = {"simulate", "waiting"}  # The modules above the rooms, at the package's top.


def _room(parts: list[str]) -> str:
    """The room of a module or package given as its path parts under addon/."""
    if (ADDON / parts[0]).is_dir():
        return parts[0]
    return "above" if parts[0] in ABOVE else "top"


def _imported_rooms(path: Path) -> set[str]:
    package = list(path.relative_to(ADDON).parent.parts)
    rooms = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if not isinstance(node, ast.ImportFrom) or node.level == 0:
            continue
        base = package[: len(package) - node.level + 1] + (
            node.module.split(".") if node.module else []
        )
        targets = [base] if node.module else [base + [alias.name] for alias in node.names]
        rooms.update(_room(t) for t in targets if t)
    return rooms


def test_every_module_lives_in_a_room_or_above_them():
    loose = [p.name for p in ADDON.glob("*.py") if p.name != "__init__.py" and p.stem not in ABOVE]
    assert loose == []
    rooms = {p.name for p in ADDON.iterdir() if p.is_dir() and not p.name.startswith("__")}
    assert rooms == set(ORDER) - {"above"}


def test_rooms_import_only_the_rooms_below_them():
    wrong = []
    for path in sorted(ADDON.rglob("*.py")):
        parts = list(path.relative_to(ADDON).with_suffix("").parts)
        if parts == ["__init__"]:
            continue  # Registration imports every room.
        room = _room(parts)
        for target in _imported_rooms(path) - {room}:
            if target == "top" or ORDER.index(target) < ORDER.index(room):
                wrong.append(f"{path.relative_to(ADDON)} imports {target}")
    assert wrong == []
