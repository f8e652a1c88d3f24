"""Compatibility shim for this restructure only: hapticut.scene was split into hapticut.scenefile
(the file format) and hapticut.scenebuild (building scenes). Import from those; the integrator
removes this module once every branch is merged."""

import sys

from .. import scenebuild as _build
from .. import scenefile as _scenefile
from ..scenebuild import *  # noqa: F403
from ..scenebuild import __all__ as _build_all
from ..scenebuild import builder, errors, geometry, labels, quality, repair, report, tetwild, vtu
from ..scenefile import *  # noqa: F403
from ..scenefile import __all__ as _scenefile_all
from ..scenefile import format, model  # noqa: A004

# The old submodule paths (hapticut.scene.model, hapticut.scene.builder, ...) keep working.
for _module in (
    builder,
    errors,
    geometry,
    labels,
    quality,
    repair,
    report,
    tetwild,
    vtu,
    format,
    model,
):
    sys.modules[f"{__name__}.{_module.__name__.rsplit('.', 1)[1]}"] = _module

__all__ = [*_build_all, *_scenefile_all]
del sys, _build, _scenefile, _module
