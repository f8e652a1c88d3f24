"""The extension built and validated with Blender's own tool, installed from the zip with
package_install_files and enabled (in a child Python: the user resource directory must be
set before bpy starts)."""

import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import blender_scene
import bpy

INSTALL_SCRIPT = """
import json, sys
import bpy
zip_path = sys.argv[1]
result = bpy.ops.extensions.package_install_files(
    filepath=zip_path, repo="user_default", enable_on_install=True
)
addons = [a.module for a in bpy.context.preferences.addons]
module = "bl_ext.user_default.hapticut"
prefs = bpy.context.preferences.addons[module].preferences if module in addons else None
print("RESULT " + json.dumps({
    "result": sorted(result),
    "enabled": module in addons,
    "operator": hasattr(bpy.types, "HAPTICUT_OT_tetrahedralize"),
    "scene_properties": hasattr(bpy.types.Scene, "hapticut"),
    "preferences": prefs is not None and hasattr(prefs, "toolkit_path"),
}))
"""


def extension_tool() -> list[str]:
    """blender_ext.py inside the bpy module (bpy/<version>/scripts/addons_core/bl_pkg/cli)."""
    scripts = Path(bpy.utils.system_resource("SCRIPTS"))
    tool = scripts / "addons_core" / "bl_pkg" / "cli" / "blender_ext.py"
    assert tool.is_file(), tool
    return [sys.executable, str(tool)]


def build_zip(output_dir: Path) -> Path:
    output_dir.mkdir(parents=True, exist_ok=True)
    source = str(blender_scene.REPO / "addon")
    subprocess.run([*extension_tool(), "build", "--source-dir", source, "--output-dir",
                    str(output_dir)], check=True, capture_output=True, text=True)  # fmt: skip
    (package,) = output_dir.glob("hapticut-*.zip")
    return package


def test_build_and_validate_the_extension(tmp_path):
    package = build_zip(tmp_path / "dist")
    for source in (str(blender_scene.REPO / "addon"), str(package)):
        done = subprocess.run([*extension_tool(), "validate", source],
                              capture_output=True, text=True)  # fmt: skip
        assert done.returncode == 0, done.stdout + done.stderr
    names = zipfile.ZipFile(package).namelist()
    assert "blender_manifest.toml" in names
    assert "operators/tetrahedralize.py" in names
    # Pure Python: no compiled module, no bundled numpy or wheel.
    assert not [n for n in names if n.endswith((".so", ".pyd", ".whl", ".pyc"))]
    assert not [n for n in names if "numpy" in n]


def test_install_from_the_zip_and_enable(tmp_path):
    package = build_zip(tmp_path / "dist")
    resources = tmp_path / "user"
    resources.mkdir()
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(resources))
    done = subprocess.run([sys.executable, "-c", INSTALL_SCRIPT, str(package)], env=env,
                          capture_output=True, text=True, timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    line = next(x for x in done.stdout.splitlines() if x.startswith("RESULT "))
    result = json.loads(line.removeprefix("RESULT "))
    assert result == {"result": ["FINISHED"], "enabled": True, "operator": True,
                      "scene_properties": True, "preferences": True}  # fmt: skip
    installed = list(resources.rglob("blender_manifest.toml"))
    assert len(installed) == 1 and installed[0].parent.name == "hapticut"
