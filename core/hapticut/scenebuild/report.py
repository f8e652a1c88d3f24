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
        if self.deviation_mm is not None:
            out["deviation_mm"] = self.deviation_mm
            out["meshing_attempts"] = self.meshing_attempts
        out["timings_s"] = self.timings_s
        return _plain(out)


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
