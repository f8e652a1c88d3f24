"""The stiffness a blade renders in contact, the figure a device's stiffness limit bounds.

A rigid blade's points share one ideal pose, so its n point springs act in parallel: in contact
it renders n k, whatever length of its edge touches (docs/decisions.md, "The rigid blade").
Independent points each render their own spring k, as the paper's blade does. The servo
applies its limit to the same figure (docs/servo.md, "Stiffness limit").
"""

from __future__ import annotations

from hapticut.scenefile import BLADE_COUPLINGS


def rendered_stiffness_N_per_mm(
    stiffness_N_per_mm: float, points: int, coupling: str = "rigid"
) -> float:
    """n k for a rigid blade of n points, k for independent points."""
    if coupling not in BLADE_COUPLINGS:
        raise ValueError(f"coupling must be one of {', '.join(BLADE_COUPLINGS)}, got {coupling!r}")
    if points < 1:
        raise ValueError(f"a blade has at least 1 point, got {points}")
    return stiffness_N_per_mm * (points if coupling == "rigid" else 1)
