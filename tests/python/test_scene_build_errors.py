"""Bad inputs to scene building: a clear error naming the region and the problem, no file."""

from __future__ import annotations

import numpy as np
import pytest
from build_test_support import icosphere, run_cli, write_obj
from hapticut.scenebuild import BuildError, BuildSettings, Region, build
from hapticut.scenefile import Material

BONE = Material("bone", "rigid")


def ball(name="ball", radius=10.0, centre=(0.0, 0.0, 0.0)):
    return Region(name, *icosphere(radius, 1, centre), BONE)


def test_an_empty_mesh_is_named():
    with pytest.raises(BuildError, match=r"region 'empty': empty mesh"):
        build([Region("empty", np.zeros((0, 3)), np.zeros((0, 3), int), BONE)])


def test_nan_vertices_are_named():
    vertices, faces = icosphere(10.0, 1)
    vertices[5, 1] = np.nan
    with pytest.raises(BuildError, match=r"region 'ball': 1 vertices .* not finite .*vertex 5"):
        build([Region("ball", vertices, faces, BONE)])


def test_a_mesh_open_beyond_repair_is_named():
    vertices, faces = icosphere(10.0, 2)
    upper = faces[vertices[faces].mean(axis=1)[:, 2] > 0]  # a hemisphere: one big hole
    with pytest.raises(BuildError, match=r"region 'bowl': open mesh: \d+ boundary edges"):
        build([Region("bowl", vertices, upper, BONE)], settings=BuildSettings(max_hole_edges=10))


def test_zero_area_faces_everywhere_are_named():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], float)
    faces = np.array([[0, 1, 2], [1, 2, 3], [0, 2, 3], [0, 1, 3]])
    with pytest.raises(BuildError, match=r"region 'flat': all 4 faces have zero area"):
        build([Region("flat", vertices, faces, BONE)])


def test_a_flat_closed_surface_is_named():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
    faces = np.array([[0, 1, 2], [1, 3, 2], [0, 2, 1], [1, 2, 3]])
    with pytest.raises(BuildError, match=r"region 'sheet'"):
        build([Region("sheet", vertices, faces, BONE)])


def test_face_indices_out_of_range_are_named():
    vertices, faces = icosphere(10.0, 1)
    faces = faces.copy()
    faces[3, 2] = len(vertices) + 4
    with pytest.raises(BuildError, match=r"region 'ball': face 3 refers to a vertex"):
        build([Region("ball", vertices, faces, BONE)])


def test_two_intersecting_regions_are_named():
    with pytest.raises(BuildError, match=r"region 'left': its surface crosses region 'right'"):
        build([ball("left", centre=(-5, 0, 0)), ball("right", centre=(5, 0, 0))])


def test_regions_closer_than_the_envelope_are_named():
    # Two balls 0.05 mm apart (nearest vertices), meshed with a 0.4 mm envelope.
    left = ball("left", 10.0, (-10.05, 0, 0))
    right = ball("right", 10.0, (10.0, 0, 0))
    left_x = left.vertices[:, 0].max()
    right = Region("right", right.vertices + [left_x + 0.05 - right.vertices[:, 0].min(), 0, 0],
                   right.faces, BONE)  # fmt: skip
    with pytest.raises(BuildError, match=r"comes within .* mm of region"):
        build([left, right], settings=BuildSettings(accuracy_mm=1.0))


@pytest.mark.parametrize(
    ("name", "content"),
    [
        ("notes.obj", b"hello\nthis is not a mesh\n"),
        ("noise.ply", b"garbage that is not ply"),
        ("noise.stl", b"\x00\x01garbage" * 10),
        ("noise.off", b"nonsense"),
    ],
)
def test_a_file_that_is_not_a_mesh_is_named(tmp_path, name, content):
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(BuildError, match="not"):
        Region.from_file(path, BONE)


def test_nan_in_an_obj_file_is_kept_and_named(tmp_path):
    vertices, faces = icosphere(10.0, 1)
    vertices[2, 0] = np.nan
    path = write_obj(tmp_path / "nan.obj", vertices, faces)
    region = Region.from_file(path, BONE)
    with pytest.raises(BuildError, match=r"region 'nan': 1 vertices"):
        build([region])


def test_duplicate_region_names_and_bad_settings_are_named():
    with pytest.raises(BuildError, match="two regions have this name"):
        build([ball("a"), ball("a", centre=(30, 0, 0))])
    with pytest.raises(BuildError, match="settings.enclosure"):
        build([ball()], settings=BuildSettings(enclosure="sphere"))
    with pytest.raises(BuildError, match="settings.accuracy_mm"):
        build([ball()], settings=BuildSettings(accuracy_mm=-1.0))
    with pytest.raises(BuildError, match="no regions"):
        build([])


def test_the_mesh_command_reports_bad_input_and_writes_nothing(tmp_path):
    left = write_obj(tmp_path / "left.obj", *icosphere(10.0, 1, (-5, 0, 0)))
    right = write_obj(tmp_path / "right.obj", *icosphere(10.0, 1, (5, 0, 0)))
    before = set(tmp_path.iterdir())
    result = run_cli("mesh", left, right, "-o", tmp_path / "out.hapticut.json", "--vtu",
                     tmp_path / "out.vtu", "-q", cwd=tmp_path)  # fmt: skip
    assert result.returncode == 1
    assert "region 'left': its surface crosses region 'right'" in result.stderr
    assert set(tmp_path.iterdir()) == before  # no scene, no .vtu, no temporary file

    notes = tmp_path / "notes.obj"
    notes.write_text("not a mesh\n")
    result = run_cli("mesh", notes, "-o", tmp_path / "out.hapticut.json", "-q", cwd=tmp_path)
    assert result.returncode == 1 and "region 'notes'" in result.stderr
    assert not (tmp_path / "out.hapticut.json").exists()
