"""``hapticut info SCENE``: counts, quality, valence and materials of a scene file."""

from __future__ import annotations

import argparse
import json
import sys

NAME = "info"
HELP = "Print a scene file's counts, tet quality, valence (tets per edge and vertex) and materials."

# The paper's Table 3 (Tanaka, Hirota and Kaneko): the models its timings ran on.
PAPER_TABLE3 = {
    "sphere80": {"faces": 80, "tets": 394, "air": 234, "body": 160, "vertices": 82},
    "sphere320": {"faces": 320, "tets": 1917, "air": 637, "body": 1280, "vertices": 353},
    "mouse": {"faces": None, "tets": 11831, "air": 5519, "body": 6312, "vertices": 2099},
}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", help="a .hapticut.json or .hapticut.msgpack file")
    parser.add_argument("--json", action="store_true", help="print the report as JSON")


def material_text(material) -> str:
    from hapticut.scenefile.model import MODEL_PARAMETERS

    parameters = MODEL_PARAMETERS.get(material.model, {})
    values = ", ".join(f"{p}={getattr(material, p):g}" for p in parameters)
    return f"{material.model}" + (f" ({values})" if values else "")


def scene_summary(scene) -> dict:
    """Everything ``info`` prints, as plain values."""
    from hapticut.scenebuild.quality import mesh_report
    from hapticut.stiffness import rendered_stiffness_N_per_mm

    report = mesh_report(
        scene.vertices, scene.tets, scene.tet_materials, [m.name for m in scene.materials]
    )
    report["materials"] = [
        {"name": m.name, "model": m.model, "description": material_text(m)} for m in scene.materials
    ]
    report["blades"] = [
        {
            "name": b.name,
            "start_mm": list(b.start_mm),
            "end_mm": list(b.end_mm),
            "points": b.points,
            "coupling": b.coupling,
            "orientation": b.orientation,
            "rendered_stiffness_N_per_mm": rendered_stiffness_N_per_mm(
                scene.stiffness_N_per_mm, b.points, b.coupling
            ),
        }
        for b in scene.blades
    ]
    report["build_report"] = scene.metadata.get("build_report")
    report["example"] = scene.metadata.get("example")
    return report


def paper_rows(summary: dict) -> list[str]:
    """Table 3 beside this scene, when the scene is one of the paper's models."""
    example = summary.get("example") or {}
    reference = PAPER_TABLE3.get(example.get("paper_model", ""))
    if reference is None:
        return []
    per_material = summary["tets_per_material"]
    air = per_material.get("air", 0)
    body = summary["tets"] - air
    rows = [
        f"Paper's Table 3 ({example['paper_model']}):",
        f"  {'':<10}{'paper':>8}{'this':>8}",
        f"  {'tets':<10}{reference['tets']:>8}{summary['tets']:>8}",
        f"  {'air':<10}{reference['air']:>8}{air:>8}",
        f"  {'body':<10}{reference['body']:>8}{body:>8}",
        f"  {'vertices':<10}{reference['vertices']:>8}{summary['used_vertices']:>8}",
    ]
    return rows


def format_summary(summary: dict) -> str:
    lines = [
        f"{summary['tets']} tets, {summary['used_vertices']} vertices, "
        f"{summary['valence']['edges']} edges, {summary['boundary_faces']} boundary faces",
        "Materials:",
    ]
    for material in summary["materials"]:
        count = summary["tets_per_material"].get(material["name"], 0)
        lines.append(f"  {material['name']:<14}{count:>9} tets  {material['description']}")
    if summary["tets"] and summary["materials"]:
        air = summary["tets_per_material"].get(summary["materials"][0]["name"], 0)
        lines.append(f"Air share: {100 * air / summary['tets']:.1f} % of the tets")
    quality = summary["quality"]
    lines.append(
        f"Quality: min dihedral {quality['min_dihedral_deg']:.2f} deg, max "
        f"{quality['max_dihedral_deg']:.2f} deg, {quality['slivers']} slivers (min dihedral "
        f"< {quality['sliver_threshold_deg']:g} deg), "
        f"{quality['inverted_or_flat']} inverted or flat"
    )
    valence = summary["valence"]
    lines.append(
        f"Valence: tets per edge max {valence['max_tets_per_edge']}, mean "
        f"{valence['mean_tets_per_edge']:.2f}; tets per vertex max "
        f"{valence['max_tets_per_vertex']}, mean {valence['mean_tets_per_vertex']:.2f}"
    )
    for blade in summary["blades"]:
        setting = blade["coupling"]
        if setting == "rigid":
            setting += f", orientation {blade['orientation']}"
        lines.append(
            f"Blade {blade['name']}: {blade['points']} points from {blade['start_mm']} to "
            f"{blade['end_mm']} mm (tool frame), {setting}; renders "
            f"{blade['rendered_stiffness_N_per_mm']:g} N/mm in contact"
        )
    build = summary.get("build_report")
    if build:
        lines.extend(format_build_report(build))
    lines.extend(paper_rows(summary))
    return "\n".join(lines)


def format_build_report(build: dict) -> list[str]:
    """The parts of a build report that ``info`` does not recompute."""
    from hapticut.scenebuild.report import accuracy_lines

    lines = [f"warning: {warning}" for warning in build.get("warnings") or []]
    settings = build.get("settings", {})
    if settings:
        sizing = (
            f"edges {settings['edge_near_mm']:.3g} mm near surfaces to "
            f"{settings['edge_far_mm']:.3g} mm far"
            if settings.get("adaptive")
            else f"uniform edges {settings['edge_near_mm']:.3g} mm"
        )
        lines.append(
            f"Built: {settings['enclosure']} enclosure (margin {settings['margin_mm']:.3g} mm), "
            f"accuracy {settings['accuracy_mm']:.3g} mm, {sizing}"
        )
    meshings = build.get("meshing_attempts") or []
    if len(meshings) > 1:
        lines.append(
            f"  meshed {len(meshings)} times to hold the accuracy (envelope "
            + " -> ".join(f"{m['envelope_mm']:.3g}" for m in meshings)
            + " mm)"
        )
    lines.extend("  " + line for line in accuracy_lines(build))
    for region, repairs in (build.get("repairs") or {}).items():
        if repairs:
            text = ", ".join(f"{k.replace('_', ' ')} {v}" for k, v in repairs.items())
            lines.append(f"  repaired {region}: {text}")
    for region, surface in (build.get("surfaces") or {}).items():
        deviation = (build.get("deviation_mm") or {}).get(region)
        lines.append(
            f"  region {region}: {surface['faces_in']} faces in, {surface['faces_meshed']} meshed"
            + (f", surface deviation {deviation:.3g} mm" if deviation is not None else "")
        )
    timings = build.get("timings_s")
    if timings:
        total = timings.get("total", 0.0)

        def step(name: str, seconds: float) -> str:
            share = f" = {100.0 * seconds / total:.1f} %" if total > 0 else ""
            return f"{name} {seconds:.2f} s{share}"

        lines.append(
            f"  build time {total:.2f} s ("
            + ", ".join(step(k, v) for k, v in timings.items() if k != "total")
            + ")"
        )
    return lines


def run(args: argparse.Namespace) -> int:
    from hapticut.scenefile import SceneError, load_scene

    try:
        scene = load_scene(args.scene)
    except (OSError, SceneError) as error:
        print(f"hapticut info: {args.scene}: {error}", file=sys.stderr)
        return 1
    summary = scene_summary(scene)
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(f"{args.scene}:")
        print(format_summary(summary))
    return 0
