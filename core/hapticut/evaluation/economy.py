"""Mesh economy: tets, build time and tick time against force error for
uniform and adaptive sizing of the air and for a cube against a bounding-tet
enclosure; and tick time against edge valence (the paper's open question on
the cost of EDGE and VERTEX transitions)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from hapticut import _core
from hapticut.evaluation import accuracy, meshes, paths

EDGE_VALENCES = (4, 6, 8, 12, 16, 20, 24, 32)


def _local_edge(tet: np.ndarray, vertices: np.ndarray, a: int, b: int) -> tuple[int, int]:
    """(local index of a, of b) in the tet as the engine stores it (re-oriented
    tets have their last two vertices swapped)."""
    x = vertices[tet]
    if np.linalg.det(x[1:] - x[0]) < 0:
        tet = tet[[0, 1, 3, 2]]
    return int(np.flatnonzero(tet == a)[0]), int(np.flatnonzero(tet == b)[0])


EDGE_OF_VERTICES = [[-1, 0, 1, 2], [0, -1, 3, 4], [1, 3, -1, 5], [2, 4, 5, -1]]


def valence_timing(repeats: int = 2000, batches: int = 7) -> list[dict]:
    """ns of one EDGE transition on the centre edge of a fan of n tets: tet 0 is
    air, the rest rigid. 'widen' pulls p into tet 0 (a-1 finds it); 'scan' pushes p
    into the rigid side so every tet refuses and (a-3) scans every face."""
    rows = []
    for n in EDGE_VALENCES:
        v, t = _core.edge_fan_mesh(n)
        labels = np.full(len(t), meshes.RIGID, np.int32)
        labels[0] = meshes.AIR
        space = _core.Space(v, t, labels, meshes.MATERIALS)
        la, lb = _local_edge(t[0], v, 0, 1)
        local = EDGE_OF_VERTICES[la][lb]
        q = (v[0] + v[1]) / 2
        inward = v[t[0]].mean(axis=0) - q
        opposite = -inward
        for case, p in (("widen", q + inward), ("scan", q + opposite * 0.5)):
            r = _core.time_transition(
                space,
                _core.ProxyState.EDGE,
                0,
                local,
                np.ascontiguousarray(q),
                np.ascontiguousarray(p),
                repeats,
                batches,
            )
            rows.append(
                {
                    "element": "edge",
                    "valence": n,
                    "case": case,
                    "ns": r["ns"],
                    "transition": f"{_core.STATE_NAMES[int(r['from'])]}->"
                    f"{_core.STATE_NAMES[int(r['to'])]}",
                }
            )
    return rows


def _bounding_tet(half_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """A regular tet enclosing the cube of half-size half_mm, as 4 outward triangles."""
    r = 3.0 * half_mm * 3**0.5 * 1.05  # Insphere radius r/3 > the cube's circumradius.
    v = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], float) / 3**0.5 * r
    tris = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]], np.int32)
    a, b, c = (v[tris[:, k]] for k in range(3))
    flip = np.einsum("ij,ij->i", np.cross(b - a, c - a), a + b + c) < 0
    tris[flip] = tris[flip][:, [0, 2, 1]]
    return v, tris


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


def sizing_economy(cache: Path, *, faces: int = 320, quick: bool = False, log=print) -> list[dict]:
    variants = [
        ("uniform 12 mm, cube", "cube", 12.0, False),
        ("uniform 6 mm, cube", "cube", 6.0, False),
        ("adaptive 2-24 mm, cube", "cube", 6.0, True),
        ("uniform 12 mm, bounding tet", "tet", 12.0, False),
    ]
    if not quick:
        variants.insert(0, ("uniform 3 mm, cube", "cube", 3.0, False))
    rows = []
    for name, enclosure, edge, adaptive in variants:
        key = f"{faces}_" + name.replace(" ", "_").replace(",", "")
        scene = _build(key, faces, enclosure, edge, adaptive, cache)
        space = scene.space()
        path, slide = paths.press_and_slide(0.001)
        best = None
        for _ in range(3):
            result = _core.TetMethodSet(space, path.shape[1])
            result.reset(np.ascontiguousarray(path[0]))
            out = result.run(path, 0.001)
            best = out if best is None or out["ns_per_update"] < best["ns_per_update"] else best
        m = accuracy.contact_metrics(path, slide, best["q"], best["force_N"])
        rows.append(
            {
                "variant": name,
                "faces": faces,
                "tets": space.tet_count,
                "build_s": scene.build_s,
                "memory_bytes": space.memory_bytes,
                "ns_per_update": best["ns_per_update"],
                "dir_err_mean_deg": m["dir_err_mean_deg"],
                "max_tets_per_edge": space.stats["max_tets_per_edge"],
                "max_tets_per_vertex": space.stats["max_tets_per_vertex"],
            }
        )
        log(
            f"  {name:30s} {space.tet_count:7d} tets {scene.build_s:6.1f} s "
            f"{best['ns_per_update']:7.1f} ns {m['dir_err_mean_deg']:.3f} deg"
        )
    return rows
