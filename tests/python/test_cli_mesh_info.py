"""`hapticut mesh` and `hapticut info` as a user runs them."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from build_test_support import EXAMPLES, icosphere, materials_at, run_cli, write_obj
from hapticut.commands.mesh import parse_material
from hapticut.scenefile import Material, load_scene


def test_mesh_then_info_on_two_nested_spheres(tmp_path):
    flesh = write_obj(tmp_path / "flesh.obj", *icosphere(20.0, 2))
    bone = write_obj(tmp_path / "bone.obj", *icosphere(8.0, 1))
    out = tmp_path / "scene.hapticut.json"
    result = run_cli(
        "mesh", flesh, bone, "--material", "flesh=drag,drag_distance_mm=0.5",
        "--material", "bone=rigid", "-o", out, "--vtu", tmp_path / "scene.vtu",
        "--enclosure", "cube", "--accuracy", "0.3",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "tetrahedralizing" in result.stderr  # the progress bar (a line per step off a tty)
    scene = load_scene(out)
    assert [(m.name, m.model) for m in scene.materials] == [
        ("air", "free"), ("flesh", "drag"), ("bone", "rigid")
    ]  # fmt: skip
    assert scene.materials[1].drag_distance_mm == 0.5
    assert materials_at(scene, [[0, 0, 0], [0, 0, 14], [0, 0, 24]]) == ["bone", "flesh", "air"]
    assert (tmp_path / "scene.vtu").stat().st_size > 0

    info = run_cli("info", out)
    assert info.returncode == 0, info.stderr
    counts = scene.metadata["build_report"]["tets_per_material"]
    assert f"{len(scene.tets)} tets" in info.stdout
    for name, count in counts.items():
        assert f"{name}" in info.stdout and str(count) in info.stdout
    assert "min dihedral" in info.stdout and "tets per edge max" in info.stdout
    assert "drag (drag_distance_mm=0.5)" in info.stdout
    # Every build step with its share of the build, the labelling's included.
    label = re.search(r"label (\d+\.\d+) s = (\d+\.\d) %", info.stdout)
    assert label, info.stdout
    timings = scene.metadata["build_report"]["timings_s"]
    assert float(label.group(2)) == pytest.approx(
        100 * timings["label"] / timings["total"], abs=0.06
    )


def test_info_prints_table3_beside_the_paper_for_the_spheres():
    result = run_cli("info", EXAMPLES / "sphere80.hapticut.msgpack")
    assert result.returncode == 0, result.stderr
    assert "Paper's Table 3 (sphere80)" in result.stdout
    assert "394" in result.stdout and "234" in result.stdout
    result = run_cli("info", EXAMPLES / "sphere320.hapticut.msgpack", "--json")
    assert result.returncode == 0 and '"tets_per_material"' in result.stdout


def test_info_names_each_blades_coupling_and_the_stiffness_it_renders():
    result = run_cli("info", EXAMPLES / "sphere80.hapticut.msgpack")
    assert result.returncode == 0, result.stderr
    # The example's 50-point scalpel at 0.1 N/mm: rigid, so its springs act together.
    assert "50 points" in result.stdout
    assert "rigid, orientation free; renders 5 N/mm in contact" in result.stdout
    as_json = run_cli("info", EXAMPLES / "sphere80.hapticut.msgpack", "--json")
    (blade,) = json.loads(as_json.stdout)["blades"]
    assert (blade["coupling"], blade["orientation"]) == ("rigid", "free")
    assert blade["rendered_stiffness_N_per_mm"] == pytest.approx(5.0)


def test_info_and_mesh_report_bad_arguments(tmp_path):
    missing = run_cli("info", tmp_path / "none.hapticut.json")
    assert missing.returncode == 1 and "none.hapticut.json" in missing.stderr
    ball = write_obj(tmp_path / "ball.obj", *icosphere(5.0, 1))
    wrong = run_cli("mesh", ball, "--material", "ball=jelly", "-o", tmp_path / "x.hapticut.json")
    assert wrong.returncode == 2 and "jelly" in wrong.stderr
    unknown = run_cli("mesh", ball, "--material", "bal=rigid", "-o", tmp_path / "x.hapticut.json")
    assert unknown.returncode == 2 and "unknown region" in unknown.stderr
    assert not (tmp_path / "x.hapticut.json").exists()


def test_parse_material():
    assert parse_material("skin=membrane,break_force_N=2") == (
        "skin", Material("skin", "membrane", break_force_N=2.0)
    )  # fmt: skip
    assert parse_material("left=rigid,name=bone") == ("left", Material("bone", "rigid"))
    assert parse_material("goo=viscous")[1].viscosity_N_s_per_mm > 0
    with pytest.raises(ValueError, match="unknown parameter"):
        parse_material("x=drag,speed=3")


def test_info_tells_when_a_build_meshed_again_to_hold_its_accuracy():
    from hapticut.commands.info import format_build_report

    once = [{"envelope_mm": 0.2, "deviation_mm": {"ball": 0.1}}]
    again = [
        {"envelope_mm": 0.2, "deviation_mm": {"ball": 0.6}},
        {"envelope_mm": 0.1, "deviation_mm": {"ball": 0.4}},
    ]
    assert not any("meshed" in line for line in format_build_report({"meshing_attempts": once}))
    lines = format_build_report({"meshing_attempts": again})
    assert "  meshed 2 times to hold the accuracy (envelope 0.2 -> 0.1 mm)" in lines


def two_blocks_with_a_narrow_gap(gap_mm: float = 0.01):
    """One region of two 10 mm blocks 0.01 mm apart: no tet mesh within the envelope keeps
    the gap, so its faces lie mm from the meshed surface (a lost narrow gap)."""
    from hapticut.scenebuild.geometry import enclosure_surface

    left = enclosure_surface("box", np.zeros(3), np.full(3, 10.0), 0.0)
    right = enclosure_surface("box", [10.0 + gap_mm, 0, 0], [20.0 + gap_mm, 10, 10], 0.0)
    return np.vstack([left[0], right[0]]), np.vstack([left[1], right[1] + 8])


def test_mesh_keeps_the_best_mesh_and_names_the_lost_feature_unless_strict(tmp_path):
    blocks = write_obj(tmp_path / "blocks.obj", *two_blocks_with_a_narrow_gap())
    out = tmp_path / "blocks.hapticut.json"
    result = run_cli("mesh", blocks, "-o", out, "-q")
    assert result.returncode == 0, result.stderr
    assert "accuracy not held: region 'blocks'" in result.stderr
    assert "lost: a narrow gap near (10.0, 5.0, 5.0) mm, 10 mm long, 0.01 mm wide" in result.stderr
    report = load_scene(out).metadata["build_report"]
    (miss,) = report["accuracy_not_held"]
    assert miss["lost_features"][0]["kind"] == "narrow gap"
    info = run_cli("info", out)
    assert "accuracy not held: region 'blocks'" in info.stdout
    assert "Air share:" in info.stdout

    strict = run_cli("mesh", blocks, "-o", tmp_path / "strict.hapticut.json", "-q",
                     "--strict-accuracy")  # fmt: skip
    assert strict.returncode == 1
    assert "region 'blocks': its meshed surface lies up to" in strict.stderr
    assert "a narrow gap" in strict.stderr
    assert not (tmp_path / "strict.hapticut.json").exists()


def test_mesh_warns_on_stderr_when_an_input_looks_like_another_unit(tmp_path):
    tiny = write_obj(tmp_path / "tiny.obj", *icosphere(1.0, 1))
    result = run_cli("mesh", tiny, "-o", tmp_path / "tiny.hapticut.json", "-q")
    assert result.returncode == 0, result.stderr
    assert "warning: region 'tiny' is 2 mm across" in result.stderr
    assert "--scale" in result.stderr
    scaled = run_cli("mesh", tiny, "-o", tmp_path / "big.hapticut.json", "-q", "--scale", "50")
    assert scaled.returncode == 0 and "warning" not in scaled.stderr
