"""Cost of EDGE and VERTEX transitions against valence (the tets around the
edge or vertex): the paper's open question (section 5) on speeding up the
transitions out of an edge or a vertex, which search every tet that shares it.

Reference fans: an edge in n tets (edge_fan_mesh), a vertex in 2n tets
(double_cone_mesh) and in 20 x 4^k tets (vertex_fan_mesh, the icosahedron's
centre and its geodesic refinements). Each case is timed with
_core.time_transition (one transition, C++ loop, median of batches)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hapticut import _core

from hapticut_evaluation import meshes, paths

EDGE_VALENCES = (4, 6, 8, 12, 16, 20, 24, 32, 48, 64)
# (mesh name, builder): the centre vertex in 2 x ring tets, or 20 x 4^k.
VERTEX_FANS = [
    (f"double cone {n}", n * 2, lambda n=n: _core.double_cone_mesh(n))
    for n in (4, 6, 8, 12, 16, 24, 32)
] + [(f"geodesic {k}", 20 * 4**k, lambda k=k: _core.vertex_fan_mesh(k)) for k in (0, 1, 2)]
# Local edge index of the edge between local vertices a and b (tet_mesh.h's table).
EDGE_OF_VERTICES = [[-1, 0, 1, 2], [0, -1, 3, 4], [1, 3, -1, 5], [2, 4, 5, -1]]
# Widening cost depends on where the taking tet sits in the fan (the scan
# stops there): time this many targets spread over the fan, report mean and max.
WIDEN_TARGETS = 8
# Sideways push out of the element's tet in the FACE and EDGE cases, relative to the step.
OFFSET = 0.05


def _outward_normals(x: np.ndarray) -> np.ndarray:
    """(4, 3) outward unit normals of a positively oriented tet's faces; face f is
    opposite local vertex f."""
    normals = np.zeros((4, 3))
    for f in range(4):
        a, b, c = (x[k] for k in range(4) if k != f)
        n = np.cross(b - a, c - a)
        n /= np.linalg.norm(n)
        normals[f] = n if n @ (x[f] - a) < 0 else -n
    return normals


# The tets that refuse: a drag material whose lag is larger than any move here,
# so every move is refused after the full test. (Rigid tets would be skipped
# after their (a-2) test, and the search would not be measured.)
REFUSING = [
    {"name": "air", "model": "free"},
    {"name": "refusing", "model": "drag", "drag_distance_mm": 1.0e3},  # The table's maximum.
]


def _space(v: np.ndarray, t: np.ndarray, air: np.ndarray | None) -> _core.Space:
    """The fan with `air` tets free and the rest refusing every move, after the
    whole search (all free when air is None)."""
    labels = np.ones(len(t), np.int32)
    labels[slice(None) if air is None else air] = 0
    return _core.Space(v, t, labels, REFUSING)


def _time(space, state, tet, local, q, p, repeats, batches) -> dict:
    r = _core.time_transition(
        space,
        state,
        int(tet),
        int(local),
        np.ascontiguousarray(q),
        np.ascontiguousarray(p),
        repeats,
        batches,
    )
    r["transition"] = f"{_core.STATE_NAMES[int(r['from'])]}->{_core.STATE_NAMES[int(r['to'])]}"
    return r


def _fan_tets(tets: np.ndarray, vertices: tuple[int, ...]) -> np.ndarray:
    """Tets holding all of `vertices`, in index order (the order of the engine's fans)."""
    return np.flatnonzero(np.all([np.any(tets == v, axis=1) for v in vertices], axis=0))


def _widen(space, state, fan, local_of, q, repeats, batches) -> tuple[list[float], str]:
    """ns of widening into tets spread over the fan (all tets free): the scan
    stops at the tet whose wedge or cone holds p."""
    x = space.vertices[space.tets]
    picks = np.unique(
        np.linspace(0, len(fan) - 1, min(WIDEN_TARGETS, len(fan))).round().astype(int)
    )
    ns, kinds = [], set()
    for i in picks:
        t = fan[i]
        target = x[t].mean(axis=0)
        r = _time(space, state, fan[0], local_of(fan[0]), q, target, repeats, batches)
        ns.append(r["ns"])
        kinds.add(r["transition"] + ("" if r["to_tet"] == t else " (other tet)"))
    return ns, ", ".join(sorted(kinds))


def _row(element, mesh, valence, case, transition, ns, ns_max=None) -> dict:
    return {
        "element": element,
        "mesh": mesh,
        "valence": valence,
        "case": case,
        "transition": transition,
        "ns": float(ns),
        "ns_max": float(ns if ns_max is None else ns_max),
    }


def edge_rows(valences=EDGE_VALENCES, repeats: int = 2000, batches: int = 7) -> list[dict]:
    """The centre edge (vertices 0-1) of a fan of n tets.
    widen: all tets free, p at a fan tet's centroid: EDGE->TET (a-1), mean over targets.
    scan: tet 0 free, the rest refusing, p pulled away from tet 0 across the fan:
    every tet refuses, (a-3) scans all 2n faces, then (b) slides (here in place).
    face: tet 0 free, the rest refusing, p along one of tet 0's edge faces and a little
    out of it: (a-3) picks that face, EDGE->FACE, after scanning the whole fan."""
    rows = []
    for n in valences:
        v, t = _core.edge_fan_mesh(n)
        q = (v[0] + v[1]) / 2

        free = _space(v, t, None)
        fan = _fan_tets(free.tets, (0, 1))

        def local_of(tet, tets=free.tets):
            a, b = (int(np.flatnonzero(tets[tet] == k)[0]) for k in (0, 1))
            return EDGE_OF_VERTICES[a][b]

        ns, kind = _widen(free, _core.ProxyState.EDGE, fan, local_of, q, repeats, batches)
        rows.append(_row("edge", f"edge fan {n}", n, "widen", kind, np.mean(ns), np.max(ns)))

        one = _space(v, t, fan[:1])
        tet = fan[0]
        x = one.vertices[one.tets[tet]]
        inward = x.mean(axis=0) - q
        r = _time(
            one, _core.ProxyState.EDGE, tet, local_of(tet), q, q - 0.5 * inward, repeats, batches
        )
        rows.append(_row("edge", f"edge fan {n}", n, "scan", r["transition"], r["ns"]))

        normals = _outward_normals(x)
        local = list(one.tets[tet])
        a, b = local.index(0), local.index(1)
        face = next(f for f in range(4) if f not in (a, b))  # A face through the edge.
        third = next(k for k in range(4) if k not in (a, b, face))
        along = x[third] - q
        along -= (along @ (v[1] - v[0])) / ((v[1] - v[0]) @ (v[1] - v[0])) * (v[1] - v[0])
        p = q + along + OFFSET * np.linalg.norm(along) * normals[face]
        r = _time(one, _core.ProxyState.EDGE, tet, local_of(tet), q, p, repeats, batches)
        rows.append(_row("edge", f"edge fan {n}", n, "face", r["transition"], r["ns"]))
    return rows


def vertex_rows(fans=VERTEX_FANS, repeats: int = 2000, batches: int = 7) -> list[dict]:
    """The centre vertex 0 of a fan.
    widen: all tets free, p at a fan tet's centroid: VERTEX->TET (a-1), mean over targets.
    stay: all refusing: (a-1) and every (a-3) candidate refuse, the full search ends in place.
    face / edge: tet 0 free, the rest refusing, p along a face (edge) of tet 0 through the
    vertex and a little out of tet 0: (a-3) picks it, after scanning the whole fan."""
    rows = []
    for name, valence, build in fans:
        v, t = build()
        q = v[0].copy()
        free = _space(v, t, None)
        fan = _fan_tets(free.tets, (0,))

        def local_of(tet, tets=free.tets):
            return int(np.flatnonzero(tets[tet] == 0)[0])

        ns, kind = _widen(free, _core.ProxyState.VERTEX, fan, local_of, q, repeats, batches)
        rows.append(_row("vertex", name, valence, "widen", kind, np.mean(ns), np.max(ns)))

        tet = fan[0]
        corner = local_of(tet)
        x = free.vertices[free.tets[tet]]
        refusing = _space(v, t, [])
        r = _time(
            refusing, _core.ProxyState.VERTEX, tet, corner, q, x.mean(axis=0), repeats, batches
        )
        rows.append(_row("vertex", name, valence, "stay", r["transition"], r["ns"]))

        one = _space(v, t, fan[:1])
        normals = _outward_normals(x)
        face = (corner + 1) % 4  # A face through the vertex.
        on_face = x[[k for k in range(4) if k != face]].mean(axis=0) - q
        p = q + on_face + OFFSET * np.linalg.norm(on_face) * normals[face]
        r = _time(one, _core.ProxyState.VERTEX, tet, corner, q, p, repeats, batches)
        rows.append(_row("vertex", name, valence, "face", r["transition"], r["ns"]))

        other = (corner + 1) % 4  # The edge from the vertex to this corner.
        sides = [f for f in range(4) if f not in (corner, other)]
        along = x[other] - q
        p = q + along + OFFSET * np.linalg.norm(along) * normals[sides].sum(axis=0)
        r = _time(one, _core.ProxyState.VERTEX, tet, corner, q, p, repeats, batches)
        rows.append(_row("vertex", name, valence, "edge", r["transition"], r["ns"]))
    return rows


def run_valence(*, quick: bool = False) -> list[dict]:
    """Every EDGE and VERTEX case against valence; quick: three sizes each, short loops."""
    if quick:
        return edge_rows((4, 12, 32), repeats=200, batches=3) + vertex_rows(
            [VERTEX_FANS[0], VERTEX_FANS[3], VERTEX_FANS[6]], repeats=200, batches=3
        )
    return edge_rows() + vertex_rows()


def fit(rows: list[dict]) -> list[dict]:
    """Least-squares ns = fixed + per_tet x valence, per (element, case)."""
    out = []
    for key in sorted({(r["element"], r["case"]) for r in rows}):
        sel = [r for r in rows if (r["element"], r["case"]) == key]
        if len(sel) < 2:
            continue
        n = np.array([r["valence"] for r in sel], float)
        ns = np.array([r["ns"] for r in sel])
        slope, intercept = np.polyfit(n, ns, 1)
        residual = ns - (intercept + slope * n)
        out.append(
            {
                "element": key[0],
                "case": key[1],
                "ns_fixed": float(intercept),
                "ns_per_tet": float(slope),
                "r2": float(1.0 - residual.var() / max(ns.var(), 1e-300)),
            }
        )
    return out


def transition_share(cache: Path, *, faces: int = 320, points: int = 8) -> dict:
    """How often a tick of the 1 kHz press-and-slide stroke on the rigid sphere
    leaves an EDGE or a VERTEX, and the valences of that mesh."""
    path, _ = paths.press_and_slide(0.001, points=points)
    return stroke_share(meshes.sphere_in_cube(faces, cache), path)


def stroke_share(scene: meshes.TetScene, path: np.ndarray) -> dict:
    """Transitions per tick by the state they leave along a (ticks, N, 3) 1 kHz path
    through the scene, and the scene's valences."""
    space = scene.space()
    points = path.shape[1]
    proxies = _core.ProxySet(space, points)
    proxies.reset(np.ascontiguousarray(path[0]))
    proxies.clear_counters()
    proxies.run(path, 0.001)
    c = proxies.counters
    by_from = c["transitions"].sum(axis=(0, 2, 3))
    ticks = int(c["ticks"].sum())
    stats = space.stats
    return {
        "ticks": ticks,
        "transitions_per_tick": float(by_from.sum() / ticks),
        "edge_per_tick": float(by_from[2] / ticks),
        "vertex_per_tick": float(by_from[3] / ticks),
        "mean_tets_per_edge": float(stats["mean_tets_per_edge"]),
        "max_tets_per_edge": int(stats["max_tets_per_edge"]),
        "mean_tets_per_vertex": float(stats["mean_tets_per_vertex"]),
        "max_tets_per_vertex": int(stats["max_tets_per_vertex"]),
    }
