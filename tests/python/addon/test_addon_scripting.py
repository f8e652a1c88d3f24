"""docs/addon.md, "Scripting", used as a script would: its code blocks run as they stand (mark
a region and a blade, build, wait, export, simulate, wait, bake), and every operator and
property its lists name is the registered add-on's, both ways, so the docs cannot drift."""

import json
import os
import re
import subprocess
import tempfile

import blender_scene
import bpy
import numpy as np
import pytest

DOCS = blender_scene.REPO / "docs" / "addon.md"
# The lists' headings: a Blender type and its property holding the add-on's settings.
PROPERTY_LISTS = ("Object.hapticut", "Scene.hapticut", "Scene.hapticut_live")
IDENTIFIER = re.compile(r"`([A-Za-z_][A-Za-z0-9_]*)`")


def scripting_section() -> str:
    text = DOCS.read_text()
    start = text.index("\n## Scripting\n")
    end = text.index("\n## ", start + 1)
    return text[start:end]


def code_blocks(section: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", section, re.S)


def list_items(section: str) -> dict[str, str]:
    """Each "- `Heading`...: ..." item of the section (continuation lines joined), by heading."""
    items, current = {}, None
    for line in section.splitlines():
        found = re.match(r"- `([A-Za-z_.]+)`", line)
        if found:
            current = found.group(1)
            items[current] = line
        elif current and line.startswith("  "):
            items[current] += " " + line.strip()
        else:
            current = None
    return items


def registered_properties(heading: str) -> set[str]:
    """The identifiers of the property group at heading ("Scene.hapticut"); nested groups'
    items (custom_parameters' value, problems' fields) are named in the lists too; every
    group's built-in ``name`` is not (custom_parameters are looked up by it)."""
    owner, attribute = heading.split(".")
    group = getattr(bpy.types, owner).bl_rna.properties[attribute].fixed_type
    names = set()
    for prop in group.properties:
        names.add(prop.identifier)
        if prop.type == "COLLECTION":
            names |= {p.identifier for p in prop.fixed_type.properties}
    return names - {"rna_type", "name"}


def test_every_listed_name_is_registered_and_every_registered_one_listed(addon):
    section = scripting_section()
    documented_ops = set(re.findall(r"bpy\.ops\.hapticut\.([a-z_]+)\(", section))
    registered_ops = {name for name in dir(bpy.ops.hapticut) if not name.startswith("_")}
    assert documented_ops == registered_ops
    items = list_items(section)
    for heading in PROPERTY_LISTS:
        text = items[heading].split(":", 1)[1]
        documented = set(IDENTIFIER.findall(text))
        assert documented == registered_properties(heading), heading


def test_the_recipe_runs_as_a_script(addon, tmp_path, monkeypatch):
    from addon.bake import baking

    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    bpy.ops.wm.read_homefile(use_empty=True)
    blocks = code_blocks(scripting_section())
    assert len(blocks) == 4
    namespace = {"__name__": "__main__"}
    for block in blocks[:3]:
        exec(compile(block, str(DOCS), "exec"), namespace)
    scene = bpy.context.scene
    # Built and exported.
    assert scene.hapticut.status.startswith("built"), scene.hapticut.error
    assert not scene.hapticut.running
    exported = namespace["exported"]
    assert exported == str(tmp_path / "cube.hapticut.msgpack") and os.path.getsize(exported) > 0
    executable = blender_scene.toolkit_executable()
    copy = str(tmp_path / "cube.hapticut.json")
    subprocess.run([executable, "convert", exported, copy], check=True, capture_output=True)
    with open(copy) as file:
        assert [b["name"] for b in json.load(file)["blades"]] == ["Plane"]
    # Simulated, baked when done, baked again from the recording.
    assert namespace["baked"]["frames"] >= scene.frame_end - scene.frame_start + 1
    assert os.path.isfile(scene.hapticut_live.recording_path)
    names = {o.name for o in baking.baked_objects()}
    assert names == {"Ideal Plane", "Force Plane", "Cut Plane"}
    again = json.loads(scene.hapticut_live.bake_report)
    assert again["frames"] == namespace["baked"]["frames"]
    assert again["blades"]["Plane"]["max_force_N"] > 0
    # The headless live session: driven, recorded, stopped, baked.
    stroke = scene.hapticut_live.recording_path
    exec(compile(blocks[3], str(DOCS), "exec"), namespace)
    live = namespace["live_path"]
    assert live != stroke and os.path.basename(live).startswith("live-")
    from addon.live import live_link

    assert live_link.current() is None  # Stopped.
    baked_live = json.loads(scene.hapticut_live.bake_report)
    assert baked_live["recording"] == live and baked_live["ticks"] > 100
    # The knife went where the script moved it: down to 2 mm (into the cube) and back up.
    poses = live_link.link().read_recording(live).ideal_pose("Plane")
    posed = np.abs(poses[:, :3]).sum(axis=1) > 0  # Ticks before the first pose hold zeros.
    heights = poses[np.argmax(posed) :, 2]
    assert heights.min() == pytest.approx(2.0, abs=0.01) and heights[-1] > 19.0


def test_wait_raises_the_build_error(addon, tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    blender_scene.empty_scene("")
    corners = [(x, y, z) for x in (-5, 5) for y in (-5, 5) for z in (-5, 5)]
    faces = [(4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    lid = blender_scene.mesh_object("Lid", corners, faces)  # A box without its bottom.
    lid.hapticut.role = "REGION"
    blender_scene.knife()
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    with pytest.raises(RuntimeError, match="the build failed: Lid: the mesh is open"):
        bpy.ops.hapticut.wait()
    assert bpy.context.scene.hapticut.status == "failed"
