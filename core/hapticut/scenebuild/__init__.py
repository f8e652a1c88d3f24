"""Building a scene from surface meshes (builder.py; docs/scene-building.md): repair,
simplification (simplify.py), enclosure, sizing, fTetWild (tetwild.py), labels (labels.py),
quality (quality.py). The file format is hapticut.scenefile."""

from .builder import (
    BuildSettings,
    RefineZone,
    Region,
    build,
    check_layout,
    cut_variant,
    units_warning,
)
from .errors import BuildCancelled, BuildError
from .report import BuildReport

__all__ = [
    "BuildCancelled",
    "BuildError",
    "BuildReport",
    "BuildSettings",
    "RefineZone",
    "Region",
    "build",
    "check_layout",
    "cut_variant",
    "units_warning",
]
