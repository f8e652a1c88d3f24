"""The build report as the panel's lines (tets, boundary faces, its warnings with their
remedies, deviation, quality, valence, time per stage). No bpy."""

from __future__ import annotations

import math

from .problem_remedies import remedy as problem_remedy


def report_lines(report: dict) -> list[str]:
    lines = [f"{report.get('tets', 0)} tets, {report.get('boundary_faces', 0)} boundary faces"]
    for warning, remedy in warnings(report):
        lines.append(f"warning: {warning}")
        lines += [f"  to fix: {remedy}"] if remedy else []
    for name, count in report.get("tets_per_material", {}).items():
        lines.append(f"  {name}: {count} tets")
    if "air_share" in report:
        lines.append(f"  air {100 * report['air_share']:.0f} % of the tets")
    for name, deviation in report.get("deviation_mm", {}).items():
        lines.append(f"  {name}: surface deviation {deviation:.3g} mm")
    meshings = len(report.get("meshing_attempts", []))
    if meshings > 1:
        lines.append(f"  meshed {meshings} times to hold the accuracy")
    quality = report.get("quality", {})
    if quality:
        lines.append(
            f"dihedral {quality.get('min_dihedral_deg', 0):.1f}..."
            f"{quality.get('max_dihedral_deg', 0):.1f} deg, "
            f"{quality.get('slivers', 0)} slivers"
        )
    valence = report.get("valence", {})
    if valence:
        lines.append(
            f"tets per edge max {valence.get('max_tets_per_edge', 0)}, per vertex max "
            f"{valence.get('max_tets_per_vertex', 0)}"
        )
    timings = report.get("timings_s", {})
    if timings:
        lines.append("time: " + ", ".join(f"{k} {v:.1f} s" for k, v in timings.items()))
    return lines


# What the panel says each build setting costs, beside the last build's figures.
SETTING_COSTS = (
    "Edge near: the tets at the surfaces; half of it gives about 4-8x the tets and the time",
    "Edge far: the tets away from them, mostly air; larger is cheaper",
    "Accuracy: how far surfaces may move; tighter keeps thin features, costs more tets",
)
FIRST_TRY = (
    "0 derives a setting from the regions: accuracy 1 % of their diagonal, edge near their "
    "mean edge, edge far 4x near; a ~100 mm object builds in under a minute"
)


def cost_lines(report: dict) -> list[str]:
    """What the build settings cost: the last build's resolved settings and figures, then
    what each setting trades (before any build: what 0 means)."""
    settings = report.get("settings", {})
    if not settings:
        return [FIRST_TRY, *SETTING_COSTS]
    total = report.get("timings_s", {}).get("total")
    took = f" in {total:.1f} s" if total is not None else ""
    return [
        f"last build: accuracy {settings.get('accuracy_mm', 0):.2g} mm, edges "
        f"{settings.get('edge_near_mm', 0):.2g} / {settings.get('edge_far_mm', 0):.2g} mm: "
        f"{report.get('tets', 0):,} tets{took}",
        *SETTING_COSTS,
    ]


def warnings(report: dict) -> list[tuple[str, str]]:
    """The build's warnings, each with what to do in the panel ("" when nothing is known):
    the toolkit's own, then each region whose meshed surface did not hold the accuracy (what
    it lost and where, in world mm)."""
    found = [(text, problem_remedy(text)) for text in report.get("warnings", [])]
    settings = report.get("settings", {})
    for miss in report.get("accuracy_not_held", []):
        deviation, accuracy = _apart(miss["deviation_mm"], miss["accuracy_mm"])
        text = f"accuracy not held: {miss['region']} lies up to {deviation} mm from your surface"
        text += f", beyond the accuracy ({accuracy} mm)"
        for feature in miss.get("lost_features", [])[:2]:
            width = feature.get("thickness_mm")
            text += f"; lost a {feature.get('kind', 'thin part')}"
            text += f" {width:.2g} mm across" if width is not None else ""
            text += " near (" + ", ".join(f"{c:.0f}" for c in feature["centre_mm"]) + ") mm"
        found.append((text, _accuracy_remedy(miss, settings)))
    return found


def _apart(deviation: float, accuracy: float) -> tuple[str, str]:
    """Both figures with the digits that tell them apart (1.214 beyond 1.21, not 1.21 beyond
    1.21)."""
    for digits in (3, 4, 5, 6):
        shown = f"{deviation:.{digits}g}", f"{accuracy:.{digits}g}"
        if shown[0] != shown[1]:
            return shown
    return shown


def _accuracy_remedy(miss: dict, settings: dict) -> str:
    near = settings.get("edge_near_mm")
    now_near = f" (now {near:.2g} mm)" if near else ""
    if miss.get("lost_mm", 0.0) >= miss.get("strayed_mm", 0.0):
        return (
            f"lower Edge near{now_near} in the Build panel to keep it (more tets, slower), or "
            f"raise Accuracy to {math.ceil(miss['deviation_mm'] * 10) / 10:g} mm or more to "
            "accept it; then "
            "Tetrahedralize"
        )
    return "lower Accuracy in the Build panel (the surface strays), then Tetrahedralize"
