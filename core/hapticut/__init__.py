"""Hapticut: feel and animate a blade cutting through layered material.

The engine (``hapticut._core``, C++) implements the tetrahedral proxy method of
Tanaka, Hirota and Kaneko; this package adds scene files, scene building,
benchmarks and the ``hapticut`` command.
"""

# The repository's one version (VERSION): written into the package when it is built
# (pyproject.toml), read from the checkout in a source tree never built.
try:
    from ._version import __version__
except ImportError:
    from pathlib import Path as _Path

    __version__ = (_Path(__file__).resolve().parents[2] / "VERSION").read_text().strip()


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
