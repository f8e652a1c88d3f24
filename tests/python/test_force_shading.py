"""Force shading (beyond the paper) with normals from the source surface
the scene was built from: on faces the tet mesh split, the shaded normal is the
source's own interpolated field."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("hapticut._core")

from hapticut import _core  # noqa: E402
from hapticut_evaluation import (
    _baselines,
    meshes,
)


def _source_field(vertices, triangles):
    """The source's smooth normal field: angle-weighted unit vertex normals,
    interpolated (barycentric, unnormalised) over the triangle that holds x."""
    normals = np.zeros_like(vertices)
    for tri in triangles:
        x = vertices[tri]
        n = np.cross(x[1] - x[0], x[2] - x[0])
        n /= np.linalg.norm(n)
        for k in range(3):
            e1 = x[(k + 1) % 3] - x[k]
            e2 = x[(k + 2) % 3] - x[k]
            cosine = e1 @ e2 / np.linalg.norm(e1) / np.linalg.norm(e2)
            normals[tri[k]] += n * np.arccos(np.clip(cosine, -1, 1))
    normals /= np.linalg.norm(normals, axis=1)[:, None]

    def field(x):
        for tri in triangles:
            a, b, c = vertices[tri]
            n = np.cross(b - a, c - a)
            w = np.array([np.cross(b - x, c - x) @ n, np.cross(c - x, a - x) @ n, 0.0]) / (n @ n)
            w[2] = 1.0 - w[0] - w[1]
            if abs((x - a) @ n) < 1e-9 * (n @ n) ** 0.5 and np.all(w > -1e-12):
                return w @ normals[tri]
        raise AssertionError(f"{x} is on no source triangle")

    return field


def test_force_shading_follows_the_source_field_across_split_faces():
    # A rigid block in a Kuhn grid: each face of the block is split into 8 tet
    # faces, while the source box has 2 triangles a face. The shaded normal on
    # any piece must be the source's field (not a re-interpolation of unit
    # normals at the pieces' corners), found at the shaded contact point.
    axis = np.linspace(-45.0, 45.0, 7)
    scene = meshes.grid_scene("block", axis, axis, axis, ((-15, -15, -15), (15, 15, 15)))
    space = scene.space(stiffness_N_per_mm=0.1)
    source_v, source_t = meshes.cube_surface(15.0)
    field = _source_field(source_v, source_t)
    shading = _core.ForceShading(space, source_v, source_t)
    depth = 1.0
    spots = [(3.0, -7.0), (-9.0, 4.0), (6.5, 6.0), (-2.0, -11.0), (0.5, 0.25)]
    for x, y in spots:
        start = np.array([[x, y, 20.0]])
        pressed = np.array([[x, y, 15.0 - depth]])
        method = _baselines.TetMethodSet(space, 1, shading)
        method.reset(start)
        method.step(pressed, 0.001)
        q = method.q[0]
        np.testing.assert_allclose(q, [x, y, 15.0], atol=1e-9)
        # The contact point iteration of force shading (two steps from q).
        p = pressed[0]
        n = field(q)
        for _ in range(2):
            n = field(p + n * (depth / n[2]))
        expected = n / np.linalg.norm(n) * 0.1 * depth
        np.testing.assert_allclose(method.force_N[0], expected, atol=1e-12)


def test_shading_is_never_worse_than_the_plain_proxy_on_the_scanned_bunny():
    # The mouse example (the bunny scan simplified, meshed by fTetWild)
    # has bumps finer than its facets and a sharp crease where its holes were
    # closed. Shading must not err more than the plain proxy, mean and p95,
    # with normals from its own rigid surface or from the scan.
    from hapticut_evaluation import example_shading

    (row,) = example_shading.run_example_shading(
        quick=True, repeats=0, scenes=("mouse",), log=lambda *_: None
    )
    figures = {k: round(v, 2) for k, v in row.items() if k.endswith("_deg")}
    assert row["contact_updates"] > 3000, figures
    assert example_shading.never_worse(row), figures


def test_shading_source_and_nearest_triangle_are_checked():
    axis = np.linspace(-45.0, 45.0, 7)
    scene = meshes.grid_scene("block", axis, axis, axis, ((-15, -15, -15), (15, 15, 15)))
    space = scene.space()
    vertices = np.array([[0.0, 0.0, 20.0], [1.0, 0.0, 20.0], [0.0, 1.0, 20.0]])
    with pytest.raises(ValueError, match="source triangle 0 uses vertex 3"):
        _core.ForceShading(space, vertices, np.array([[0, 1, 3]], np.int32))
    vertices[1, 2] = np.nan
    with pytest.raises(ValueError, match="source vertex 1 is not finite"):
        _core.ForceShading(space, vertices, np.array([[0, 1, 2]], np.int32))
