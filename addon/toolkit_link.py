"""The toolkit's numpy-only modules, loaded inside Blender from the installed toolkit.

The servo client, the recording reader, the layouts and the cut surface have one source:
``core/hapticut`` (docs/addon.md). ``hapticut paths --json`` says where the installed package
is; its pure-Python files are loaded from there as the package ``hapticut`` without its
compiled module (``hapticut/__init__.py`` imports nothing compiled), so the client always
matches the servo it talks to. No bpy here.
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import os
import sys
from types import SimpleNamespace

from . import steps, toolkit

MODULES = ("servo_layout", "servo_client", "recording", "cut_surface")

_link: SimpleNamespace | None = None


def toolkit_paths_steps(
    executable: str, timeout_s: float = toolkit.QUICK_TIMEOUT_S
) -> steps.Steps[dict]:
    text = yield from toolkit.quick_steps(executable, "paths", "--json", timeout_s=timeout_s)
    try:
        return json.loads(text)
    except json.JSONDecodeError as error:
        raise toolkit.ToolkitError(f"hapticut paths --json printed no JSON ({error})") from None


def _package(directory: str):
    existing = sys.modules.get("hapticut")
    if existing is not None:
        where = os.path.dirname(os.path.abspath(existing.__file__ or ""))
        if os.path.realpath(where) != os.path.realpath(directory):
            raise toolkit.ToolkitError(
                f"another hapticut package is loaded ({where}), not the toolkit's ({directory})"
            )
        return existing
    spec = importlib.util.spec_from_file_location(
        "hapticut", os.path.join(directory, "__init__.py"), submodule_search_locations=[directory]
    )
    if spec is None or spec.loader is None:
        raise toolkit.ToolkitError(f"the toolkit's package at {directory} cannot be loaded")
    module = importlib.util.module_from_spec(spec)
    sys.modules["hapticut"] = module
    try:
        spec.loader.exec_module(module)
    except Exception:
        del sys.modules["hapticut"]
        raise
    return module


def link_steps(
    executable: str, refresh: bool = False, timeout_s: float = toolkit.QUICK_TIMEOUT_S
) -> steps.Steps[SimpleNamespace]:
    """The modules (``link.servo_client``, ...), ``link.servo`` (the servo executable) and
    ``link.executable`` (the toolkit's, for its children);
    toolkit.ToolkitError saying what is missing. Asks the toolkit once (at most timeout_s)."""
    global _link
    if _link is not None and not refresh:
        return _link
    found = yield from toolkit_paths_steps(executable, timeout_s)
    if not found.get("servo"):
        raise toolkit.ToolkitError(found.get("servo_error") or "the toolkit has no servo")
    package = _package(found["package"])
    modules = {}
    for name in MODULES:
        try:
            modules[name] = importlib.import_module(f"hapticut.{name}")
        except ImportError as error:
            raise toolkit.ToolkitError(
                f"the toolkit at {found['package']} has no usable hapticut.{name} ({error}); "
                f"reinstall it: {toolkit.INSTALL_COMMAND}"
            ) from None
    _link = SimpleNamespace(
        servo=found["servo"],
        executable=executable,
        package=package,
        version=found["version"],
        **modules,
    )
    return _link


def link(
    executable: str, refresh: bool = False, timeout_s: float = toolkit.QUICK_TIMEOUT_S
) -> SimpleNamespace:
    """link_steps in one call."""
    return steps.run_to_end(link_steps(executable, refresh, timeout_s))
