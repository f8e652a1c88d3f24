"""`hapticut build-request`, `preview` and `convert`: the add-on's side of the toolkit, run as
the add-on runs them (child processes), without Blender."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from build_test_support import EXAMPLES, icosphere, run_cli
from hapticut.build_request import RequestError, input_problems, read_request
from hapticut.engine import space_from_scene
from hapticut.preview import preview_arrays
from hapticut.scenebuild import Region
from hapticut.scenefile import Material, load_scene


def write_request(folder, regions, blades=(), settings=None, **extra):
    entries = []
    for i, (name, (vertices, faces), material) in enumerate(regions):
        np.savez(folder / f"region-{i}.npz", vertices=vertices, faces=faces)
        entries.append({"name": name, "mesh": f"region-{i}.npz", "material": material})
    request = {"format": "hapticut.build-request", "version": 1, "regions": entries,
               "blades": list(blades), "settings": settings or {}, **extra}  # fmt: skip
    path = folder / "request.json"
    path.write_text(json.dumps(request))
    return path


# Flesh whose cut tets keep a tenth of its drag (the add-on's "Once cut: Weaker").
FLESH = {"name": "flesh", "model": "drag", "drag_distance_mm": 0.5,
         "cut": {"becomes": "weaker", "factor": 0.1}}  # fmt: skip


def nested_spheres(folder):
    return write_request(
        folder,
        [("Flesh", icosphere(20.0, 2), FLESH),
         ("Bone", icosphere(8.0, 1), {"name": "bone", "model": "rigid"})],
        blades=[{"name": "Knife", "start_mm": [-10, 0, 0], "end_mm": [10, 0, 0], "points": 8,
                 "device": "sim"}],
        settings={"enclosure": "cube", "accuracy_mm": 1.0},
    )  # fmt: skip


def test_build_request_streams_progress_and_writes_the_build_whole(tmp_path):
    request = nested_spheres(tmp_path)
    out = tmp_path / "work" / "build"
    result = run_cli("build-request", request, "--out", out, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    events = [json.loads(line) for line in result.stdout.splitlines()]
    progress = [e for e in events if e["event"] == "progress"]
    fractions = [e["fraction"] for e in progress]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0
    stages = list(dict.fromkeys(e["stage"] for e in progress))
    assert stages == ["validate", "repair", "simplify", "check", "sizing", "tetrahedralize",
                      "label", "report", "done", "write"]  # fmt: skip
    assert events[-1]["event"] == "done" and events[-1]["tets"] > 100
    assert sorted(os.listdir(out)) == ["preview.npz", "report.json", "scene.hapticut.msgpack"]
    assert os.listdir(out.parent) == ["build"]  # No staging directory left.
    scene = load_scene(out / "scene.hapticut.msgpack")
    # The flesh's cut variant follows the regions' materials, in no region: every tet starts
    # uncut, and the servo loads the scene as it is.
    assert [m.name for m in scene.materials] == ["air", "flesh", "bone", "flesh_cut"]
    flesh, bone, flesh_cut = scene.materials[1:]
    assert (flesh.cut_to, bone.cut_to, flesh_cut.cut_to) == ("flesh_cut", "", "")
    assert (flesh_cut.model, flesh_cut.drag_distance_mm) == ("drag", pytest.approx(0.05))
    assert set(np.unique(scene.tet_materials)) == {0, 1, 2}
    space_from_scene(scene)
    assert scene.blades[0].name == "Knife" and scene.blades[0].points == 8
    assert (scene.blades[0].coupling, scene.blades[0].orientation) == ("rigid", "free")
    assert scene.metadata["blade_devices"] == {"Knife": "sim"}
    report = json.loads((out / "report.json").read_text())
    assert report["tets"] == len(scene.tets) and set(report["deviation_mm"]) == {"Flesh", "Bone"}
    # A second build replaces the first whole.
    again = run_cli("build-request", request, "--out", out, "--progress", "none", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert [json.loads(x)["event"] for x in again.stdout.splitlines()] == ["done"]


def test_build_request_names_the_region_of_a_builder_error(tmp_path):
    # Two spheres crossing each other: the builder refuses, naming one.
    a, b = icosphere(10.0, 2), icosphere(10.0, 2)
    b = (b[0] + [8.0, 0, 0], b[1])
    request = write_request(tmp_path, [("Left", a, {"name": "l", "model": "rigid"}),
                                       ("Right", b, {"name": "r", "model": "rigid"})])  # fmt: skip
    result = run_cli("build-request", request, "--out", tmp_path / "build")
    assert result.returncode == 1
    error = json.loads(result.stdout.splitlines()[-1])
    assert error["event"] == "error" and error["object"] in ("Left", "Right")
    assert "crosses region" in error["problem"]
    assert result.stderr.strip().splitlines()[-1].startswith("hapticut build-request: ")
    assert not (tmp_path / "build").exists()


def test_check_lists_open_self_intersecting_and_flat_regions(tmp_path):
    vertices, faces = icosphere(10.0, 1)
    flat = (vertices * [1, 1, 0], faces)
    crossing_vertices = np.vstack([vertices, vertices + [5.0, 0, 0]])
    crossing = (crossing_vertices, np.vstack([faces, faces + len(vertices)]))
    request = write_request(tmp_path, [
        ("Open", (vertices, faces[1:]), {"name": "a", "model": "rigid"}),
        ("Crossing", crossing, {"name": "a", "model": "rigid"}),
        ("Flat", flat, {"name": "a", "model": "rigid"}),
        ("Good", (vertices + [40.0, 0, 0], faces), {"name": "a", "model": "rigid"}),
    ])  # fmt: skip
    result = run_cli("build-request", request, "--check")
    assert result.returncode == 1
    problems = [json.loads(x) for x in result.stdout.splitlines()]
    found = {
        (p["object"], p["problem"].split(" (")[0]) for p in problems if p["event"] == "problem"
    }
    assert ("Open", "the mesh is open") in found
    assert ("Crossing", "the mesh intersects itself") in found
    assert ("Flat", "the region has no volume") in found
    assert not [name for name, _ in found if name == "Good"]
    assert problems[-1] == {"event": "checked", "problems": len(found)}


def check_events(tmp_path, regions):
    result = run_cli("build-request", write_request(tmp_path, regions), "--check")
    return result, [json.loads(line) for line in result.stdout.splitlines()]


def test_check_finds_regions_crossing_as_the_build_does(tmp_path):
    # What Tetrahedralize refuses after repairing and simplifying, the check finds alone.
    a, b = icosphere(10.0, 2), icosphere(10.0, 2)
    b = (b[0] + [8.0, 0, 0], b[1])
    rigid = {"name": "r", "model": "rigid"}
    result, events = check_events(tmp_path, [("Left", a, rigid), ("Right", b, rigid)])
    assert result.returncode == 1, result.stderr
    (problem,) = [e for e in events if e["event"] == "problem"]
    assert {problem["object"], problem["problem"].split("'")[1]} == {"Left", "Right"}
    assert "crosses region" in problem["problem"]
    assert events[-1] == {"event": "checked", "problems": 1}
    # The progress names the build's steps and the region being worked on.
    progress = [e for e in events if e["event"] == "progress"]
    assert list(dict.fromkeys(e["stage"] for e in progress)) == [
        "validate", "repair", "simplify", "check"
    ]  # fmt: skip
    messages = [e["message"] for e in progress]
    assert {"stage": "validate", "message": "checking Left (320 faces)"}.items() <= next(
        e for e in progress if e["message"] == "checking Left (320 faces)"
    ).items()
    assert "repairing Left (320 faces)" in messages and "simplifying Right (320 faces)" in messages
    assert "checking that regions do not cross (640 faces)" in messages


def test_check_finds_a_region_lying_on_a_copy_of_itself(tmp_path):
    ball = icosphere(10.0, 2)
    rigid = {"name": "r", "model": "rigid"}
    result, events = check_events(tmp_path, [("Cow", ball, rigid), ("Cow.001", ball, rigid)])
    assert result.returncode == 1, result.stderr
    (problem,) = [e for e in events if e["event"] == "problem"]
    other = "Cow.001" if problem["object"] == "Cow" else "Cow"
    assert problem["object"] in ("Cow", "Cow.001") and f"region {other!r}" in problem["problem"]


def test_check_passes_nested_regions_and_ends_its_progress(tmp_path):
    result = run_cli("build-request", nested_spheres(tmp_path), "--check")
    assert result.returncode == 0, result.stderr
    events = [json.loads(line) for line in result.stdout.splitlines()]
    assert events[-1] == {"event": "checked", "problems": 0}
    progress = [e for e in events if e["event"] == "progress"]
    assert progress[-1]["stage"] == "done" and progress[-1]["fraction"] == 1.0
    fractions = [e["fraction"] for e in progress]
    assert fractions == sorted(fractions)


def test_progress_names_each_meshing_when_the_build_meshes_again(monkeypatch):
    """An envelope three times the accuracy lets fTetWild stray (test_scene_build.py): the
    builder meshes again, and every progress line of a later meshing names its step and
    which meshing it is, with the reason once."""
    import io

    from hapticut.commands.build_request import JsonLines
    from hapticut.scenebuild import BuildSettings, build, builder

    monkeypatch.setattr(builder, "ENVELOPE_SHARE", 3.0)
    stream = io.StringIO()
    region = Region("ball", *icosphere(10.0, 2), Material("bone", "rigid"))
    build([region], settings=BuildSettings(accuracy_mm=0.3), progress=JsonLines(stream))
    events = [json.loads(line) for line in stream.getvalue().splitlines()]
    for line in stream.getvalue().splitlines()[-12:]:
        print(line)
    again = [e for e in events if e.get("meshing", 1) > 1]
    assert again, "the build should have meshed again"
    assert {e["meshings"] for e in again} == {builder.MESHING_ATTEMPTS}
    first = again[0]
    assert (first["stage"], first["meshing"]) == ("tetrahedralize", 2)
    assert first["message"].startswith("meshing again with a 0.45 mm envelope")
    assert {"tetrahedralize", "label", "report"} <= {e["stage"] for e in again}
    # Each line of the first meshing precedes the second's; the end is "done".
    assert all(e.get("meshing", 1) == 1 for e in events[: events.index(first)])
    assert events[-1]["stage"] == "done" and events[-1]["fraction"] == 1.0


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"format": "x"}, "format"),
        ({"version": 2}, "version"),
        ({"settings": {"voxels": 3}}, "settings/voxels"),
        ({"scene_file": "../x.hapticut.json"}, "scene_file"),
        ({"blades": [{"name": "k", "start_mm": [0, 0], "end_mm": [1, 0, 0]}]}, "blades/0/start_mm"),
        ({"blades": [{"name": "k", "start_mm": [0, 0, 0], "end_mm": [1, 0, float("nan")]}]},
         "blades/0/end_mm"),
        ({"blades": [{"name": "k", "start_mm": [0, 0, 0], "end_mm": [1, 0, 0],
                      "coupling": "hinged"}]}, "blades/0/coupling"),
        ({"blades": [{"name": "k", "start_mm": [0, 0, 0], "end_mm": [1, 0, 0],
                      "orientation": 1}]}, "blades/0/orientation"),
    ],
)  # fmt: skip
def test_a_bad_request_names_its_field(tmp_path, change, field):
    path = nested_spheres(tmp_path)
    data = json.loads(path.read_text())
    data.update(change)
    path.write_text(json.dumps(data))
    with pytest.raises(RequestError) as error:
        read_request(path)
    assert error.value.field == field
    result = run_cli("build-request", path, "--out", tmp_path / "out")
    assert result.returncode == 2 and f"request {field}: " in result.stderr


def test_a_missing_mesh_and_a_bad_material_are_named(tmp_path):
    path = nested_spheres(tmp_path)
    os.unlink(tmp_path / "region-1.npz")
    with pytest.raises(RequestError, match="regions/1/mesh"):
        read_request(path)
    path = nested_spheres(tmp_path)
    data = json.loads(path.read_text())
    data["regions"][0]["material"]["stiffness"] = 3
    path.write_text(json.dumps(data))
    with pytest.raises(RequestError, match="regions/0/material/stiffness: not a material"):
        read_request(path)


def with_cuts(tmp_path, flesh_cut, bone_cut=None):
    """nested_spheres with the flesh's cut entry replaced (None: none) and one for the bone."""
    path = nested_spheres(tmp_path)
    data = json.loads(path.read_text())
    flesh, bone = (region["material"] for region in data["regions"])
    for material, cut in ((flesh, flesh_cut), (bone, bone_cut)):
        material.pop("cut", None)
        if cut is not None:
            material["cut"] = cut
    path.write_text(json.dumps(data))
    return path


@pytest.mark.parametrize(
    ("model", "parameters", "factor", "scaled"),
    [
        ("drag", {"drag_distance_mm": 2.0}, 0.1, {"drag_distance_mm": 0.2}),
        ("viscous", {"viscosity_N_s_per_mm": 0.002, "max_lag_mm": 10.0}, 0.5,
         {"viscosity_N_s_per_mm": 0.001, "max_lag_mm": 5.0}),
        ("membrane", {"break_force_N": 0.3}, 1.0, {"break_force_N": 0.3}),
    ],
)  # fmt: skip
def test_a_weaker_cut_variant_scales_every_parameter_of_its_model(
    tmp_path, model, parameters, factor, scaled
):
    material = {"name": "tissue", "model": model, **parameters}
    path = with_cuts(tmp_path, {"becomes": "weaker", "factor": factor})
    data = json.loads(path.read_text())
    data["regions"][0]["material"] = {**material, "cut": {"becomes": "weaker", "factor": factor}}
    path.write_text(json.dumps(data))
    region = read_request(path).regions[0]
    assert region.material == Material(cut_to="tissue_cut", **material)
    assert region.cut_material == Material("tissue_cut", model, **scaled)


def test_free_once_cut_names_the_air_and_no_cut_leaves_cut_to_unset(tmp_path):
    flesh, bone = read_request(with_cuts(tmp_path, {"becomes": "free"})).regions
    assert (flesh.material.cut_to, flesh.cut_material) == ("air", None)
    assert (bone.material.cut_to, bone.cut_material) == ("", None)
    flesh, _ = read_request(with_cuts(tmp_path, None)).regions
    assert (flesh.material.cut_to, flesh.cut_material) == ("", None)


@pytest.mark.parametrize(
    ("flesh_cut", "bone_cut", "field", "reason"),
    [
        ({"becomes": "weaker", "factor": 1.5}, None, "regions/0/material/cut/factor",
         "must be in (0, 1], not 1.5"),
        ({"becomes": "weaker", "factor": 0}, None, "regions/0/material/cut/factor",
         '0 leaves no resistance: "becomes": "free"'),
        ({"becomes": "weaker", "factor": "a tenth"}, None, "regions/0/material/cut/factor",
         "must be a finite number"),
        ({"becomes": "weaker"}, None, "regions/0/material/cut/factor", "required field missing"),
        ({"becomes": "free", "factor": 0.1}, None, "regions/0/material/cut/factor",
         "not a setting of a free cut variant"),
        ({"becomes": "gone"}, None, "regions/0/material/cut/becomes",
         "must be one of free, weaker, not 'gone'"),
        ("free", None, "regions/0/material/cut", "must be an object"),
        (None, {"becomes": "free"}, "regions/1/material/cut",
         "material 'bone' is rigid: a blade never cuts it, so it takes no cut variant"),
    ],
)  # fmt: skip
def test_a_bad_cut_variant_names_its_field(tmp_path, flesh_cut, bone_cut, field, reason):
    path = with_cuts(tmp_path, flesh_cut, bone_cut)
    with pytest.raises(RequestError) as error:
        read_request(path)
    assert error.value.field == field and reason in error.value.reason
    result = run_cli("build-request", path, "--check")
    assert result.returncode == 2 and f"request {field}: " in result.stderr


def test_check_names_the_region_whose_cut_variant_the_scene_cannot_hold(tmp_path):
    # Two regions of one material cut to different strengths, and a material named as the
    # flesh's cut variant would be: Check Scene finds both before anything is meshed.
    ball = icosphere(5.0, 1)
    far = (ball[0] + [30.0, 0, 0], ball[1])
    weaker = {"name": "flesh", "model": "drag", "drag_distance_mm": 0.5,
              "cut": {"becomes": "weaker", "factor": 0.1}}  # fmt: skip
    cases = [
        ({**weaker, "cut": {"becomes": "weaker", "factor": 0.2}},
         "material 'flesh' is given two different cut variants"),
        ({"name": "flesh_cut", "model": "viscous", "viscosity_N_s_per_mm": 0.001},
         "the cut variant of material 'flesh' would be named 'flesh_cut', which another "
         "material has: rename that material"),
    ]  # fmt: skip
    for other, problem in cases:
        result, events = check_events(tmp_path, [("A", ball, weaker), ("B", far, other)])
        assert result.returncode == 1, result.stderr
        (found,) = [e for e in events if e["event"] == "problem"]
        assert found["object"] in ("A", "B") and found["problem"].startswith(problem), found


def test_input_problems_pass_a_closed_sphere():
    region = Region("Ball", *icosphere(10.0, 2), Material("a", "rigid"))
    assert input_problems([region]) == []


def test_preview_holds_each_material_regions_closed_surface():
    scene = load_scene(EXAMPLES / "finger.hapticut.msgpack")
    preview = preview_arrays(scene)
    assert list(preview["material_names"]) == [m.name for m in scene.materials]
    for index in range(1, len(scene.materials)):
        faces = preview["faces"][preview["face_materials"] == index]
        assert len(faces) > 0
        edges = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        _, uses = np.unique(edges, axis=0, return_counts=True)
        assert set(uses.tolist()) == {2}, scene.materials[index].name  # Closed surfaces.
    assert 0 not in preview["face_materials"]  # Air has no surface of its own.


def test_preview_and_convert_commands(tmp_path):
    source = EXAMPLES / "finger.hapticut.msgpack"
    result = run_cli("preview", source, "--out", tmp_path / "p.npz")
    assert result.returncode == 0, result.stderr
    with np.load(tmp_path / "p.npz", allow_pickle=False) as data:
        assert json.loads(str(data["report_json"]))["tets"] == len(load_scene(source).tets)
    converted = tmp_path / "finger.hapticut.json"
    assert run_cli("convert", source, converted).returncode == 0
    assert load_scene(converted) == load_scene(source)
    broken = tmp_path / "broken.hapticut.json"
    broken.write_text("{}")
    for args in (("preview", broken, "--out", tmp_path / "q.npz"), ("convert", broken, converted)):
        result = run_cli(*args)
        assert result.returncode == 1 and str(broken) in result.stderr
    assert not (tmp_path / "q.npz").exists()


def test_version():
    result = run_cli("--version")
    assert result.returncode == 0 and result.stdout.startswith("hapticut ")
