"""Hapticut: feel and animate a blade cutting through layered material.

The engine (``hapticut._core``, C++) implements the tetrahedral proxy method of
Tanaka, Hirota and Kaneko; this package adds scene files, scene building,
benchmarks and the ``hapticut`` command.
"""

from importlib.metadata import version as _version

# The repository's one version (VERSION), as pip installed it (pyproject.toml).
__version__ = _version("hapticut")


def servo_path() -> str:
    """The ``hapticut-servo`` executable installed with this package.

    ``$HAPTICUT_SERVO`` overrides it (a build tree's binary). Raises
    FileNotFoundError saying how to get one when it is missing.
    """
    import os

    override = os.environ.get("HAPTICUT_SERVO")
    if override:
        if not os.access(override, os.X_OK):
            raise FileNotFoundError(f"HAPTICUT_SERVO={override!r} is not an executable file")
        return override
    here = os.path.dirname(os.path.abspath(__file__))
    path = os.path.join(here, "bin", "hapticut-servo")
    if not os.access(path, os.X_OK):
        raise FileNotFoundError(
            f"hapticut-servo not found at {path}: this hapticut was installed without the "
            "servo (reinstall with `pip install .`, which builds it with "
            "HAPTICUT_BUILD_SERVO=ON), or set HAPTICUT_SERVO to a built binary"
        )
    return path
