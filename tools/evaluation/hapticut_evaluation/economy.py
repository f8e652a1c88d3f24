"""Mesh economy: tets, build time and tick time against force error for
uniform and adaptive sizing of the air and for a cube against a bounding-tet
enclosure (tick time against valence: valence.py)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from hapticut import _core
from hapticut.scenebuild.geometry import enclosure_surface

from hapticut_evaluation import _baselines, accuracy, meshes, paths


def _bounding_tet(half_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """The builder's regular-tet enclosure (4 outward triangles) whose insphere holds the
    cube of half-size half_mm grown by 5 %."""
    low, high = np.full(3, -half_mm), np.full(3, half_mm)
    vertices, faces = enclosure_surface("tetrahedron", low, high, 0.05 * half_mm)
    return vertices, faces.astype(np.int32)


def _build(
    name: str, faces: int, enclosure: str, edge_mm: float, adaptive: bool, cache: Path
) -> meshes.TetScene:
    file = cache / f"economy_{name}.npz"
    sv, st = meshes.icosphere(faces)
    if file.exists():
        d = np.load(file)
        return meshes.TetScene(
            name, d["vertices"], d["tets"], d["labels"], float(d["build_s"]), sv, st
        )
    ev, et = (
        meshes.cube_surface(meshes.CUBE_HALF_MM)
        if enclosure == "cube"
        else _bounding_tet(meshes.SPHERE_RADIUS_MM + 5.0)
    )
    vertices = np.vstack([sv, ev])
    triangles = np.vstack([st, et + len(sv)])
    bg = None
    if adaptive:
        # Sizing field: 2 mm at the sphere, growing with distance to 4x edge_mm.
        gv, gt = meshes.tetrahedralize(vertices, triangles, edge_length_mm=4 * edge_mm)
        distance = np.abs(np.linalg.norm(gv, axis=1) - meshes.SPHERE_RADIUS_MM)
        bg = (gv, gt, np.clip(2.0 + 0.5 * distance, 2.0, 4 * edge_mm))
    start = time.perf_counter()
    tv, tt = meshes.tetrahedralize(vertices, triangles, edge_length_mm=edge_mm, bg=bg)
    build_s = time.perf_counter() - start
    labels = np.where(
        meshes.inside_convex(tv[tt].mean(axis=1), sv, st), meshes.RIGID, meshes.AIR
    ).astype(np.int32)
    cache.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(file, vertices=tv, tets=tt, labels=labels, build_s=build_s)
    return meshes.TetScene(name, tv, tt, labels, build_s, sv, st)


def sizing_economy(
    cache: Path,
    *,
    faces: int = 320,
    quick: bool = False,
    repeats: int = 5,
    min_seconds: float = 3.0,
    log=print,
) -> list[dict]:
    variants = [
        ("uniform 12 mm, cube", "cube", 12.0, False),
        ("uniform 6 mm, cube", "cube", 6.0, False),
        ("adaptive 2-24 mm, cube", "cube", 6.0, True),
        ("uniform 12 mm, bounding tet", "tet", 12.0, False),
    ]
    if not quick:
        variants.insert(0, ("uniform 3 mm, cube", "cube", 3.0, False))
    path, slide = paths.press_and_slide(0.001)
    built = []
    for name, enclosure, edge, adaptive in variants:
        key = f"{faces}_" + name.replace(" ", "_").replace(",", "")
        scene = _build(key, faces, enclosure, edge, adaptive, cache)
        space = scene.space()
        method = _baselines.TetMethodSet(space, path.shape[1])
        method.reset(np.ascontiguousarray(path[0]))
        built.append((name, scene, space, method))
    # All variants timed in the same rounds (see accuracy.time_round_robin).
    best_ns = accuracy.time_round_robin(
        [method for *_, method in built], path, 0.001, repeats, 0.0 if quick else min_seconds
    )
    rows = []
    edges = {name: (edge, adaptive) for name, _, edge, adaptive in variants}
    for (name, scene, space, method), ns in zip(built, best_ns, strict=True):
        result = method.run(path, 0.001, timing_repeats=0)
        m = accuracy.contact_metrics(path, slide, result["q"], result["force_N"])
        rows.append(
            {
                "variant": name,
                "faces": faces,
                "tets": space.tet_count,
                "build_s": scene.build_s,
                "memory_bytes": space.memory_bytes,
                "ns_per_update": ns,
                "dir_err_mean_deg": m["dir_err_mean_deg"],
                "max_tets_per_edge": space.stats["max_tets_per_edge"],
                "max_tets_per_vertex": space.stats["max_tets_per_vertex"],
                # The target edge length (of the far field when adaptive).
                "edge_mm": edges[name][0],
                "adaptive": edges[name][1],
            }
        )
        log(
            f"  {name:30s} {space.tet_count:7d} tets {scene.build_s:6.1f} s "
            f"{ns:7.1f} ns {m['dir_err_mean_deg']:.3f} deg"
        )
    return rows


# The examples' scenes (examples/build_examples.py, built by hapticut.scenebuild):
# the bunny standing in for the paper's mouse, and the layered finger (skin, flesh, bone).
# examples/ of the source tree: the working directory's (the evaluation runs from the
# repository's root), or the folder given with --examples.
EXAMPLES_DIR = Path("examples")


def use_examples(folder: Path) -> None:
    """Read the examples' scenes and build script from `folder`."""
    global EXAMPLES_DIR
    EXAMPLES_DIR = folder


# (example, depth of the press into its rigid surface in mm): the finger's bones are
# capsules of 2.8 to 3.5 mm radius.
EXAMPLE_DEPTH_MM = {"mouse": 2.0, "finger": 1.0}
# Sliding after each press, s (at surface.strokes' default speed).
EXAMPLE_SLIDE_S = 0.5


def examples_module():
    """examples/build_examples.py of the source tree."""
    import importlib.util

    script = EXAMPLES_DIR / "build_examples.py"
    if not script.exists():
        raise FileNotFoundError(
            f"{script} not found: run from the repository's root or pass --examples"
        )
    spec = importlib.util.spec_from_file_location("build_examples", script)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _example_regions(module, name: str):
    regions, settings, _ = module.EXAMPLES[name]()
    return regions, settings


def example_source(module, name: str):
    """The surface an example's rigid material was built from (every rigid region
    together): the truth of its force directions and the source of force shading."""
    from hapticut_evaluation import surface

    regions, _ = _example_regions(module, name)
    rigid_regions = [r for r in regions if r.material.model == "rigid"]
    offsets = np.cumsum([0] + [len(r.vertices) for r in rigid_regions[:-1]])
    return surface.SurfaceQueries(
        np.vstack([r.vertices for r in rigid_regions]),
        np.vstack([r.faces + o for r, o in zip(rigid_regions, offsets, strict=True)]),
    )


def _build_example(module, name: str, key: str, override: dict, cache: Path) -> dict:
    """The example built with settings `override`, cached: vertices, tets, rigid flag
    per tet, build seconds (the whole build, and fTetWild's share) and the sizes used."""
    import json

    file = cache / f"economy_{name}_{key}.npz"
    if file.exists():
        d = np.load(file)
        return {k: d[k] for k in d.files} | {"report": json.loads(str(d["report_json"]))}
    scene, seconds = module.build_example(name, override)
    report = scene.metadata["build_report"]
    rigid = np.array([m.model == "rigid" for m in scene.materials])[scene.tet_materials]
    data = {
        "vertices": np.asarray(scene.vertices, np.float64),
        "tets": np.asarray(scene.tets, np.int32),
        "rigid": rigid,
        "build_s": seconds,
        "tetwild_s": float(report["timings_s"].get("tetrahedralize", float("nan"))),
        "report_json": json.dumps(report),
    }
    cache.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(file, **data)
    return data | {"report": report}


# Beyond sizing and enclosure: a finer surface (the build's accuracy), to show what
# does lower the error. The bunny's own setting is 2 mm.
EXTRA_VARIANTS = {
    "mouse": [("adaptive, cube, accuracy 0.5 mm", {"enclosure": "cube", "accuracy_mm": 0.5})]
}


def _example_variants(enclosure: str, near_mm: float, quick: bool) -> list[tuple[str, dict]]:
    """(label, BuildSettings fields) for one example: adaptive sizing in its own
    enclosure, in a cube and in a bounding tet; uniform sizing (the adaptive build's
    surface edge length, and twice that) in its own enclosure."""
    names = {"box": "box", "cube": "cube", "tetrahedron": "bounding tet"}
    kinds = [enclosure] + [k for k in ("cube", "tetrahedron") if k != enclosure]
    variants = [(f"adaptive, {names[k]}", {"enclosure": k}) for k in kinds]
    if quick:
        return variants[:2]
    for factor in (1, 2):
        edge = factor * near_mm
        variants.append(
            (
                f"uniform {edge:.3g} mm, {names[enclosure]}",
                {"enclosure": enclosure, "adaptive": False, "edge_near_mm": edge},
            )
        )
    return variants


def _key(settings, override: dict) -> str:
    """Cache key of a build: the overridden fields, readable, and a hash of the whole
    settings (so a change to the example's own settings rebuilds)."""
    import hashlib
    from dataclasses import replace

    readable = "_".join(
        f"{k}-{v:.4g}" if isinstance(v, float) else f"{k}-{v}" for k, v in override.items()
    )
    digest = hashlib.sha1(repr(replace(settings, **override)).encode()).hexdigest()[:8]
    return f"{readable}_{digest}"


def example_economy(
    cache: Path,
    *,
    quick: bool = False,
    points: int = 8,
    repeats: int = 5,
    min_seconds: float = 3.0,
    log=print,
) -> list[dict]:
    """Tets, build time, tick time and force error of the tet proxy (and with force
    shading) on the examples' rigid surfaces, for adaptive and uniform sizing and a cube
    or a bounding tet as the enclosure. Every non-rigid material is made free, so the
    force is the contact force alone; the truth is the source surface's normal at the
    closest source point to the proxy (facet normal, and the smooth normal
    interpolated from its vertex normals). Returns [] when the examples are missing."""
    from hapticut_evaluation import surface

    try:
        module = examples_module()
    except FileNotFoundError as error:
        log(f"  skipped: {error}")
        return []
    rows = []
    for name in ("mouse",) if quick else ("mouse", "finger"):
        _, settings = _example_regions(module, name)
        source = example_source(module, name)
        path, slide = surface.strokes(
            source, 0.001, points=points, depth_mm=EXAMPLE_DEPTH_MM[name], slide_s=EXAMPLE_SLIDE_S
        )
        own = {"enclosure": settings.enclosure}
        first = _build_example(module, name, _key(settings, own), own, cache)
        near = float(first["report"]["settings"]["edge_near_mm"])
        variants = _example_variants(settings.enclosure, near, quick)
        if not quick:
            variants += EXTRA_VARIANTS.get(name, [])
        # (row, method sets: tet, shaded from the source, shaded from its own surface)
        cases = []
        for label, override in variants:
            built = _build_example(module, name, _key(settings, override), override, cache)
            labels = np.where(built["rigid"], meshes.RIGID, meshes.AIR).astype(np.int32)
            space = _core.Space(built["vertices"], built["tets"], labels, meshes.MATERIALS)
            shading = _core.ForceShading(space, source.vertices, source.triangles)
            row = {
                "example": name,
                "variant": label,
                "tets": space.tet_count,
                "boundary_faces": space.boundary_face_count,
                "build_s": float(built["build_s"]),
                "tetwild_s": float(built["tetwild_s"]),
                "memory_bytes": space.memory_bytes,
                "max_tets_per_edge": space.stats["max_tets_per_edge"],
                "max_tets_per_vertex": space.stats["max_tets_per_vertex"],
                "mean_tets_per_vertex": space.stats["mean_tets_per_vertex"],
            }
            own_shading = _core.ForceShading(space)
            sets = {}
            for tag, with_shading in (("tet", None), ("shaded", shading), ("own", own_shading)):
                sets[tag] = _baselines.TetMethodSet(space, points, with_shading)
                sets[tag].reset(np.ascontiguousarray(path[0]))
            cases.append((row, sets))
        # Every variant of this example, with and without shading, timed in the
        # same rounds (see accuracy.time_round_robin).
        all_sets = [method for _, sets in cases for method in sets.values()]
        best_ns = iter(
            accuracy.time_round_robin(all_sets, path, 0.001, repeats, 0.0 if quick else min_seconds)
        )
        for row, sets in cases:
            for tag, method in sets.items():
                result = method.run(path, 0.001, timing_repeats=0)
                m = surface.contact_metrics(source, slide, result["q"], result["force_N"])
                row[f"{tag}_ns_per_update"] = next(best_ns)
                for metric in ("facet_mean", "facet_p95", "smooth_mean", "smooth_p95"):
                    row[f"{tag}_dir_err_{metric}_deg"] = m[f"dir_err_{metric}_deg"]
                if tag == "tet":
                    row["contact_updates"] = m["contact_updates"]
                    row["surface_gap_max_mm"] = m["surface_gap_max_mm"]
            rows.append(row)
            log(
                f"  {name:7s} {row['variant']:28s} {row['tets']:7d} tets {row['build_s']:6.1f} s "
                f"{row['tet_ns_per_update']:6.1f} ns facet {row['tet_dir_err_facet_mean_deg']:.2f} "
                f"smooth {row['tet_dir_err_smooth_mean_deg']:.2f} "
                f"shaded {row['shaded_dir_err_smooth_mean_deg']:.2f} "
                f"own {row['own_dir_err_smooth_mean_deg']:.2f} deg"
            )
    return rows
