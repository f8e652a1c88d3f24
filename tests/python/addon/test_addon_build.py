"""The finger built through the add-on: preview, report, unchanged rebuild, export, reload
with the toolkit, import, and the properties surviving a save and reopen."""

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import blender_scene
import bpy
import pytest

HERE = Path(__file__).resolve().parent
# Points inside each layer of the finger (mm): bone axis, flesh, skin, outside.
PROBES = {
    "bone": (-20, 0, 0),
    "soft_tissue": (-20, 0, 6.0),
    "skin": (-20, 0, 8.3),
    "air": (-20, 0, 14),
}


def run_build(scene, timeout_s: float = 900.0) -> dict:
    """Tetrahedralize through the operator, then call what the timer would call until the
    build ends; the figures of the run."""
    from addon.authoring import building

    started = time.perf_counter()
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    longest_poll = 0.0
    stages = []
    while True:
        began = time.perf_counter()
        going = building.update(scene.name)
        longest_poll = max(longest_poll, time.perf_counter() - began)
        if scene.hapticut.stage and (not stages or stages[-1] != scene.hapticut.stage):
            stages.append(scene.hapticut.stage)
        if not going:
            break
        assert time.perf_counter() - started < timeout_s
        time.sleep(0.1)
    return {"seconds": time.perf_counter() - started, "longest_poll_s": longest_poll,
            "stages": stages}  # fmt: skip


def probe(path: str) -> dict:
    points = json.dumps([PROBES[name] for name in PROBES])
    done = subprocess.run(
        [sys.executable, str(HERE / "toolkit_probe.py"), path, points],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    return json.loads(done.stdout)


@pytest.fixture(scope="module")
def built(addon, tmp_path_factory):
    work = tmp_path_factory.mktemp("finger")
    scene = blender_scene.finger_scene(str(work))
    # Once cut, the flesh keeps a tenth of its drag and the skin no longer resists.
    flesh, skin = bpy.data.objects["Flesh"].hapticut, bpy.data.objects["Skin"].hapticut
    flesh.cut_becomes, flesh.cut_factor = "WEAKER", 0.1
    skin.cut_becomes = "FREE"
    figures = run_build(scene)
    print(
        f"\nfinger (accuracy {blender_scene.TEST_ACCURACY_MM} mm): Tetrahedralize to preview "
        f"{figures['seconds']:.1f} s, longest timer call {1000 * figures['longest_poll_s']:.1f} ms"
    )
    return scene, work, figures


def test_the_build_makes_a_preview_per_material_region(built):
    scene, work, figures = built
    assert scene.hapticut.error == ""
    assert scene.hapticut.status.startswith("built")
    preview = bpy.data.collections["Hapticut Preview"]
    by_material = {o["hapticut_material"]: o for o in preview.objects}
    assert set(by_material) == {"skin", "soft_tissue", "bone"}
    for obj in by_material.values():
        assert len(obj.data.polygons) > 20
        assert obj.data.materials[0].name.startswith("Hapticut")
    # Coloured by material model: skin (membrane) and bone (rigid) differ.
    assert tuple(by_material["skin"].color) != tuple(by_material["bone"].color)
    # The bone's surface lies within the finger, about 3.5 mm from its axis (mm = units here).
    bone = by_material["bone"].data
    radii = [(v.co.y**2 + v.co.z**2) ** 0.5 for v in bone.vertices]
    assert 2.0 < max(radii) < 5.0
    # The progress went through the builder's stages in order.
    assert figures["stages"][-1] == "done"
    assert "tetrahedralize" in figures["stages"]


def test_the_report_reaches_the_panel(built):
    from addon.authoring.report_text import report_lines

    scene, _, _ = built
    report = json.loads(scene.hapticut.report_json)
    assert report["tets"] > 1000
    assert set(report["deviation_mm"]) == {"Skin", "Flesh", "Bone"}
    assert all(0 < d < 3 * blender_scene.TEST_ACCURACY_MM for d in report["deviation_mm"].values())
    assert set(report["timings_s"]) >= {"repair", "tetrahedralize", "label", "total"}
    lines = report_lines(report)
    assert lines[0].startswith(f"{report['tets']} tets")
    meshed_again = len(report["meshing_attempts"]) > 1
    assert any("to hold the accuracy" in line for line in lines) == meshed_again
    assert any("tets per edge" in line for line in lines)


def test_an_unchanged_scene_is_not_rebuilt_and_an_edit_is(built):
    from addon.authoring import build_job

    scene, _, _ = built
    old_hash = scene.hapticut.build_hash
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    assert build_job.running(scene.name) is None
    assert scene.hapticut.status == "unchanged: not rebuilt"
    # An edit (a new material for the flesh) starts a build; cancel it, the old one stays.
    bpy.data.objects["Flesh"].hapticut.material_preset = "fat"
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    assert build_job.running(scene.name) is not None
    assert bpy.ops.hapticut.cancel_build() == {"FINISHED"}
    bpy.data.objects["Flesh"].hapticut.material_preset = "soft_tissue"
    assert scene.hapticut.build_hash == old_hash


@pytest.mark.parametrize("suffix", [".hapticut.msgpack", ".hapticut.json"])
def test_export_and_reload_with_the_toolkit(built, tmp_path, suffix):
    scene, _, _ = built
    path = str(tmp_path / f"finger{suffix}")
    assert bpy.ops.hapticut.export_scene(filepath=path) == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    contents = probe(path)
    assert contents["materials"] == {
        "air": "free", "skin": "membrane", "soft_tissue": "drag", "bone": "rigid",
        "soft_tissue_cut": "drag",
    }  # fmt: skip
    # The panel's Once cut: the servo reads each material's cut variant from the scene.
    assert contents["cut_to"] == {"skin": "air", "soft_tissue": "soft_tissue_cut"}
    assert contents["drag_distance_mm"] == {
        "soft_tissue": pytest.approx(2.0), "soft_tissue_cut": pytest.approx(0.2)
    }  # fmt: skip
    # Every tet starts uncut: the variant fills none.
    filled = {k: v for k, v in contents["tets_per_material"].items() if v > 0}
    assert set(filled) == set(contents["materials"]) - {"soft_tissue_cut"}
    # Each layer's tets hold that layer's material.
    assert contents["at"] == list(PROBES)
    assert contents["blades"] == ["Knife"]
    assert contents["blade_devices"] == {"Knife": "sim"}


def test_import_shows_a_scene_made_elsewhere(built):
    scene, _, _ = built
    example = str(blender_scene.REPO / "examples" / "finger.hapticut.msgpack")
    assert bpy.ops.hapticut.import_scene(filepath=example) == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    objects = bpy.data.collections["Hapticut Preview"].objects
    names = {o["hapticut_material"] for o in objects}
    assert names == {"skin", "flesh", "bone"}  # The example's own material names.
    # The build's preview was replaced, not added to: its meshes are gone too.
    assert len(objects) == 3
    assert "Hapticut soft_tissue" not in bpy.data.meshes
    assert json.loads(scene.hapticut.report_json)["tets"] > 1000


def test_import_of_a_broken_file_reports_the_toolkit_error(built, tmp_path):
    broken = tmp_path / "broken.hapticut.json"
    broken.write_text('{"format": "hapticut.scene", "version": 1}')
    with pytest.raises(RuntimeError, match="hapticut preview"):
        bpy.ops.hapticut.import_scene(filepath=str(broken))
        bpy.ops.hapticut.wait()
    assert "hapticut preview" in bpy.context.scene.hapticut.error


def test_properties_survive_save_and_reopen(built, tmp_path):
    scene, _, _ = built
    knife = bpy.data.objects["Knife"]
    knife.hapticut.device = "spacemouse"
    flesh = bpy.data.objects["Flesh"]
    flesh.hapticut.custom_model = "viscous"
    with bpy.context.temp_override(object=flesh, active_object=flesh):
        assert bpy.ops.hapticut.set_custom_material() == {"FINISHED"}
    flesh.hapticut.custom_parameters["viscosity_N_s_per_mm"].value = 0.002
    report = scene.hapticut.report_json
    path = str(tmp_path / "finger.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.read_homefile(use_empty=True)
    assert "Knife" not in bpy.data.objects
    bpy.ops.wm.open_mainfile(filepath=path)
    knife, flesh = bpy.data.objects["Knife"], bpy.data.objects["Flesh"]
    assert knife.hapticut.role == "BLADE"
    assert knife.hapticut.device == "spacemouse"
    assert (knife.hapticut.edge_vertex_a, knife.hapticut.edge_vertex_b) == (0, 1)
    assert bpy.data.objects["Bone"].hapticut.material_preset == "bone"
    assert bpy.data.objects["Skin"].hapticut.cut_becomes == "FREE"
    assert (flesh.hapticut.cut_becomes, flesh.hapticut.cut_factor) == ("WEAKER", pytest.approx(0.1))
    assert flesh.hapticut.material_preset == "custom"
    parameters = {p.name: p.value for p in flesh.hapticut.custom_parameters}
    assert parameters["viscosity_N_s_per_mm"] == pytest.approx(0.002)
    assert "max_lag_mm" in parameters
    scene = bpy.context.scene
    assert scene.hapticut.report_json == report
    assert scene.hapticut.accuracy == pytest.approx(blender_scene.TEST_ACCURACY_MM)
    assert os.path.isfile(scene.hapticut.work_directory + "/build/scene.hapticut.msgpack")
