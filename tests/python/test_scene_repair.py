"""Repairs before meshing (pymeshlab): each happens and is counted in the report."""

from __future__ import annotations

import numpy as np
import pytest
from build_test_support import bunny_path, icosphere
from hapticut.scenebuild.geometry import signed_volume
from hapticut.scenebuild.repair import read_obj, read_surface, repair_surface
from hapticut.scenebuild.simplify import simplify_surface

MAX_HOLE = 100


def test_the_bunny_scans_109_boundary_edges_are_closed_and_reported():
    vertices, faces = read_surface(bunny_path())
    surface, repairs = repair_surface("bunny", vertices, faces, MAX_HOLE)
    assert repairs["boundary_edges_before"] == 109
    assert repairs["closed_holes"] == 5
    assert repairs["faces_added_in_holes"] > 0
    assert signed_volume(surface.vertices, surface.faces) > 0


def test_split_vertices_are_merged_and_reported():
    vertices, faces = icosphere(10.0, 1)
    split = vertices[faces].reshape(-1, 3)  # every face with its own three vertices
    surface, repairs = repair_surface("ball", split, np.arange(len(split)).reshape(-1, 3), MAX_HOLE)
    assert repairs["merged_duplicate_vertices"] == len(split) - len(vertices)
    assert len(surface.vertices) == len(vertices)


def test_a_fin_on_an_edge_is_removed_as_non_manifold_and_reported():
    vertices, faces = icosphere(10.0, 1)
    a, b = faces[0, 0], faces[0, 1]
    vertices = np.vstack([vertices, [[30.0, 30.0, 30.0]]])
    faces = np.vstack([faces, [[a, b, len(vertices) - 1]]])
    surface, repairs = repair_surface("finned", vertices, faces, MAX_HOLE)
    assert repairs["removed_faces_at_non_manifold_edges"] >= 1
    assert signed_volume(surface.vertices, surface.faces) > 0


def test_zero_area_and_duplicate_faces_are_removed_and_reported():
    vertices, faces = icosphere(10.0, 1)
    midpoint = (vertices[faces[0, 0]] + vertices[faces[0, 1]]) / 2
    vertices = np.vstack([vertices, midpoint])
    repeated = [faces[0, 0], faces[0, 1], faces[0, 1]]
    collinear = [faces[0, 0], faces[0, 1], len(vertices) - 1]
    faces = np.vstack([faces, [repeated, collinear], faces[:2]])
    surface, repairs = repair_surface("ball", vertices, faces, MAX_HOLE)
    assert repairs["removed_zero_area_faces"] == 2
    assert repairs["removed_duplicate_faces"] == 2
    assert len(surface.faces) == 80


def test_an_inside_out_mesh_is_turned_and_reported():
    vertices, faces = icosphere(10.0, 1)
    surface, repairs = repair_surface("ball", vertices, faces[:, ::-1], MAX_HOLE)
    assert repairs.get("inverted_inside_out") == 1
    assert signed_volume(surface.vertices, surface.faces) > 0


def test_faces_run_against_their_neighbours_are_turned_and_a_coherent_mesh_left(monkeypatch):
    """Orientation is made coherent when two faces run an edge the same way (the faces
    turned are counted); a coherent mesh, and one without a non-manifold edge, skip
    pymeshlab's filters (counted by their edge uses, cheaper on a scan): nothing changes."""
    import pymeshlab

    called = []
    for name in ("meshing_re_orient_faces_coherently", "meshing_repair_non_manifold_edges"):
        real = getattr(pymeshlab.MeshSet, name)

        def recording(self, *args, real=real, name=name, **kwargs):
            called.append(name)
            return real(self, *args, **kwargs)

        monkeypatch.setattr(pymeshlab.MeshSet, name, recording)
    vertices, faces = icosphere(10.0, 2)
    surface, repairs = repair_surface("ball", vertices, faces, MAX_HOLE)
    assert called == [] and repairs == {}
    assert np.array_equal(surface.faces, faces) and np.array_equal(surface.vertices, vertices)
    turned = faces.copy()
    turned[[3, 7]] = turned[[3, 7], ::-1]
    surface, repairs = repair_surface("ball", vertices, turned, MAX_HOLE)
    assert called == ["meshing_re_orient_faces_coherently"]
    assert repairs == {"reoriented_faces": 2}

    def directed(f):
        return {tuple(e) for e in f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2).tolist()}

    assert directed(surface.faces) == directed(faces)  # Each face as it was, in any rotation.


def test_small_holes_are_closed_and_large_ones_refused():
    vertices, faces = icosphere(10.0, 2)
    punched = faces[~np.any(faces == 0, axis=1)]  # the faces around vertex 0 gone: a small hole
    surface, repairs = repair_surface("ball", vertices, punched, MAX_HOLE)
    assert repairs["closed_holes"] >= 1
    from hapticut.scenebuild import BuildError

    with pytest.raises(BuildError, match="open mesh"):
        repair_surface("ball", vertices, faces[faces[:, 0] % 2 == 0], 4)


def test_simplify_keeps_the_surface_within_its_tolerance():
    vertices, faces = icosphere(30.0, 4)  # 5120 faces
    surface, _ = repair_surface("ball", vertices, faces, MAX_HOLE)
    simple, before, deviation = simplify_surface(surface, 0.5)
    assert before == 5120
    assert len(simple.faces) < before / 3
    assert 0 < deviation <= 0.5


def test_obj_reader_fans_polygons_and_resolves_negative_indices(tmp_path):
    path = tmp_path / "quad.obj"
    path.write_text(
        "# a tetrahedron with one quad-written face\n"
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
        "f 1/1/1 3 2\nf -4 -3 -1\nf 1 4 3\nf 2 3 4\n"
        "vt 0 0\nvn 0 0 1\n"
    )
    vertices, faces = read_obj(str(path))
    assert vertices.shape == (4, 3)
    assert faces.tolist() == [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
