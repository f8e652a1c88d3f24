"""``hapticut demo-stroke``: the text demo (a 50-point blade through the 320-face sphere)."""

import re
import subprocess
import sys


def demo_stroke(*args):
    return subprocess.run(
        [sys.executable, "-m", "hapticut.cli", "demo-stroke", *args],
        capture_output=True, text=True,
    )  # fmt: skip


def test_the_stroke_presses_into_the_sphere_and_says_so():
    done = demo_stroke()
    assert done.returncode == 0, done.stderr
    out = done.stdout
    assert "scene sphere320" in out and "blade: 50 points" in out
    forces = [float(m) for m in re.findall(r"^\s*\d+\s+\S+\s+\S+\s+\S+\s+([\d.]+)", out, re.M)]
    assert forces[0] == 0.0  # It starts above the sphere, in the air.
    assert max(forces) > 1.0  # 5 mm into the body: the surface holds the points back.
    assert "transitions over the stroke" in out and "OUTSIDE" in out


def test_a_missing_scene_is_named(tmp_path):
    done = demo_stroke(str(tmp_path / "nothing.hapticut.json"))
    assert done.returncode == 1
    assert "nothing.hapticut.json" in done.stderr and "Traceback" not in done.stderr
