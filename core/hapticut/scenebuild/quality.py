"""Quality and valence of a tet mesh, in numpy, for any scene (``hapticut info``, build reports).

Valence is the paper's cost driver: an EDGE or VERTEX transition loops over the tets around
the edge or vertex (docs/method.md, Table 2: 12 tets around an edge, 20 at a vertex).
"""

from __future__ import annotations

import numpy as np

from .geometry import TET_EDGES, TET_FACES, tet_signed_volumes

# A tet with a dihedral angle below this is counted as a sliver (flat, nearly zero volume
# for its size): fTetWild's optimized meshes rarely go below it, and such tets make the
# walk's plane tests sensitive to rounding.
SLIVER_DIHEDRAL_DEG = 10.0


def dihedral_angles_deg(vertices: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """(m, 6) interior dihedral angles of each tet in degrees, one per edge (TET_EDGES order).

    The angle at edge (i, j) is between the two faces containing it: the faces opposite the
    other two vertices k and l; it is pi minus the angle between their outward normals.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    tets = np.asarray(tets)
    sign = np.sign(tet_signed_volumes(vertices, tets))[:, None]
    normals = []
    for face in TET_FACES:
        a, b, c = (vertices[tets[:, face[i]]] for i in range(3))
        n = np.cross(b - a, c - a) * sign
        length = np.linalg.norm(n, axis=1, keepdims=True)
        normals.append(n / np.where(length > 0, length, 1.0))
    angles = np.empty((len(tets), 6))
    for e, (i, j) in enumerate(TET_EDGES):
        k, m = (v for v in range(4) if v not in (i, j))
        cos = np.clip(np.einsum("ij,ij->i", normals[k], normals[m]), -1.0, 1.0)
        angles[:, e] = 180.0 - np.degrees(np.arccos(cos))
    return angles


def tet_quality(
    vertices: np.ndarray, tets: np.ndarray, sliver_deg: float = SLIVER_DIHEDRAL_DEG
) -> dict:
    """Dihedral-angle summary: min, max, mean of per-tet minimum, slivers, inverted tets."""
    if len(tets) == 0:
        return {"min_dihedral_deg": 0.0, "max_dihedral_deg": 0.0, "slivers": 0}
    angles = dihedral_angles_deg(vertices, tets)
    per_tet_min = angles.min(axis=1)
    volumes = tet_signed_volumes(vertices, tets)
    return {
        "min_dihedral_deg": round(float(per_tet_min.min()), 3),
        "max_dihedral_deg": round(float(angles.max()), 3),
        "mean_min_dihedral_deg": round(float(per_tet_min.mean()), 3),
        "sliver_threshold_deg": sliver_deg,
        "slivers": int((per_tet_min < sliver_deg).sum()),
        "inverted_or_flat": int((volumes <= 0).sum()),
        "min_volume_mm3": float(np.abs(volumes).min()),
    }


def valence(tets: np.ndarray, vertex_count: int | None = None) -> dict:
    """Tets per edge and per vertex (max and mean over the mesh's edges and used vertices)."""
    tets = np.asarray(tets, dtype=np.int64)
    if len(tets) == 0:
        return {"edges": 0, "max_tets_per_edge": 0, "mean_tets_per_edge": 0.0}
    n = int(vertex_count if vertex_count is not None else tets.max() + 1)
    edges = np.sort(tets[:, TET_EDGES].reshape(-1, 2), axis=1)
    _, per_edge = np.unique(edges[:, 0] * n + edges[:, 1], return_counts=True)
    per_vertex = np.bincount(tets.ravel(), minlength=n)
    per_vertex = per_vertex[per_vertex > 0]
    return {
        "edges": int(len(per_edge)),
        "max_tets_per_edge": int(per_edge.max()),
        "mean_tets_per_edge": round(float(per_edge.mean()), 3),
        "max_tets_per_vertex": int(per_vertex.max()),
        "mean_tets_per_vertex": round(float(per_vertex.mean()), 3),
    }


def material_counts(tet_materials: np.ndarray, material_names: list[str]) -> dict[str, int]:
    """Tets per material name, in the materials' order (materials without tets count 0)."""
    counts = np.bincount(np.asarray(tet_materials, dtype=np.int64), minlength=len(material_names))
    return {name: int(counts[i]) for i, name in enumerate(material_names)}


def mesh_report(vertices: np.ndarray, tets: np.ndarray, tet_materials, material_names) -> dict:
    """Counts, quality and valence of a labelled tet mesh (what ``hapticut info`` prints)."""
    from .geometry import boundary_faces

    used = np.unique(np.asarray(tets).ravel()) if len(tets) else np.zeros(0, dtype=np.int64)
    return {
        "vertices": int(len(vertices)),
        "used_vertices": int(len(used)),
        "tets": int(len(tets)),
        "boundary_faces": int(len(boundary_faces(np.asarray(tets)))) if len(tets) else 0,
        "tets_per_material": material_counts(tet_materials, list(material_names)),
        "quality": tet_quality(vertices, tets),
        "valence": valence(tets, len(vertices)),
    }
