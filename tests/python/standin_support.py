"""Where the vendor stand-in libraries are (server/devices/tests/*_standin.h: a vendor
library's C symbols with a script and a record of the calls, built with the C++ tests), for
the tests that load one into the real servo through its environment variable."""

from __future__ import annotations

import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def built_standin(file_name: str) -> Path:
    """The stand-in `file_name` beside the servo under test ($HAPTICUT_SERVO, a build
    tree's), else in build/main (tests/scripts/setup.sh's build, with the C++ tests)."""
    candidates = []
    servo = os.environ.get("HAPTICUT_SERVO")
    if servo:
        candidates.append(Path(servo).resolve().parent / "devices" / file_name)
    candidates.append(ROOT / "build" / "main" / "server" / "devices" / file_name)
    for candidate in candidates:
        if candidate.is_file():
            return candidate
    raise AssertionError(
        f"the stand-in {file_name} was not built (looked at "
        f"{', '.join(map(str, candidates))}); tests/scripts/setup.sh builds it with the C++ tests"
    )
