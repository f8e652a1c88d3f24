"""hapticut.cut_surface (pure numpy, loaded by the Blender add-on) against the engine: its tet
locator agrees with Space.locate, and the cut surface of a real servo stroke through the
finger (skin, flesh, onto the bone, across) lies in cuttable material only."""

import json
from pathlib import Path

import numpy as np
import pytest
from hapticut import cut_surface
from hapticut.engine import load_space
from hapticut.recording import read_recording
from hapticut.servo_client import ServoProcess

FINGER = Path(__file__).resolve().parents[2] / "examples" / "finger.hapticut.msgpack"
CUTTABLE = {"drag", "viscous", "membrane"}
# Down from above into the bone (its surface is 3.5 mm from the axis: the skin, a membrane,
# gives way at 1 N a point, a 10 mm lag at 0.1 N/mm), then across
# and out of the finger (mm, s).
STROKE = [(0.0, (0, 0, 20)), (0.8, (0, 0, -3.0)), (1.8, (0, 22, -3.0))]


@pytest.fixture(scope="module")
def finger():
    return load_space(FINGER)


def test_the_locator_agrees_with_the_engine(finger):
    scene, space = finger
    points = np.random.default_rng(7).uniform(
        scene.vertices.min(0) - 5, scene.vertices.max(0) + 5, (20000, 3)
    )
    mine = cut_surface.TetLocator(scene.vertices, scene.tets).locate(points)
    theirs = space.locate(points)
    assert np.array_equal(mine >= 0, theirs >= 0)
    inside = theirs >= 0
    assert np.array_equal(scene.tet_materials[mine[inside]], scene.tet_materials[theirs[inside]])
    assert (~inside).sum() > 100  # Some points were outside the mesh.


def stroke_poses(rate_Hz: float) -> list:
    times = np.arange(0, STROKE[-1][0] + 1e-9, 1 / rate_Hz)
    keys_t = [t for t, _ in STROKE]
    xyz = np.stack([np.interp(times, keys_t, [p[i] for _, p in STROKE]) for i in range(3)], 1)
    return [[float(t), *map(float, p), 1.0, 0.0, 0.0, 0.0] for t, p in zip(times, xyz, strict=True)]


@pytest.fixture(scope="module")
def stroke_recording(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cut")
    record = folder / "stroke.rec"
    stroke_recording_to(record, folder)
    return read_recording(record)


def stroke_recording_to(record: Path, folder: Path) -> None:
    """The servo's recording of STROKE through the finger, at record."""
    path = folder / "stroke.path.json"
    path.write_text(json.dumps({"poses": stroke_poses(1000.0)}))
    servo = ServoProcess(
        [
            str(FINGER),
            "--device",
            f"scalpel=sim:{path},hand=0,hold_s=0",
            "--as-fast-as-possible",
            "--exit-when-done",
            "--engage",
            "--quiet",
            "--record",
            str(record),
        ],
        control=False,
    ).start()
    assert servo.wait(120) == 0, servo.stderr_lines


def test_the_cut_surface_of_a_servo_stroke_is_in_cuttable_material_only(finger, stroke_recording):
    scene, space = finger
    rec = stroke_recording
    blade = rec.blade("scalpel")
    times = rec.ticks["time_s"] - rec.ticks["time_s"][0]
    models = [m.model for m in scene.materials]
    surface = cut_surface.cut_surface(
        blade["q"],
        blade["state"],
        times,
        24.0,
        1,
        scene.vertices,
        scene.tets,
        scene.tet_materials,
        models,
    )
    assert len(surface.faces) > 50
    corners = surface.vertices[surface.faces]
    centres = corners.mean(axis=1)
    midpoints = (corners + np.roll(corners, 1, axis=1)).reshape(-1, 3) / 2
    # A point on a face between a cuttable tet and another lies in both within the tolerance:
    # the engine's locate may name either, the cut surface's own locator names the cuttable
    # one, and such a point counts as cut.
    locator = cut_surface.TetLocator(scene.vertices, scene.tets)
    for points in (centres, midpoints, surface.vertices):
        tets = space.locate(points)
        assert np.all(tets >= 0)
        engine_models = np.array([models[m] for m in scene.tet_materials[tets]])
        tied = ~np.isin(engine_models, list(CUTTABLE))
        own = locator.locate(points[tied])
        assert np.all(own >= 0)
        found = set(engine_models[~tied]) | {models[m] for m in scene.tet_materials[own]}
        assert found <= CUTTABLE, found
    # The cut tets are the tets the cutting points were in at the rows, all cuttable.
    rows = surface.row_ticks
    held = locator.locate(blade["q"][rows][surface.cutting])
    assert np.array_equal(surface.cut_tets, np.unique(held))
    assert {models[m] for m in scene.tet_materials[surface.cut_tets]} <= CUTTABLE
    # Through the flesh; the frames run from the first to the last frame.
    found = {models[m] for m in scene.tet_materials[space.locate(centres)]}
    assert "drag" in found
    assert surface.face_frames.min() >= 1
    assert surface.face_frames.max() <= 1 + int(np.ceil(times[-1] * 24))
    # The device points went into the bone (and no face is there: checked above).
    assert blade["p"][:, :, 2].min() == pytest.approx(-3.0)
    in_bone = scene.tet_materials[np.maximum(space.locate(blade["p"].reshape(-1, 3)), 0)]
    assert np.any(np.array(models)[in_bone] == "rigid")


def test_points_that_are_held_or_in_air_or_rigid_do_not_cut(finger):
    scene, _ = finger
    models = [m.model for m in scene.materials]
    locator = cut_surface.TetLocator(scene.vertices, scene.tets)
    q = np.array([[[-20, 0, 0], [-20, 0, 5.0], [-20, 0, 8.0], [-20, 0, 14], [-20, 0, 5.0]]])
    states = np.array([[0, 0, 0, 0, 1]])  # The last one is held on a face.
    cuts = cut_surface.cuttable_points(q, states, locator, scene.tet_materials, models)
    assert cuts.tolist() == [[False, True, True, False, False]]


def test_a_quad_needs_all_four_corners_cutting():
    q = np.zeros((3, 3, 3))
    q[:, :, 0] = np.arange(3)[None, :]
    q[:, :, 1] = np.arange(3)[:, None]
    states = np.zeros((3, 3), np.uint8)
    cutting = np.ones((3, 3), bool)
    cutting[2, 2] = False
    surface = cut_surface.sweep(q, states, np.arange(3), np.array([1.0, 2.0, 3.0]), cutting)
    assert len(surface.faces) == 2 * 3  # Three of the four quads.
    assert sorted(set(surface.face_frames.tolist())) == [2, 3]
    states[1, 0] = 1  # Point 0 left its tet at row 1: its quads go.
    surface = cut_surface.sweep(q, states, np.arange(3), np.array([1.0, 2.0, 3.0]), cutting)
    assert len(surface.faces) == 2 * 1


def test_the_preview_holds_the_tets_the_bake_locates_in(finger):
    from hapticut.preview import preview_arrays

    scene, _ = finger
    arrays = preview_arrays(scene)
    assert np.array_equal(arrays["tets"], scene.tets)
    assert np.array_equal(arrays["tet_materials"], scene.tet_materials)
    assert np.array_equal(arrays["tet_vertices"], scene.vertices)
    assert arrays["tets"].dtype == np.int32


def test_the_cut_surface_command_writes_what_the_function_computes(finger, tmp_path):
    """``hapticut cut-surface`` (the bake's child) on a servo recording and the scene's
    preview: the file holds each blade's surface as cut_surface computes it."""
    from hapticut.cli import main
    from hapticut.preview import write_preview

    scene, _ = finger
    record = tmp_path / "stroke.rec"
    stroke_recording_to(record, tmp_path)
    preview = tmp_path / "finger.npz"
    write_preview(scene, preview)
    out = tmp_path / "cuts.npz"
    args = [str(record), str(preview), "--out", str(out), "--fps", "24", "--ticks", "900"]
    assert main(["cut-surface", *args]) == 0
    surfaces = cut_surface.read_cut_surfaces(out)
    assert list(surfaces) == ["scalpel"]
    rec = read_recording(record)
    expected = cut_surface.recording_cut_surfaces(
        rec, cut_surface.preview_tets(preview), 24.0, 1, 2, 900
    )["scalpel"]
    got = surfaces["scalpel"]
    assert len(got.faces) > 20
    for field in ("vertices", "faces", "face_frames", "cutting", "row_ticks", "cut_tets"):
        assert np.array_equal(getattr(got, field), getattr(expected, field)), field
    # Fewer ticks, fewer rows: the bake cuts only what it keys.
    assert got.row_ticks.max() < 900 < len(rec)


def test_the_bakes_cut_tets_are_the_engines(finger, stroke_recording, tmp_path):
    """One source: the surface a bake renders is cut where the engine cut (the recording's
    cut order), and its cut tets are the engine's set at the last tick it keys."""
    from hapticut.preview import write_preview

    scene, _ = finger
    rec = stroke_recording
    preview = tmp_path / "finger.npz"
    write_preview(scene, preview)
    tets = cut_surface.preview_tets(preview)
    ticks = len(rec)
    surface = cut_surface.recording_cut_surfaces(rec, tets, 24.0, 1, 2, ticks)["scalpel"]
    engine = rec.cut_order()
    assert len(engine) > 20 and len(surface.faces) > 20
    assert np.array_equal(surface.cut_tets, np.unique(engine))
    # Every point that cuts at a row is in a tet the engine cut.
    q = rec.blade("scalpel")["q"][surface.row_ticks]
    locator = cut_surface.TetLocator(tets["vertices"], tets["tets"])
    found = locator.locate(q[surface.cutting])
    assert np.isin(found, engine).all()
    # Halfway through the keys, the engine's set then.
    half = int(np.argmax(rec.cut_blocks["total"] >= len(engine) // 2)) + 1
    early = cut_surface.recording_cut_surfaces(rec, tets, 24.0, 1, 2, half)["scalpel"]
    assert np.array_equal(early.cut_tets, np.unique(rec.cut_order(half - 1)))
    assert 0 < len(early.cut_tets) < len(surface.cut_tets)


@pytest.mark.parametrize(
    ("extra", "problem"),
    [
        (["--fps", "0"], "--fps must be a positive number"),
        (["--fps", "nan"], "--fps must be a positive number"),
        (["--fps", "24", "--substeps", "0"], "--substeps must be at least 1"),
        (["--fps", "24", "--ticks", "1"], "--ticks must be at least 2"),
    ],
)
def test_the_cut_surface_command_names_a_bad_number(tmp_path, capsys, extra, problem):
    from hapticut.cli import main

    out = tmp_path / "cuts.npz"
    assert main(["cut-surface", "r.rec", "p.npz", "--out", str(out), *extra]) == 2
    assert problem in capsys.readouterr().err
    assert not out.exists()


def test_the_cut_surface_command_names_a_file_it_cannot_read(tmp_path, capsys):
    from hapticut.cli import main

    missing = tmp_path / "missing.rec"
    out = tmp_path / "cuts.npz"
    assert main(["cut-surface", str(missing), "p.npz", "--out", str(out), "--fps", "24"]) == 1
    assert str(missing) in capsys.readouterr().err
    assert not out.exists()


def test_a_bake_keys_the_record_nearest_each_frame_within_the_range():
    times = np.arange(1001) / 1000.0  # 1 s at 1 kHz.
    frames, nearest = cut_surface.frame_ticks(times, 24.0, 10)
    assert frames.tolist() == list(range(10, 35))
    assert nearest.tolist() == [round(k * 1000 / 24) for k in range(25)]
    frames, nearest = cut_surface.frame_ticks(times, 24.0, 10, frame_end=19)
    assert frames.tolist() == list(range(10, 20)) and len(nearest) == 10
    assert cut_surface.frame_ticks(times, 24.0, 10, frame_end=9)[0].size == 0
    # The cut surface's rows are the same ticks, twice a frame with two substeps.
    rows, row_frames = cut_surface.row_ticks_at_frames(times, 24.0, 10, substeps=2)
    assert len(rows) == 49
    assert rows[::2].tolist() == cut_surface.frame_ticks(times, 24.0, 10)[1].tolist()
    assert row_frames[2] == pytest.approx(10 + 0.042 * 24)
