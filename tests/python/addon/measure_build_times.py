"""Prints, for the finger and the bunny examples, the time from Tetrahedralize to the preview
and the UI's longest stall (the longest call of the function the timer calls), through the
add-on inside bpy. A measurement, not a test: nothing is asserted.

    python tests/python/addon/measure_build_times.py [finger] [bunny]
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import blender_scene  # noqa: E402
import bpy  # noqa: E402
import numpy as np  # noqa: E402

BUNNY_LENGTH_MM = 120.0


def finger(work: str):
    """The finger example as examples/build_examples.py builds it (all five parts)."""
    scene = blender_scene.empty_scene(work)
    blender_scene.region("Skin", "finger_skin.obj", "skin")
    blender_scene.region("Flesh", "finger_flesh.obj", "soft_tissue")
    for part in ("proximal", "middle", "distal"):
        blender_scene.region(f"Bone {part}", f"finger_bone_{part}.obj", "bone")
    blender_scene.knife()
    scene.hapticut.accuracy, scene.hapticut.edge_near, scene.hapticut.edge_far = 0.5, 2.5, 12.0
    return scene


REPAIRED_BUNNY = """
import sys
import numpy as np
sys.path.insert(0, sys.argv[1])
from build_examples import mouse_region
from hapticut.scenebuild.repair import repair_surface
region = mouse_region()
surface, _ = repair_surface(region.name, region.vertices, region.faces, 100)
np.savez(sys.argv[2], vertices=surface.vertices, faces=surface.faces)
"""


def bunny(work: str):
    """The mouse example's bunny (pymeshlab's sample, 120 mm long) with its holes closed by
    the toolkit's repair in a child Python (the add-on refuses open meshes), as the mouse
    example builds it."""
    path = Path(work) / "bunny.npz"
    examples = str(blender_scene.REPO / "examples")
    subprocess.run([sys.executable, "-c", REPAIRED_BUNNY, examples, str(path)], check=True)
    scene = blender_scene.empty_scene(work)
    with np.load(path) as data:
        obj = blender_scene.mesh_object("Bunny", data["vertices"], data["faces"])
    obj.hapticut.role = "REGION"
    obj.hapticut.material_preset = "bone"
    blender_scene.knife()
    settings = scene.hapticut
    settings.enclosure, settings.accuracy, settings.edge_far = "cube", 2.6, 40.0
    return scene


def measure(name: str, make) -> dict:
    from addon.authoring import building

    scene = make(tempfile.mkdtemp(prefix=f"hapticut-measure-{name}-"))
    started = time.perf_counter()
    bpy.ops.hapticut.tetrahedralize()
    calls = []  # Seconds per call of what the timer calls; the last one makes the preview.
    while True:
        began = time.perf_counter()
        going = building.update(scene.name)
        calls.append(time.perf_counter() - began)
        if not going:
            break
        time.sleep(0.1)
    import json

    report = json.loads(scene.hapticut.report_json or "{}")
    return {"name": name, "seconds": time.perf_counter() - started,
            "stall_ms": 1000 * max(calls), "running_ms": 1000 * max(calls[:-1], default=0.0),
            "tets": report.get("tets", 0), "error": scene.hapticut.error,
            "build_s": report.get("timings_s", {}).get("total", float("nan"))}  # fmt: skip


def main(names: list[str]) -> int:
    blender_scene.enable_addon()
    examples = {"finger": finger, "bunny": bunny}
    rows = [measure(name, examples[name]) for name in names or list(examples)]
    print(
        f"{'example':<8} {'tets':>7} {'to preview s':>13} {'builder s':>10} {'stall ms':>9}"
        f" {'while running ms':>17}"
    )
    for row in rows:
        print(f"{row['name']:<8} {row['tets']:>7} {row['seconds']:>13.1f} {row['build_s']:>10.1f}"
              f" {row['stall_ms']:>9.1f} {row['running_ms']:>17.1f} {row['error']}")  # fmt: skip
    print(f"bpy {bpy.app.version_string}; {np.__name__} {np.__version__}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
