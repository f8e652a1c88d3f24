"""``hapticut bench stability``: the passivity controller's table (docs/stability.md).

The bench itself is C++ (server/devices/stability.cpp): a virtual hand presses
on bone through the engine at servo rates of 250 Hz to 1 kHz and link delays of
0 to 5 ms, without and with the passivity controller: first at the stiffnesses
the servo allows a device at each rate (its stiffness limit), then a stress
test beyond them. This runs the installed ``hapticut-stability`` and returns
its tables.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import hapticut


def stability_path() -> Path:
    """The hapticut-stability executable: $HAPTICUT_STABILITY, else the one in the package."""
    override = os.environ.get("HAPTICUT_STABILITY")
    if override:
        return Path(override)
    return Path(hapticut.__file__).resolve().parent / "bin" / "hapticut-stability"


def run(extra_args: list[str] | None = None) -> str:
    executable = stability_path()
    if not executable.is_file():
        raise FileNotFoundError(
            f"{executable}: hapticut-stability is not installed (pip install . builds it "
            "with HAPTICUT_BUILD_DEVICES on)"
        )
    result = subprocess.run(
        [str(executable), *(extra_args or [])], capture_output=True, text=True, check=False
    )
    if result.returncode != 0:
        raise RuntimeError(f"{executable} failed ({result.returncode}): {result.stderr.strip()}")
    return result.stdout
