"""The in-memory scene of format version 1, and the error every scene check raises.

Units: lengths in mm, forces in N, time in s (the C++ twin is core/include/hapticut/scene.h).
"""

# Field names carry their units (`_N`, `_Hz`), which N815 reads as mixedCase.
# ruff: noqa: N815

from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields
from typing import Any

import numpy as np

from hapticut import _core

FORMAT_NAME = "hapticut.scene"
FORMAT_VERSION = 1
UNITS = {"length": "mm", "force": "N", "time": "s"}
# The material table and the settings' ranges are defined once, in C++ (material_table.h,
# parameter_range.h); everything here is derived from them.
MATERIAL_TABLE: dict[str, Any] = _core.material_table()
SETTING_RANGES: dict[str, dict[str, Any]] = _core.setting_ranges()
MATERIAL_MODELS = tuple(model["name"] for model in MATERIAL_TABLE["models"])
# The parameters each model takes (True: required, False: optional).
MODEL_PARAMETERS: dict[str, dict[str, bool]] = {
    model["name"]: {p["name"]: p["required"] for p in model["parameters"]}
    for model in MATERIAL_TABLE["models"]
}
# Every parameter's range (name, unit, minimum, minimum_exclusive, maximum, default, summary).
PARAMETER_RANGES: dict[str, dict[str, Any]] = {
    p["name"]: p for model in MATERIAL_TABLE["models"] for p in model["parameters"]
}
MATERIAL_PARAMETERS = tuple(PARAMETER_RANGES)


def _default(ranges: dict[str, dict[str, Any]], name: str) -> float:
    """The table's default of ``name`` (the dataclasses below restate no number)."""
    return ranges[name]["default"]


def parameter_problem(name: str, value: float) -> str:
    """'' when ``value`` is in the range of the material parameter or setting ``name``, else
    what is wrong, worded as the scene reader says it ("must be > 0, got -0.5")."""
    return _core.range_problem(name, float(value))


class SceneError(ValueError):
    """A scene the format does not allow.

    ``field`` is the JSON pointer of the offending field (``"/mesh/tets/17/2"``; ``"(root)"`` for
    the whole document), ``reason`` says what is wrong; the message is ``"<field>: <reason>"``.
    """

    def __init__(self, field: str, reason: str) -> None:
        super().__init__(f"{field}: {reason}")
        self.field = field
        self.reason = reason

    def __reduce__(self):
        return (type(self), (self.field, self.reason))


@dataclass(frozen=True)
class Material:
    """One material; only the parameters of its ``model`` are written to a file."""

    name: str
    model: str  # One of MATERIAL_MODELS.
    drag_distance_mm: float = 0.0  # drag: the proxy trails its target by at most this.
    viscosity_N_s_per_mm: float = 0.0  # viscous: resistance c in f = c v.
    max_lag_mm: float = _default(PARAMETER_RANGES, "max_lag_mm")  # viscous: cap on the lag.
    break_force_N: float = 0.0  # membrane: rigid until k |p' - q| exceeds this.
    # rigid: friction at a rigid blade's contacts, static and dynamic (0: frictionless).
    static_friction: float = _default(PARAMETER_RANGES, "static_friction")
    dynamic_friction: float = _default(PARAMETER_RANGES, "dynamic_friction")
    # drag, viscous, membrane: the material (by name) a tet of this one acts as once a blade
    # has cut it; "" (the default): a cut tet stays as it is (docs/scene-format.md).
    cut_to: str = ""


BLADE_COUPLINGS = ("rigid", "independent")
BLADE_ORIENTATIONS = ("free", "locked")


@dataclass(frozen=True)
class BladeSpec:
    """A blade edge in the tool frame, sampled by ``points`` proxies (ends included).

    coupling: "rigid" (one ideal pose for the whole edge) or "independent" (the paper's points,
    each on its own); orientation of a rigid blade: "free" or "locked" to the device's
    (docs/decisions.md, "The rigid blade").
    """

    name: str
    start_mm: tuple[float, float, float]
    end_mm: tuple[float, float, float]
    points: int = 50
    coupling: str = "rigid"  # One of BLADE_COUPLINGS.
    orientation: str = "free"  # One of BLADE_ORIENTATIONS.


@dataclass(frozen=True)
class Safety:
    """Limits the servo's safety layer applies between the engine and the device."""

    max_force_N: float = _default(SETTING_RANGES, "max_force_N")
    max_torque_N_mm: float = _default(SETTING_RANGES, "max_torque_N_mm")
    ramp_time_s: float = _default(SETTING_RANGES, "ramp_time_s")
    capped_tick_force_N: float = _default(SETTING_RANGES, "capped_tick_force_N")


@dataclass(eq=False)
class Scene:
    """A scene as read from a file: materials, the labelled tet mesh, blades and settings.

    vertices: (n, 3) float64 in mm; tets: (m, 4) int32 vertex indices, positively oriented after
    reading; tet_materials: (m,) int32 indices into ``materials``.
    """

    materials: list[Material]
    vertices: np.ndarray
    tets: np.ndarray
    tet_materials: np.ndarray
    blades: list[BladeSpec] = field(default_factory=list)
    stiffness_N_per_mm: float = _default(SETTING_RANGES, "stiffness_N_per_mm")
    servo_rate_Hz: float = _default(SETTING_RANGES, "servo_rate_Hz")
    # 0: derived from the mesh's size by the engine.
    tolerance_mm: float = _default(SETTING_RANGES, "tolerance_mm")
    # Cap on one proxy's transitions per tick: an engine budget, which the file keeps in its
    # "safety" object under this name.
    max_transitions_per_tick: int = int(_default(SETTING_RANGES, "max_transitions_per_tick"))
    safety: Safety = field(default_factory=Safety)
    metadata: dict[str, Any] = field(default_factory=dict)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Scene):
            return NotImplemented
        return all(_equal(getattr(self, f.name), getattr(other, f.name)) for f in fields(self))


def _equal(a: Any, b: Any) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(np.asarray(a), np.asarray(b))
    return bool(a == b)


def scene_to_dict(scene: Scene) -> dict[str, Any]:
    """The scene as plain values and numpy arrays (the shape hapticut._core exchanges)."""
    out = {f.name: getattr(scene, f.name) for f in fields(scene)}
    out["materials"] = [asdict(material) for material in scene.materials]
    out["blades"] = [asdict(blade) for blade in scene.blades]
    out["safety"] = asdict(scene.safety)
    return out


def scene_from_dict(data: dict[str, Any]) -> Scene:
    """The inverse of scene_to_dict (missing optional entries take their defaults)."""
    kwargs = dict(data)
    kwargs["materials"] = [Material(**item) for item in data["materials"]]
    kwargs["vertices"] = np.asarray(data["vertices"], dtype=np.float64).reshape(-1, 3)
    kwargs["tets"] = np.asarray(data["tets"], dtype=np.int32).reshape(-1, 4)
    kwargs["tet_materials"] = np.asarray(data["tet_materials"], dtype=np.int32).reshape(-1)
    kwargs["blades"] = [
        BladeSpec(**{**item, "start_mm": tuple(item["start_mm"]), "end_mm": tuple(item["end_mm"])})
        for item in data.get("blades", [])
    ]
    kwargs["safety"] = Safety(**data.get("safety", {}))
    return Scene(**kwargs)
