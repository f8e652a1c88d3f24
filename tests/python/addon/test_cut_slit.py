"""The cut's slit (addon/bake/cut_slit.py, numpy only): two sheets, each face offset along
its own normal, facing away from each other; their corners' smooth normals, and the baked
mesh shading by them; a blade's half-thickness."""

import numpy as np
import pytest

from addon.bake import cut_slit

SQUARE = np.array([(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0, 1.0, 0.0), (0.0, 1.0, 0.0)])
TRIANGLES = np.array([(0, 1, 2), (0, 2, 3)])


def test_the_sheets_lie_offset_each_side_and_face_away():
    vertices, faces, frames = cut_slit.slit(SQUARE, TRIANGLES, np.array([4, 7]), 0.25)
    assert vertices.shape == (12, 3) and faces.shape == (4, 3)
    assert list(frames) == [4, 7, 4, 7]
    assert np.allclose(vertices[:6, 2], 0.25) and np.allclose(vertices[6:, 2], -0.25)
    corners = np.vstack([SQUARE[TRIANGLES].reshape(-1, 3)] * 2)
    assert np.allclose(vertices[:, :2], corners[:, :2])
    assert np.allclose((vertices[:6] + vertices[6:]) / 2, corners[:6])  # Twins in order.
    assert normals(vertices, faces)[:2, 2].min() > 0 > normals(vertices, faces)[2:, 2].max()


def test_faces_wound_both_ways_stay_back_to_back():
    # The same square with its second triangle wound the other way (a sweep that turned):
    # averaged vertex normals would cancel on the shared edge; each face keeps its own.
    flipped = np.array([(0, 1, 2), (0, 3, 2)])
    vertices, faces, _ = cut_slit.slit(SQUARE, flipped, np.array([1, 1]), 0.5)
    facing = normals(vertices, faces)
    assert np.allclose(np.einsum("ij,ij->i", facing[:2], facing[2:]), -1.0)
    assert np.allclose(np.abs(vertices[:, 2]), 0.5)


def normals(vertices, faces):
    corners = vertices[faces]
    crossed = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    return crossed / np.linalg.norm(crossed, axis=1, keepdims=True)


def test_half_thickness():
    box = np.array([(x, y, z) for x in (0, 40) for y in (0, 8) for z in (0, 0.6)], float)
    assert cut_slit.half_thickness(box) == pytest.approx(0.3)
    assert cut_slit.half_thickness(SQUARE) == pytest.approx(0.0, abs=1e-12)


# The square folded along its diagonal 0-2, a little (a turn of the blade) and far (a crease).
BENT = np.array([(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0, 1.0, 0.0), (0.0, 1.0, 0.3)])
FOLDED = np.array([(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0, 1.0, 0.0), (0.0, 1.0, 3.0)])


@pytest.mark.parametrize("second", [(0, 2, 3), (0, 3, 2)], ids=["wound alike", "wound both ways"])
def test_a_gently_bent_surface_shades_smoothly_across_its_triangles(second):
    faces = np.array([(0, 1, 2), second])
    corner = cut_slit.slit_normals(BENT, faces)  # (4, 3, 3): front sheet, then back
    assert corner.shape == (4, 3, 3)
    assert np.allclose(np.linalg.norm(corner, axis=2), 1.0)
    own = normals(*cut_slit.slit(BENT, faces, np.array([1, 1]), 0.1)[:2])
    # Each corner leans to its own face's side; the shared corners (0 and 2) of the two
    # triangles of a sheet's side agree, where flat shading would show the diagonal.
    assert (np.einsum("fkj,fj->fk", corner, own) > 0.9).all()
    side = np.sign(own[0] @ own[1])  # The second triangle's front faces the other way.
    for v in (0, 2):
        first = corner[0][list(faces[0]).index(v)]
        second_corner = corner[1][list(faces[1]).index(v)]
        assert np.allclose(first, side * second_corner)
    assert np.allclose(corner[2:], -corner[:2, ::-1])  # The back sheet: reversed, opposite.


def test_a_fold_beyond_the_crease_angle_keeps_each_face_flat():
    faces = np.array([(0, 1, 2), (0, 2, 3)])
    corner = cut_slit.slit_normals(FOLDED, faces)
    own = normals(*cut_slit.slit(FOLDED, faces, np.array([1, 1]), 0.1)[:2])
    assert np.allclose(corner, own[:, None, :])


def test_the_baked_cut_shades_by_the_smooth_normals(addon):
    """The cut mesh the bake makes (baking.cut_mesh) carries the corner normals: Blender's own
    would be each face's, the slit's faces being apart."""
    from types import SimpleNamespace

    import bpy

    from addon.bake import baking

    faces = np.array([(0, 1, 2), (0, 2, 3)])
    surface = SimpleNamespace(vertices=BENT, faces=faces, face_frames=np.array([1, 1]))
    mesh = baking.cut_mesh("cut normals test", surface, 1.0, 0.1)
    try:
        if hasattr(mesh, "corner_normals"):  # Blender 4.1 on
            shaded = np.array([n.vector for n in mesh.corner_normals])
        else:  # pragma: no cover - older Blenders
            mesh.calc_normals_split()
            shaded = np.array([loop.normal for loop in mesh.loops])
        expected = cut_slit.slit_normals(BENT, faces).reshape(-1, 3)
        assert np.allclose(shaded, expected, atol=1e-3)
    finally:
        bpy.data.meshes.remove(mesh)
