"""The build report as the panel's lines (tets, boundary faces, deviation, quality, valence,
time per stage). No bpy."""

from __future__ import annotations


def report_lines(report: dict) -> list[str]:
    lines = [f"{report.get('tets', 0)} tets, {report.get('boundary_faces', 0)} boundary faces"]
    for name, count in report.get("tets_per_material", {}).items():
        lines.append(f"  {name}: {count} tets")
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
