"""The Python reader and writer of scene files (format version 1)."""

from __future__ import annotations

import json
import math
import os
import pickle
import time

import jsonschema
import msgpack
import numpy as np
import pytest
from hapticut.scenefile import (
    JSON,
    MSGPACK,
    SCHEMA_PATH,
    BladeSpec,
    Material,
    Safety,
    Scene,
    SceneError,
    encoding_for_path,
    load_scene,
    parse_scene,
    save_scene,
    scene_from_dict,
    scene_to_dict,
    serialize_scene,
)
from scene_test_support import (
    ERROR_CASES,
    EXAMPLE_PATH,
    apply_patch,
    example_tree,
    grid_scene,
)


def encode(tree, encoding: str) -> bytes:
    return json.dumps(tree).encode() if encoding == JSON else msgpack.packb(tree)


def error_of(data: bytes, encoding: str, strict: bool = False) -> str:
    with pytest.raises(SceneError) as caught:
        parse_scene(data, encoding, strict=strict)
    return str(caught.value)


@pytest.fixture
def example() -> Scene:
    return load_scene(EXAMPLE_PATH)


# --- Reading ---------------------------------------------------------------------------------


def test_example_file_reads_with_every_field(example: Scene):
    assert [m.name for m in example.materials] == ["air", "flesh"]
    assert example.materials[1] == Material("flesh", "drag", drag_distance_mm=1.0)
    assert example.vertices.dtype == np.float64 and example.vertices.shape == (5, 3)
    assert example.tets.dtype == np.int32 and example.tets.tolist() == [[0, 1, 2, 3], [1, 2, 3, 4]]
    assert example.tet_materials.dtype == np.int32 and example.tet_materials.tolist() == [1, 0]
    assert example.blades == [BladeSpec("scalpel", (0.0, 0.0, 0.0), (100.0, 0.0, 0.0), 50)]
    # The file names neither: a rigid blade with its own orientation, the defaults.
    assert (example.blades[0].coupling, example.blades[0].orientation) == ("rigid", "free")
    assert (example.stiffness_N_per_mm, example.servo_rate_Hz, example.tolerance_mm) == (
        0.1,
        1000.0,
        0.0,
    )
    assert example.safety == Safety()
    assert "description" in example.metadata


def test_optional_sections_take_their_defaults():
    tree = example_tree()
    for key in ("coupling", "tolerance_mm", "blades", "metadata"):
        del tree[key]
    scene = parse_scene(json.dumps(tree).encode())
    assert scene.blades == [] and scene.metadata == {} and scene.safety == Safety()
    assert (scene.stiffness_N_per_mm, scene.servo_rate_Hz, scene.tolerance_mm) == (0.1, 1000, 0)


def test_every_model_with_its_parameters_reads():
    tree = example_tree()
    tree["materials"] += [
        {"name": "bone", "model": "rigid"},
        {"name": "fluid", "model": "viscous", "viscosity_N_s_per_mm": 0.001, "max_lag_mm": 5},
        {"name": "thin", "model": "viscous", "viscosity_N_s_per_mm": 0.002},
        {"name": "skin", "model": "membrane", "break_force_N": 1.0},
        {"name": "grip", "model": "rigid", "static_friction": 0.4, "dynamic_friction": 0.3},
    ]
    materials = parse_scene(json.dumps(tree).encode()).materials
    assert materials[3] == Material("fluid", "viscous", viscosity_N_s_per_mm=0.001, max_lag_mm=5.0)
    assert materials[4].max_lag_mm == 50.0  # The default cap.
    assert materials[5] == Material("skin", "membrane", break_force_N=1.0)
    # Rigid: frictionless unless the file says.
    assert (materials[2].static_friction, materials[2].dynamic_friction) == (0.0, 0.0)
    assert materials[6] == Material("grip", "rigid", static_friction=0.4, dynamic_friction=0.3)


def test_integral_floats_count_as_integers():
    tree = example_tree()
    tree["mesh"]["tets"][1] = [1.0, 2.0, 3.0, 4.0]
    tree["mesh"]["tet_materials"] = [1.0, 0]
    scene = parse_scene(json.dumps(tree).encode())
    assert scene.tets.tolist() == [[0, 1, 2, 3], [1, 2, 3, 4]]
    assert scene.tet_materials.tolist() == [1, 0]


# --- Bad inputs: one table shared with tests/cpp/scene_io_test.cpp ---------------------------


@pytest.mark.parametrize("encoding", [JSON, MSGPACK])
@pytest.mark.parametrize("case", ERROR_CASES, ids=[case["name"] for case in ERROR_CASES])
def test_bad_input_names_field_and_reason(case, encoding):
    data = encode(apply_patch(example_tree(), case["patch"]), encoding)
    assert error_of(data, encoding, strict=case.get("strict", False)) == case["error"]


def test_error_carries_field_and_reason():
    tree = apply_patch(example_tree(), [{"op": "replace", "path": "/mesh/tets/1/3", "value": 99}])
    with pytest.raises(SceneError) as caught:
        parse_scene(json.dumps(tree).encode())
    assert isinstance(caught.value, ValueError)
    assert caught.value.field == "/mesh/tets/1/3"
    assert caught.value.reason == "vertex index 99 out of range (5 vertices)"
    assert str(pickle.loads(pickle.dumps(caught.value))) == str(caught.value)


@pytest.mark.parametrize("encoding", [JSON, MSGPACK])
@pytest.mark.parametrize("fraction", [0.0, 0.3, 0.5, 0.99])
def test_truncated_file(encoding, fraction):
    data = serialize_scene(load_scene(EXAMPLE_PATH), encoding)
    message = error_of(data[: int(len(data) * fraction)], encoding)
    name = "JSON" if encoding == JSON else "MessagePack"
    assert message.startswith(f"(root): truncated or not valid {name}: ")


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
@pytest.mark.parametrize("encoding", [JSON, MSGPACK])
def test_non_finite_coordinate(value, encoding):
    # MessagePack carries NaN and infinities natively. JSON has none: the NaN and Infinity
    # literals Python's json writes, and a number beyond the double range such as 1e999, are not
    # read as JSON by either reader (both decode with the C++ decoder).
    tree = example_tree()
    tree["mesh"]["vertices"][3][1] = value
    if encoding == MSGPACK:
        assert (
            error_of(encode(tree, encoding), encoding) == "/mesh/vertices/3/1: not a finite number"
        )
        return
    assert error_of(encode(tree, encoding), encoding).startswith(
        "(root): truncated or not valid JSON"
    )
    tree["mesh"]["vertices"][3][1] = 12345.5
    text = encode(tree, encoding).replace(b"12345.5", b"1e999" if value > 0 else b"-1e999")
    if not math.isnan(value):
        assert error_of(text, encoding).endswith(
            "number overflow parsing '" + ("1e999'" if value > 0 else "-1e999'")
        )


def test_non_finite_parameter_in_msgpack():
    tree = example_tree()
    tree["materials"][1]["drag_distance_mm"] = math.nan
    message = error_of(msgpack.packb(tree), MSGPACK)
    assert message == "/materials/1/drag_distance_mm: not a finite number"


def test_inverted_tet_is_reoriented_by_default_and_rejected_when_strict():
    tree = example_tree()
    tree["mesh"]["tets"][1] = [2, 1, 3, 4]
    data = json.dumps(tree).encode()
    assert parse_scene(data).tets.tolist() == [[0, 1, 2, 3], [2, 1, 4, 3]]
    assert error_of(data, JSON, strict=True) == "/mesh/tets/1: inverted (negative volume)"


def test_bad_json_text():
    message = error_of(b'{"format": "hapticut.scene",, }', JSON)
    assert message.startswith("(root): truncated or not valid JSON: ")
    assert error_of(b"\xff\xfe", JSON).startswith("(root): truncated or not valid JSON: ")


# --- Writing ---------------------------------------------------------------------------------


@pytest.mark.parametrize("encoding", [JSON, MSGPACK])
def test_round_trip(example: Scene, encoding):
    again = parse_scene(serialize_scene(example, encoding), encoding)
    assert again == example
    assert again.tets.dtype == np.int32 and again.vertices.dtype == np.float64


def test_json_to_msgpack_to_json_is_byte_identical(example: Scene):
    json_bytes = serialize_scene(example, JSON)
    via_msgpack = parse_scene(serialize_scene(parse_scene(json_bytes), MSGPACK), MSGPACK)
    assert serialize_scene(via_msgpack, JSON) == json_bytes


def test_round_trip_keeps_exact_doubles_and_metadata():
    rng = np.random.default_rng(7)
    scene = grid_scene(3)
    scene.vertices = scene.vertices + rng.uniform(-1e-3, 1e-3, scene.vertices.shape)
    scene.metadata = {"author": "Zoë", "nested": {"list": [1, 2.5, None, True]}}
    scene.blades = [BladeSpec("edge", (0.1, 0.2, 0.3), (1e-7, 2e20, -3.5), 3)]
    for encoding in (JSON, MSGPACK):
        again = parse_scene(serialize_scene(scene, encoding), encoding)
        assert again == scene
        assert again.vertices.tobytes() == scene.vertices.tobytes()


@pytest.mark.parametrize("encoding", [JSON, MSGPACK])
def test_blade_coupling_and_orientation_are_written_and_read(encoding):
    scene = grid_scene(2)
    scene.blades = [
        BladeSpec("knife", (-50.0, 0.0, 0.0), (50.0, 0.0, 0.0), 50),
        BladeSpec("brush", (0.0, 0.0, 0.0), (10.0, 0.0, 0.0), 5, coupling="independent"),
        BladeSpec("probe", (0.0, 0.0, 0.0), (0.0, 5.0, 0.0), 3, orientation="locked"),
    ]
    data = serialize_scene(scene, encoding)
    tree = json.loads(data) if encoding == JSON else msgpack.unpackb(data)
    assert [(b["coupling"], b["orientation"]) for b in tree["blades"]] == [
        ("rigid", "free"),
        ("independent", "free"),
        ("rigid", "locked"),
    ]
    assert parse_scene(data, encoding) == scene
    # A blade that names neither takes the defaults; one that names them keeps them.
    tree["blades"][0].pop("coupling")
    tree["blades"][0].pop("orientation")
    again = parse_scene(json.dumps(tree).encode())
    assert again.blades == scene.blades


@pytest.mark.parametrize(
    ("field", "value", "error"),
    [
        ("coupling", "hinged", "unknown coupling 'hinged' of blade 'knife' (expected rigid, "
         "independent)"),
        ("orientation", "fixed", "unknown orientation 'fixed' of blade 'knife' (expected free, "
         "locked)"),
        ("coupling", 1, "expected a string, got int"),
    ],
)  # fmt: skip
def test_writer_names_the_blade_and_field_of_a_bad_setting(field, value, error):
    scene = grid_scene(2)
    scene.blades = [
        BladeSpec("ok", (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), 2),
        BladeSpec("knife", (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), 2, **{field: value}),
    ]
    with pytest.raises(SceneError) as caught:
        serialize_scene(scene)
    assert (caught.value.field, caught.value.reason) == (f"/blades/1/{field}", error)


def test_writer_checks_the_scene_like_the_reader(example: Scene):
    example.vertices = example.vertices.copy()
    example.vertices[0, 0] = math.nan
    with pytest.raises(SceneError, match=r"^/mesh/vertices/0/0: not a finite number$"):
        serialize_scene(example)
    bad_model = Scene([Material("x", "jelly")], example.vertices, example.tets, [0, 0])
    with pytest.raises(SceneError, match=r"^/materials/0/model: unknown model 'jelly'"):
        serialize_scene(bad_model)


def test_only_the_models_parameters_are_written():
    scene = load_scene(EXAMPLE_PATH)
    scene.materials = [Material("air", "free", drag_distance_mm=3.0), scene.materials[1]]
    tree = json.loads(serialize_scene(scene))
    assert tree["materials"][0] == {"name": "air", "model": "free"}


def test_save_chooses_encoding_from_the_name(example: Scene, tmp_path):
    assert encoding_for_path("a.hapticut.msgpack") == MSGPACK
    assert encoding_for_path("a.hapticut.json") == JSON
    save_scene(example, tmp_path / "scene.hapticut.msgpack")
    data = (tmp_path / "scene.hapticut.msgpack").read_bytes()
    assert msgpack.unpackb(data)["format"] == "hapticut.scene"
    assert load_scene(tmp_path / "scene.hapticut.msgpack") == example


def test_save_is_atomic(example: Scene, tmp_path, monkeypatch):
    path = tmp_path / "scene.hapticut.json"
    save_scene(example, path)
    before = path.read_bytes()
    assert os.listdir(tmp_path) == ["scene.hapticut.json"]  # No temporary left behind.

    def failing_fsync(fd):
        raise OSError("disk full")

    changed = Scene(example.materials, example.vertices * 2, example.tets, example.tet_materials)
    monkeypatch.setattr(os, "fsync", failing_fsync)
    with pytest.raises(OSError, match="disk full"):
        save_scene(changed, path)
    monkeypatch.undo()
    assert path.read_bytes() == before
    assert os.listdir(tmp_path) == ["scene.hapticut.json"]

    invalid = Scene([], example.vertices, example.tets, example.tet_materials)
    with pytest.raises(SceneError, match="^/materials: empty"):
        save_scene(invalid, path)
    assert path.read_bytes() == before


def test_missing_file_raises_os_error(tmp_path):
    with pytest.raises(FileNotFoundError):
        load_scene(tmp_path / "absent.hapticut.json")


# --- Schema ----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def schema_validator():
    schema = json.loads(SCHEMA_PATH.read_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def test_schema_accepts_what_the_readers_write(schema_validator, example: Scene):
    schema_validator.validate(example_tree())
    schema_validator.validate(json.loads(serialize_scene(example)))


# The cases a schema can express; the rest (ranges against other fields, finiteness, unique
# names, volume) only the readers check.
SCHEMA_CASES = [
    "root_not_an_object",
    "wrong_format_version",
    "missing_units",
    "wrong_length_unit",
    "stiffness_zero",
    "transitions_zero",
    "no_materials",
    "unknown_model",
    "missing_drag_distance",
    "parameter_of_another_model",
    "missing_mesh",
    "vertex_with_two_coordinates",
    "zero_tets",
    "tet_with_three_vertices",
    "negative_vertex_index",
    "fractional_vertex_index",
    "repeated_vertex",
    "blade_with_no_points",
    "blade_unknown_coupling",
    "blade_coupling_not_a_string",
    "blade_unknown_orientation",
    "misspelt_root_field",
]


@pytest.mark.parametrize("name", SCHEMA_CASES)
def test_schema_rejects_what_it_can_express(schema_validator, name):
    (case,) = [case for case in ERROR_CASES if case["name"] == name]
    assert not schema_validator.is_valid(apply_patch(example_tree(), case["patch"]))


# --- Cut memory (docs/decisions.md, "Cut memory") --------------------------------------------


def _with_cut_to(example: Scene, cut_to: str) -> Scene:
    flesh_cut = Material("flesh_cut", "drag", drag_distance_mm=0.1)
    materials = [example.materials[0], Material("flesh", "drag", 1.0, cut_to=cut_to), flesh_cut]
    return Scene(materials, example.vertices, example.tets, example.tet_materials, example.blades)


@pytest.mark.parametrize("encoding", [JSON, MSGPACK])
def test_cut_to_round_trips(example: Scene, encoding):
    scene = _with_cut_to(example, "flesh_cut")
    again = parse_scene(serialize_scene(scene, encoding), encoding)
    assert [m.cut_to for m in again.materials] == ["", "flesh_cut", ""]
    assert again == scene


@pytest.mark.parametrize("encoding", [JSON, MSGPACK])
def test_a_bad_cut_to_names_the_material(example: Scene, encoding):
    with pytest.raises(SceneError, match="^/materials/1/cut_to: material 'flesh': cut_to names"):
        serialize_scene(_with_cut_to(example, "gristle"), encoding)
    tree = example_tree()
    tree["materials"][1]["cut_to"] = "flesh"
    assert error_of(encode(tree, encoding), encoding) == (
        "/materials/1/cut_to: material 'flesh': cut_to makes a cycle ('flesh' -> 'flesh')"
    )


def test_the_engine_takes_cut_to_from_a_scene(example: Scene):
    from hapticut.engine import space_from_scene

    space_from_scene(_with_cut_to(example, "flesh_cut"))
    with pytest.raises(ValueError, match="cut_to 'air'"):
        bad = _with_cut_to(example, "flesh_cut")
        bad.materials[1] = Material("flesh", "drag", 1.0, cut_to="air")
        bad.materials[0] = Material("air", "rigid")
        space_from_scene(bad)


# --- Dicts and size --------------------------------------------------------------------------


def test_scene_dict_round_trip(example: Scene):
    as_dict = scene_to_dict(example)
    assert set(as_dict["materials"][0]) == {
        "name",
        "model",
        "drag_distance_mm",
        "viscosity_N_s_per_mm",
        "max_lag_mm",
        "break_force_N",
        "static_friction",
        "dynamic_friction",
        "cut_to",
    }
    assert scene_from_dict(as_dict) == example
    assert scene_from_dict(json.loads(json.dumps(as_dict, default=np.ndarray.tolist))) == example


@pytest.mark.parametrize("encoding", [JSON, MSGPACK])
def test_hundred_thousand_tets(encoding):
    scene = grid_scene(26)  # 105,456 tets
    data = serialize_scene(scene, encoding)
    start = time.perf_counter()
    again = parse_scene(data, encoding)
    seconds = time.perf_counter() - start
    megabytes = len(data) / 1e6
    print(f"\nparse {len(scene.tets)} tets, {megabytes:.1f} MB {encoding}: {seconds:.3f} s")
    assert again == scene
