"""One source per default and per version.

The defaults live in parameter_range.h and the version in VERSION; what is derived from them
needs no test of its own. These tests hold what is checked instead of derived (the Blender
manifest, which Blender parses as a literal) and show that the derived values reach every reader.
"""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
import tomllib
from pathlib import Path

import hapticut
import numpy as np
from hapticut import _core
from hapticut.scenefile import SCHEMA_PATH
from hapticut.scenefile.model import (
    PARAMETER_RANGES,
    SETTING_RANGES,
    BladeSpec,
    Material,
    Safety,
    Scene,
    scene_to_dict,
)
from hapticut.servo_client import ServoClient, ServoProcess

ROOT = Path(__file__).resolve().parents[2]
VERSION = (ROOT / "VERSION").read_text().strip()
FINGER = ROOT / "examples" / "finger.hapticut.msgpack"


def test_the_installed_package_carries_its_version_without_pip_metadata():
    """Blender's Python loads the toolkit's __init__.py from its folder with no view of pip's
    metadata (the add-on's toolkit_link): the version is a file in the package."""
    probe = (
        "import importlib.util, sys\n"
        f"spec = importlib.util.spec_from_file_location('hapticut', {hapticut.__file__!r},"
        f" submodule_search_locations=[{str(Path(hapticut.__file__).parent)!r}])\n"
        "module = importlib.util.module_from_spec(spec)\n"
        "sys.modules['hapticut'] = module\n"
        "spec.loader.exec_module(module)\n"
        "print(module.__version__)\n"
    )
    done = subprocess.run(
        [sys.executable, "-I", "-S", "-c", probe], capture_output=True, text=True, check=True
    )
    assert done.stdout.strip() == VERSION
    assert (Path(hapticut.__file__).parent / "_version.py").read_text().count(VERSION) == 1


def test_version_is_one_line_of_numbers():
    assert (ROOT / "VERSION").read_text() == VERSION + "\n"
    assert all(part.isdigit() for part in VERSION.split(".")), VERSION


def test_toolkit_reports_the_version():
    assert hapticut.__version__ == VERSION
    result = subprocess.run(
        [sys.executable, "-m", "hapticut.cli", "--version"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout == f"hapticut {VERSION}\n"


def test_blender_manifest_states_the_version():
    # Blender reads the manifest itself: it stays a literal, checked here.
    manifest = tomllib.loads((ROOT / "addon" / "blender_manifest.toml").read_text())
    assert manifest["version"] == VERSION


def test_servo_reports_the_version():
    result = subprocess.run(
        [hapticut.servo_path(), "--version"], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith(f"hapticut-servo {VERSION} (protocol "), result.stdout
    with ServoProcess([str(FINGER), "--wait", "--device", "scalpel=viewport", "--quiet"]) as s:
        client = ServoClient(port=s.port).connect()
        try:
            assert client.hello()["servo"] == f"hapticut-servo {VERSION}"
        finally:
            client.close()


def test_python_defaults_are_the_tables():
    safety = Safety()
    for f in dataclasses.fields(Safety):
        assert getattr(safety, f.name) == SETTING_RANGES[f.name]["default"], f.name
    scene = Scene([], np.zeros((0, 3)), np.zeros((0, 4), np.int32), np.zeros(0, np.int32))
    assert isinstance(scene.max_transitions_per_tick, int)
    for name in ("stiffness_N_per_mm", "servo_rate_Hz", "tolerance_mm", "max_transitions_per_tick"):
        assert getattr(scene, name) == SETTING_RANGES[name]["default"], name
    assert Material("goo", "viscous").max_lag_mm == PARAMETER_RANGES["max_lag_mm"]["default"]


def test_cpp_defaults_are_the_tables():
    # A scene dict without coupling, tolerance or safety takes the C++ Scene's defaults.
    vertices, tets = _core.two_tets_mesh(10.0)
    scene = {
        "materials": [{"name": "goo", "model": "viscous", "viscosity_N_s_per_mm": 0.01}],
        "vertices": vertices,
        "tets": tets,
        "tet_materials": np.zeros(len(tets), np.int32),
        "blades": [{"name": "b", "start_mm": (0, 0, 0), "end_mm": (1, 0, 0)}],
    }
    read = _core.parse_scene_bytes(_core.serialize_scene_bytes(scene, "json"), "json")
    for name in ("stiffness_N_per_mm", "servo_rate_Hz", "tolerance_mm", "max_transitions_per_tick"):
        assert read[name] == SETTING_RANGES[name]["default"], name
    for name, value in read["safety"].items():
        assert value == SETTING_RANGES[name]["default"], name
    assert read["materials"][0]["max_lag_mm"] == PARAMETER_RANGES["max_lag_mm"]["default"]
    # And the Python model writes the same file as the C++ defaults do.
    python_scene = Scene(
        [Material("goo", "viscous", viscosity_N_s_per_mm=0.01)],
        vertices,
        tets,
        np.zeros(len(tets), np.int32),
    )
    python_dict = scene_to_dict(python_scene)
    python_dict["blades"] = scene["blades"]
    assert json.loads(_core.serialize_scene_bytes(python_dict, "json")) == json.loads(
        _core.serialize_scene_bytes(scene, "json")
    )


def test_blade_defaults_agree():
    # A blade's defaults are no range of the table: the schema, the Python model and the C++
    # BladeSpec each state them, and this holds them equal.
    schema = json.loads(SCHEMA_PATH.read_text())["$defs"]["blade"]["properties"]
    python = {f.name: f.default for f in dataclasses.fields(BladeSpec)}
    vertices, tets = _core.two_tets_mesh(10.0)
    scene = {
        "materials": [{"name": "air", "model": "free"}],
        "vertices": vertices,
        "tets": tets,
        "tet_materials": np.zeros(len(tets), np.int32),
        "blades": [{"name": "b", "start_mm": (0, 0, 0), "end_mm": (1, 0, 0)}],
    }
    cpp = _core.parse_scene_bytes(_core.serialize_scene_bytes(scene, "json"), "json")["blades"][0]
    for name in ("points", "coupling", "orientation"):
        assert schema[name]["default"] == python[name] == cpp[name], name
