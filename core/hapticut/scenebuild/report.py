"""The build report: what a build did and measured, written into the scene file as
``metadata["build_report"]`` (docs/scene-building.md, step 8)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np


@dataclass
class SurfaceReport:
    """One region's surface: faces given and meshed, simplification error, enclosed volume."""

    faces_in: int
    faces_meshed: int
    simplification_deviation_mm: float
    volume_mm3: float | None = None  # Set by the crossing and nesting check.


@dataclass
class BuildReport:
    """What a build did and measured; ``as_json()`` is scene.metadata["build_report"]
    (docs/scene-building.md lists its entries)."""

    tetwild: str  # "pytetwild <version>".
    # What a user should know: an input whose size suggests other units than mm.
    warnings: list[str] = field(default_factory=list)
    repairs: dict[str, dict] = field(default_factory=dict)  # Per region (repair_surface).
    surfaces: dict[str, SurfaceReport] = field(default_factory=dict)
    self_intersecting_faces: dict[str, int] = field(default_factory=dict)  # Within one region.
    nesting: dict[str, str] = field(default_factory=dict)  # Region -> direct parent ("": none).
    settings: dict[str, Any] = field(default_factory=dict)  # As resolved for this build.
    enclosure: dict[str, Any] = field(default_factory=dict)
    boundary: dict[str, Any] = field(default_factory=dict)  # _check_boundary.
    labels: dict[str, Any] = field(default_factory=dict)  # labels.containment's statistics.
    tets_per_region: dict[str, int] = field(default_factory=dict)  # "(air)" too.
    mesh: dict[str, Any] = field(default_factory=dict)  # quality.mesh_report.
    deviation_mm: dict[str, float] | None = None  # Per region, when measured.
    # Input faces inside their own region's volume (the surface crosses itself), left out
    # of the deviation: per region, when there are any.
    buried_faces: dict[str, int] = field(default_factory=dict)
    # The regions still beyond accuracy_mm after the last meshing (the best one is kept):
    # deviation, the meshed surface's stray and the input's loss, and the lost features
    # (centre, length, thickness, depth, faces). Empty when the accuracy was held.
    accuracy_not_held: list[dict[str, Any]] = field(default_factory=list)
    # Each meshing's envelope and deviations, when measured (builder.MESHING_ATTEMPTS).
    meshing_attempts: list[dict[str, Any]] = field(default_factory=list)
    timings_s: dict[str, float] = field(default_factory=dict)  # Per step, and "total".

    def as_json(self) -> dict[str, Any]:
        """Plain JSON values, entries in the order the scene file has always had them."""
        out: dict[str, Any] = {
            "tetwild": self.tetwild,
            "repairs": self.repairs,
            "surfaces": {
                name: {k: v for k, v in asdict(surface).items() if v is not None}
                for name, surface in self.surfaces.items()
            },
            "self_intersecting_faces": self.self_intersecting_faces,
            "nesting": self.nesting,
            "settings": self.settings,
            "enclosure": self.enclosure,
            "boundary": self.boundary,
            "labels": self.labels,
            "tets_per_region": self.tets_per_region,
            **self.mesh,
        }
        per_material = self.mesh.get("tets_per_material") or {}
        if self.mesh.get("tets"):
            # The air is material 0, the first entry (builder._materials).
            air = next(iter(per_material.values()), 0)
            out["air_share"] = round(air / self.mesh["tets"], 4)
        if self.deviation_mm is not None:
            out["deviation_mm"] = self.deviation_mm
            out["meshing_attempts"] = self.meshing_attempts
            out["accuracy_not_held"] = self.accuracy_not_held
            if self.buried_faces:
                out["buried_faces"] = self.buried_faces
        if self.warnings:
            out["warnings"] = self.warnings
        out["timings_s"] = self.timings_s
        return _plain(out)


def figures_apart(deviation_mm: float, accuracy_mm: float) -> tuple[str, str]:
    """A deviation and the accuracy it is beyond, with the digits that tell them apart
    (1.214 beyond 1.21, not 1.21 beyond 1.21); the add-on's panel words them the same way
    (addon/authoring/report_text.py)."""
    for digits in (3, 4, 5, 6):
        shown = f"{deviation_mm:.{digits}g}", f"{accuracy_mm:.{digits}g}"
        if shown[0] != shown[1]:
            break
    return shown


def accuracy_lines(report: dict) -> list[str]:
    """Where a build did not hold its accuracy, as lines for people (``hapticut mesh`` and
    ``hapticut info``; the add-on's panel has its own short copy in
    addon/authoring/report_text.py)."""
    lines = []
    for miss in report.get("accuracy_not_held") or []:
        deviation, accuracy = figures_apart(miss["deviation_mm"], miss["accuracy_mm"])
        lines.append(
            f"accuracy not held: region {miss['region']!r} lies up to {deviation} mm from its "
            f"input, beyond accuracy_mm ({accuracy} mm)"
        )
        if miss["lost_mm"] >= miss["strayed_mm"]:
            for feature in miss["lost_features"]:
                centre = ", ".join(f"{c:.1f}" for c in feature["centre_mm"])
                thick = feature["thickness_mm"]
                kind = feature.get("kind", "thin part")
                size = ""
                if thick is not None:
                    size = f", {thick:.2g} mm " + ("wide" if kind == "narrow gap" else "thick")
                lines.append(
                    f"  lost: a {kind} near ({centre}) mm, {feature['length_mm']:.2g} mm long"
                    f"{size}, up to {feature['deviation_mm']:.2g} mm off"
                )
            finer = any(f.get("meshed_finer") for f in miss["lost_features"])
            lines.append(
                ("  meshed finer there without keeping it" if finer else "  too fine to chase")
                + ": the best mesh is kept; lower edge_near_mm to keep it (slower), or "
                "raise accuracy_mm to accept it"
            )
        else:
            lines.append("  the meshed surface strays from the input: lower accuracy_mm")
    return lines


def _plain(value):
    """The report as plain JSON values (numpy scalars and tuples converted)."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    return value
