"""Truth for rigid contact on surfaces without a formula (the bunny, the bone of
the layered limb): closest points on the source triangles, the source's facet
normal and its smooth (interpolated vertex) normal there, and press-and-slide
strokes that follow the surface. Plain numpy, brute force in chunks: the
evaluation's surfaces have a few thousand triangles."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# Point x triangle pairs per chunk of the brute-force search (memory bound).
CHUNK_PAIRS = 4_000_000


@dataclass
class SurfaceQueries:
    """What the evaluation asks of a closed triangle surface wound outward (closest points,
    facet and vertex normals), precomputed; the surface itself is the product's
    `hapticut.scenebuild.geometry.Surface` (vertices and faces)."""

    vertices: np.ndarray  # (V, 3)
    triangles: np.ndarray  # (T, 3)

    def __post_init__(self) -> None:
        self.vertices = np.ascontiguousarray(self.vertices, np.float64)
        self.triangles = np.ascontiguousarray(self.triangles, np.int32)
        a, b, c = (self.vertices[self.triangles[:, k]] for k in range(3))
        self.a, self.b, self.c = a, b, c
        n = np.cross(b - a, c - a)
        area2 = np.linalg.norm(n, axis=1)
        self.facet_normals = n / np.maximum(area2, 1e-300)[:, None]
        self.areas = area2 / 2.0
        self.vertex_normals = angle_weighted_normals(self.vertices, self.triangles)
        # Bounding spheres for pruning: centroid and farthest corner.
        self.centres = (a + b + c) / 3.0
        self.centre_norms2 = np.einsum("ij,ij->i", self.centres, self.centres)
        self.radii = np.max([np.linalg.norm(x - self.centres, axis=1) for x in (a, b, c)], axis=0)
        self.size = float(np.linalg.norm(self.vertices.max(axis=0) - self.vertices.min(axis=0)))

    def closest(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Closest surface point to each of (M, 3) points: (points (M, 3), triangle
        index (M,), barycentric weights (M, 3)). Triangles are pruned by their
        bounding spheres (no triangle is nearer than its centre's distance minus its
        radius, none farther than the nearest centre) before the exact test."""
        points = np.atleast_2d(np.asarray(points, np.float64))
        m = len(points)
        best_point = np.zeros((m, 3))
        best_tri = np.zeros(m, np.int64)
        best_bary = np.zeros((m, 3))
        step = max(1, CHUNK_PAIRS // max(1, len(self.triangles)))
        for lo in range(0, m, step):
            chunk = points[lo : lo + step]
            d2 = (
                np.einsum("ij,ij->i", chunk, chunk)[:, None]
                - 2.0 * chunk @ self.centres.T
                + self.centre_norms2[None, :]
            )
            distance = np.sqrt(np.maximum(d2, 0.0))
            # Margin: the expanded squared distance loses digits near zero.
            bound = distance.min(axis=1) + 1e-5 * (1.0 + self.size)
            rows, tris = np.nonzero(distance - self.radii[None, :] <= bound[:, None])
            closest, bary = closest_on_triangles(
                chunk[rows], self.a[tris], self.b[tris], self.c[tris]
            )
            gap = np.einsum("ij,ij->i", closest - chunk[rows], closest - chunk[rows])
            # Per point (rows are sorted), the candidate with the smallest gap.
            order = np.lexsort((gap, rows))
            first = order[np.searchsorted(rows[order], np.arange(len(chunk)))]
            best_point[lo : lo + step] = closest[first]
            best_tri[lo : lo + step] = tris[first]
            best_bary[lo : lo + step] = bary[first]
        return best_point, best_tri, best_bary

    def smooth_normal(self, triangle: np.ndarray, bary: np.ndarray) -> np.ndarray:
        """The vertex normals interpolated at barycentric `bary` in `triangle`, unit."""
        n = np.einsum("ij,ijk->ik", bary, self.vertex_normals[self.triangles[triangle]])
        return n / np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]

    def sample(self, count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
        """`count` points spread over the surface by area (fixed by the seed):
        (points, triangle index)."""
        rng = np.random.default_rng(seed)
        tri = rng.choice(len(self.triangles), size=count, p=self.areas / self.areas.sum())
        u, v = rng.random(count), rng.random(count)
        flip = u + v > 1.0
        u[flip], v[flip] = 1.0 - u[flip], 1.0 - v[flip]
        x = self.a[tri] + (self.b[tri] - self.a[tri]) * u[:, None]
        x += (self.c[tri] - self.a[tri]) * v[:, None]
        return x, tri


def angle_weighted_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Unit vertex normals, facet normals weighted by the corner angles (as force
    shading computes them)."""
    normals = np.zeros_like(vertices)
    corners = [vertices[triangles[:, k]] for k in range(3)]
    facet = np.cross(corners[1] - corners[0], corners[2] - corners[0])
    facet /= np.maximum(np.linalg.norm(facet, axis=1), 1e-300)[:, None]
    for k in range(3):
        e1 = corners[(k + 1) % 3] - corners[k]
        e2 = corners[(k + 2) % 3] - corners[k]
        e1 /= np.maximum(np.linalg.norm(e1, axis=1), 1e-300)[:, None]
        e2 /= np.maximum(np.linalg.norm(e2, axis=1), 1e-300)[:, None]
        angle = np.arccos(np.clip(np.einsum("ij,ij->i", e1, e2), -1.0, 1.0))
        np.add.at(normals, triangles[:, k], facet * angle[:, None])
    return normals / np.maximum(np.linalg.norm(normals, axis=1), 1e-300)[:, None]


def closest_on_triangles(p, a, b, c) -> tuple[np.ndarray, np.ndarray]:
    """Closest points on triangles abc to p (broadcast), and their barycentric
    weights (Ericson, Real-Time Collision Detection 5.1.5, by Voronoi region)."""
    ab, ac, ap = b - a, c - a, p - a
    d1 = np.einsum("...k,...k", ab, ap)
    d2 = np.einsum("...k,...k", ac, ap)
    bp = p - b
    d3 = np.einsum("...k,...k", ab, bp)
    d4 = np.einsum("...k,...k", ac, bp)
    cp = p - c
    d5 = np.einsum("...k,...k", ab, cp)
    d6 = np.einsum("...k,...k", ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    shape = np.broadcast_shapes(d1.shape)
    w = np.zeros((*shape, 3))
    with np.errstate(divide="ignore", invalid="ignore"):
        # Interior first; the regions below overwrite it where they apply.
        denom = va + vb + vc
        v_in, w_in = vb / denom, vc / denom
        w[..., 0], w[..., 1], w[..., 2] = 1.0 - v_in - w_in, v_in, w_in
        regions = [
            # (condition, weights), later entries win: edges, then vertices.
            (
                (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0),
                _edge(1, 2, (d4 - d3) / ((d4 - d3) + (d5 - d6))),
            ),
            ((vb <= 0) & (d2 >= 0) & (d6 <= 0), _edge(0, 2, d2 / (d2 - d6))),
            ((vc <= 0) & (d1 >= 0) & (d3 <= 0), _edge(0, 1, d1 / (d1 - d3))),
            ((d6 >= 0) & (d5 <= d6), _corner(2)),
            ((d3 >= 0) & (d4 <= d3), _corner(1)),
            ((d1 <= 0) & (d2 <= 0), _corner(0)),
        ]
        for condition, weights in regions:
            mask = np.broadcast_to(condition, shape)
            w[mask] = np.broadcast_to(weights(shape), (*shape, 3))[mask]
    w = np.nan_to_num(w, nan=1.0 / 3.0)
    closest = w[..., 0:1] * a + w[..., 1:2] * b + w[..., 2:3] * c
    return closest, w


def _edge(i: int, j: int, t):
    def weights(shape):
        out = np.zeros((*shape, 3))
        out[..., i] = 1.0 - np.broadcast_to(t, shape)
        out[..., j] = np.broadcast_to(t, shape)
        return out

    return weights


def _corner(i: int):
    def weights(shape):
        out = np.zeros((*shape, 3))
        out[..., i] = 1.0
        return out

    return weights


def strokes(
    surface: SurfaceQueries,
    dt_s: float,
    *,
    points: int = 8,
    depth_mm: float = 2.0,
    approach_mm: float = 5.0,
    slide_s: float = 0.5,
    speed_mm_s: float = 100.0,
    seed: int = 5,
) -> tuple[np.ndarray, np.ndarray]:
    """Press-and-slide strokes that follow a curved surface: from approach_mm
    outside a sampled surface point, press depth_mm in along its smooth normal,
    then slide at speed_mm_s, each tick stepping along the tangent, snapping to
    the closest surface point and pressing depth_mm below it. Returns the path
    (ticks, points, 3) and a (ticks,) mask of the slide phase."""
    rng = np.random.default_rng(seed)
    start, tri = surface.sample(points, seed)
    _, _, bary = surface.closest(start)
    normal = surface.smooth_normal(tri, bary)
    tangent = rng.normal(size=(points, 3))
    tangent -= normal * np.einsum("ij,ij->i", tangent, normal)[:, None]
    tangent /= np.linalg.norm(tangent, axis=1)[:, None]
    press_s = (approach_mm + depth_mm) / speed_mm_s
    press_ticks = int(round(press_s / dt_s))
    slide_ticks = int(round(slide_s / dt_s))
    path = np.zeros((press_ticks + slide_ticks + 1, points, 3))
    for k in range(press_ticks + 1):
        height = approach_mm - (approach_mm + depth_mm) * k / press_ticks
        path[k] = start + normal * height
    x = start
    for k in range(press_ticks + 1, len(path)):
        x, tri, bary = surface.closest(x + tangent * speed_mm_s * dt_s)
        normal = surface.smooth_normal(tri, bary)
        tangent -= normal * np.einsum("ij,ij->i", tangent, normal)[:, None]
        tangent /= np.maximum(np.linalg.norm(tangent, axis=1), 1e-300)[:, None]
        path[k] = x - normal * depth_mm
    slide = np.zeros(len(path), bool)
    slide[press_ticks + 1 :] = True
    return np.ascontiguousarray(path), slide


def contact_metrics(
    surface: SurfaceQueries, mask: np.ndarray, q: np.ndarray, force: np.ndarray
) -> dict:
    """Force-direction error (degrees) over the `mask` ticks against the source's
    normal at the closest source point to the proxy: its facet normal, and its
    smooth normal (vertex normals interpolated). Ticks without force are skipped."""
    q, f = q[mask].reshape(-1, 3), force[mask].reshape(-1, 3)
    magnitude = np.linalg.norm(f, axis=1)
    touching = magnitude > 1e-9
    q, f, magnitude = q[touching], f[touching], magnitude[touching]
    closest, tri, bary = surface.closest(q)
    out = {"contact_updates": int(touching.sum())}
    for name, normal in (
        ("facet", surface.facet_normals[tri]),
        ("smooth", surface.smooth_normal(tri, bary)),
    ):
        cosine = np.einsum("ij,ij->i", f, normal) / magnitude
        angle = np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))
        out[f"dir_err_{name}_mean_deg"] = float(angle.mean()) if len(angle) else float("nan")
        out[f"dir_err_{name}_p95_deg"] = (
            float(np.percentile(angle, 95)) if len(angle) else float("nan")
        )
    out["surface_gap_max_mm"] = float(np.linalg.norm(q - closest, axis=1).max()) if len(q) else 0.0
    return out
