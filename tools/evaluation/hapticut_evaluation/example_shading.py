"""Force shading on the shipped example scenes (examples/*.hapticut.msgpack): the
force direction error of the tet proxy without shading, with shading from the
scene's own rigid surface (what a servo has on an exported scene) and with
shading from the source surface the scene was built from. Shading must never be
worse than the plain proxy."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hapticut import _core

from hapticut_evaluation import _baselines, accuracy, economy, meshes, surface

# (example, depth of the press into its rigid surface in mm): the finger's bones
# are capsules of 2.8 to 3.5 mm radius; the spheres and the bunny take 2 mm.
SCENES = ("sphere80", "sphere320", "finger", "mouse")
DEPTH_MM = {"sphere80": 2.0, "sphere320": 2.0} | economy.EXAMPLE_DEPTH_MM

# Press-and-slide strokes per scene (surface.strokes).
STROKES = 8

# The variants compared on every scene, by their column prefix.
PLAIN, OWN, SOURCE = "plain", "own", "source"
LABELS = {
    PLAIN: "tet proxy",
    OWN: "shaded from the scene's rigid surface",
    SOURCE: "shaded from the source surface",
}


def scene_space(path: Path) -> _core.Space:
    """The scene's tet mesh with every rigid material rigid and every other free,
    so the force is the contact force alone."""
    from hapticut.scenefile import load_scene

    scene = load_scene(path)
    rigid = np.array([m.model == "rigid" for m in scene.materials])[scene.tet_materials]
    labels = np.where(rigid, meshes.RIGID, meshes.AIR).astype(np.int32)
    return _core.Space(
        np.asarray(scene.vertices, np.float64),
        np.asarray(scene.tets, np.int32),
        labels,
        meshes.MATERIALS,
    )


def never_worse(row: dict) -> bool:
    """Does shading (both kinds) err no more than the plain proxy, mean and p95?"""
    return all(
        row[f"{kind}_dir_err_{stat}_deg"] <= row[f"{PLAIN}_dir_err_{stat}_deg"]
        for kind in (OWN, SOURCE)
        for stat in ("smooth_mean", "smooth_p95")
    )


def example_strokes(scenes, points: int, log):
    """(name, space, source surface, path, slide) for each example scene found: its tet mesh
    with rigid and free only (scene_space), the surface it was built from, and the
    press-and-slide strokes on it (surface.strokes); nothing when the examples are missing."""
    try:
        module = economy.examples_module()
    except FileNotFoundError as error:
        log(f"  skipped: {error}")
        return
    for name in scenes:
        file = economy.EXAMPLES_DIR / f"{name}.hapticut.msgpack"
        if not file.exists():
            log(f"  skipped {name}: {file} not found")
            continue
        source = economy.example_source(module, name)
        path, slide = surface.strokes(
            source, 0.001, points=points, depth_mm=DEPTH_MM[name], slide_s=economy.EXAMPLE_SLIDE_S
        )
        yield name, scene_space(file), source, path, slide


def run_example_shading(
    *,
    quick: bool = False,
    points: int = STROKES,
    repeats: int = 5,
    min_seconds: float = 3.0,
    scenes=SCENES,
    log=print,
) -> list[dict]:
    """One row per example scene; [] when the examples are missing."""
    rows, cases = [], []
    for name, space, source, path, slide in example_strokes(scenes, points, log):
        shadings = {
            PLAIN: None,
            OWN: _core.ForceShading(space),
            SOURCE: _core.ForceShading(space, source.vertices, source.triangles),
        }
        sets = {}
        for kind, shading in shadings.items():
            sets[kind] = _baselines.TetMethodSet(space, points, shading)
            sets[kind].reset(np.ascontiguousarray(path[0]))
        row = {"example": name, "tets": space.tet_count, "source_triangles": len(source.triangles)}
        cases.append((row, sets, source, path, slide))
    if not cases:
        return rows
    # Every scene and variant timed in the same rounds (see accuracy.time_round_robin).
    all_sets = [method for _, sets, *_ in cases for method in sets.values()]
    best_ns = iter(
        accuracy.time_round_robin_paths(
            all_sets,
            [path for *_, path, _ in cases for _ in range(len(LABELS))],
            0.001,
            repeats,
            0.0 if quick else min_seconds,
        )
    )
    for row, sets, source, path, slide in cases:
        for kind, method in sets.items():
            result = method.run(path, 0.001, timing_repeats=0)
            m = surface.contact_metrics(source, slide, result["q"], result["force_N"])
            row[f"{kind}_ns_per_update"] = next(best_ns)
            for metric in ("facet_mean", "smooth_mean", "smooth_p95"):
                row[f"{kind}_dir_err_{metric}_deg"] = m[f"dir_err_{metric}_deg"]
            if kind == PLAIN:
                row["contact_updates"] = m["contact_updates"]
        row["never_worse"] = never_worse(row)
        rows.append(row)
        log(
            f"  {row['example']:9s} {row['tets']:6d} tets: smooth error plain "
            f"{row['plain_dir_err_smooth_mean_deg']:.2f}, own "
            f"{row['own_dir_err_smooth_mean_deg']:.2f}, source "
            f"{row['source_dir_err_smooth_mean_deg']:.2f} deg"
        )
    return rows


def economy_never_worse(economy_rows: list[dict]) -> list[tuple[str, bool]]:
    """(example and variant, never worse) for the mesh-economy rows, which carry
    both kinds of shading (`shaded`: from the source, `own`: the scene's surface)."""
    out = []
    for r in economy_rows:
        ok = all(
            r[f"{kind}_dir_err_{stat}_deg"] <= r[f"tet_dir_err_{stat}_deg"]
            for kind in ("shaded", "own")
            for stat in ("smooth_mean", "smooth_p95")
        )
        out.append((f"{r['example']} {r['variant']}", ok))
    return out
