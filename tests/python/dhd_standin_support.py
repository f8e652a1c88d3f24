"""Where the DHD stand-in is (server/devices/tests/dhd_standin.h: libdhd's C symbols with a
script and a record of the calls, built with the C++ tests), for the tests that load it
into the real servo through $HAPTICUT_DHD_LIB."""

from __future__ import annotations

import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
STANDIN_NAME = "libhapticut-dhd-standin.so"


def standin_library() -> Path:
    """The stand-in beside the servo under test ($HAPTICUT_SERVO, a build tree's), else in
    build/main (tests/scripts/setup.sh's build, with the C++ tests)."""
    candidates = []
    servo = os.environ.get("HAPTICUT_SERVO")
    if servo:
        candidates.append(Path(servo).resolve().parent / "devices" / STANDIN_NAME)
    candidates.append(ROOT / "build" / "main" / "server" / "devices" / STANDIN_NAME)
    for candidate in candidates:
        if candidate.is_file():
            return candidate
    raise AssertionError(
        f"the DHD stand-in was not built (looked at {', '.join(map(str, candidates))}); "
        "tests/scripts/setup.sh builds it with the C++ tests"
    )
