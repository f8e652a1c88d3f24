"""The build report as the panel's lines (tets, boundary faces, deviation, quality, valence,
time per stage). No bpy."""

from __future__ import annotations


def report_lines(report: dict) -> list[str]:
    lines = [f"{report.get('tets', 0)} tets, {report.get('boundary_faces', 0)} boundary faces"]
    lines += [f"warning: {warning}" for warning in report.get("warnings", [])]
    for name, count in report.get("tets_per_material", {}).items():
        lines.append(f"  {name}: {count} tets")
    if "air_share" in report:
        lines.append(f"  air {100 * report['air_share']:.0f} % of the tets")
    for name, deviation in report.get("deviation_mm", {}).items():
        lines.append(f"  {name}: surface deviation {deviation:.3g} mm")
    for miss in report.get("accuracy_not_held", []):
        lines.append(
            f"  accuracy not held: {miss['region']} up to {miss['deviation_mm']:.3g} mm "
            f"(accuracy {miss['accuracy_mm']:.3g} mm)"
        )
        for feature in miss["lost_features"][:2]:
            width = feature["thickness_mm"]
            lines.append(
                f"    lost a {feature['kind']}"
                + (f" {width:.2g} mm across" if width is not None else "")
                + " near ("
                + ", ".join(f"{c:.0f}" for c in feature["centre_mm"])
                + ") mm"
            )
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
