"""The toolkit's numpy-only modules, loaded inside Blender from the installed toolkit, behind
one typed facade (``ToolkitLink``): what the add-on calls of them is listed there.

The servo client, the recording reader, the layouts and the cut surface have one source:
``core/hapticut`` (docs/addon.md). ``hapticut paths --json`` says where the installed package
is; its pure-Python files are loaded from there as the package ``hapticut`` without its
compiled module (``hapticut/__init__.py`` imports nothing compiled), so the client always
matches the servo it talks to. No bpy here.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import sys
from types import ModuleType
from typing import TYPE_CHECKING

from ..background import steps
from . import runner

if TYPE_CHECKING:  # The toolkit's own types, for readers and tools; loaded at run time below.
    import numpy as np
    from hapticut.cut_surface import CutSurface
    from hapticut.recording import Recording
    from hapticut.servo_client import ServoClient

MODULES = ("servo_layout", "servo_client", "recording", "cut_surface")


class ToolkitLink:
    """The installed toolkit as the add-on uses it: its executables and the calls the live
    link and the bake make into its numpy-only modules (``core/hapticut``)."""

    def __init__(self, servo: str, executable: str, version: str, modules: dict[str, ModuleType]):
        self.servo = servo  # The servo executable.
        self.executable = executable  # The toolkit's, for its children.
        self.version = version
        self.modules = modules  # By name (MODULES), as loaded from the installed package.
        self._servo_client = modules["servo_client"]
        self._recording = modules["recording"]
        self._cut_surface = modules["cut_surface"]

    @property
    def servo_error(self) -> type[Exception]:
        """What the servo client raises for a refused or unanswered message."""
        return self._servo_client.ServoError

    def servo_client(self, port: int, timeout_s: float) -> ServoClient:
        return self._servo_client.ServoClient(port=port, timeout_s=timeout_s)

    def cut_set(self):
        """An empty servo_client.CutSet: the scene's cut tets as the stream carries them."""
        return self._servo_client.CutSet()

    def read_recording(self, path: str) -> Recording:
        return self._recording.read_recording(path)

    def preview_tets(self, path: str) -> dict:
        return self._cut_surface.preview_tets(path)

    def frame_ticks(
        self, times_s: np.ndarray, fps: float, frame_start: int, frame_end: int | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        return self._cut_surface.frame_ticks(times_s, fps, frame_start, frame_end)

    def covered_steps(self, times_s: np.ndarray, step_s: float) -> int:
        return self._cut_surface.covered_steps(times_s, step_s)

    def read_cut_surfaces(self, path: str) -> dict[str, CutSurface]:
        return self._cut_surface.read_cut_surfaces(path)


_link: ToolkitLink | None = None


def _package(directory: str) -> ModuleType:
    existing = sys.modules.get("hapticut")
    if existing is not None:
        where = os.path.dirname(os.path.abspath(existing.__file__ or ""))
        if os.path.realpath(where) != os.path.realpath(directory):
            raise runner.ToolkitError(
                f"another hapticut package is loaded ({where}), not the toolkit's ({directory})"
            )
        return existing
    spec = importlib.util.spec_from_file_location(
        "hapticut", os.path.join(directory, "__init__.py"), submodule_search_locations=[directory]
    )
    if spec is None or spec.loader is None:
        raise runner.ToolkitError(f"the toolkit's package at {directory} cannot be loaded")
    module = importlib.util.module_from_spec(spec)
    sys.modules["hapticut"] = module
    try:
        spec.loader.exec_module(module)
    except Exception:
        del sys.modules["hapticut"]
        raise
    return module


def link_steps(
    executable: str, refresh: bool = False, timeout_s: float = runner.QUICK_TIMEOUT_S
) -> steps.Steps[ToolkitLink]:
    """The toolkit's link; runner.ToolkitError saying what is missing. Asks the toolkit once
    (at most timeout_s)."""
    global _link
    if _link is not None and not refresh:
        return _link
    found = yield from runner.json_steps(executable, "paths", timeout_s)
    if not found.get("servo"):
        raise runner.ToolkitError(found.get("servo_error") or "the toolkit has no servo")
    _package(found["package"])
    modules = {}
    for name in MODULES:
        try:
            modules[name] = importlib.import_module(f"hapticut.{name}")
        except ImportError as error:
            raise runner.ToolkitError(
                f"the toolkit at {found['package']} has no usable hapticut.{name} ({error}); "
                f"reinstall it: {runner.INSTALL_COMMAND}"
            ) from None
    _link = ToolkitLink(found["servo"], executable, found["version"], modules)
    return _link


def link(
    executable: str, refresh: bool = False, timeout_s: float = runner.QUICK_TIMEOUT_S
) -> ToolkitLink:
    """link_steps in one call."""
    return steps.run_to_end(link_steps(executable, refresh, timeout_s))
