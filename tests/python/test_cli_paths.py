"""``hapticut paths --json``: what the Blender add-on reads to load the client and start the
servo from the installed toolkit."""

import json
import os
import subprocess
import sys

import hapticut


def test_paths_names_the_package_and_the_servo():
    done = subprocess.run(
        [sys.executable, "-m", "hapticut.cli", "paths", "--json"],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    found = json.loads(done.stdout)
    assert found["package"] == os.path.dirname(os.path.abspath(hapticut.__file__))
    assert found["servo"] == hapticut.servo_path() and os.access(found["servo"], os.X_OK)
    assert found["servo_error"] == ""
    assert found["version"] == hapticut.__version__
    pure = ("servo_client.py", "recording.py", "servo_layout.py", "cut_surface.py", "cut_clip.py")
    for name in pure:
        assert os.path.isfile(os.path.join(found["package"], name))


def test_a_missing_servo_is_named(tmp_path):
    env = dict(os.environ, HAPTICUT_SERVO=str(tmp_path / "nothing"))
    done = subprocess.run(
        [sys.executable, "-m", "hapticut.cli", "paths", "--json"],
        capture_output=True, text=True, check=True, env=env,
    )  # fmt: skip
    found = json.loads(done.stdout)
    assert found["servo"] == ""
    assert "HAPTICUT_SERVO" in found["servo_error"]
