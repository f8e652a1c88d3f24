"""Where the OpenHaptics stand-in is (server/devices/tests/hd_standin.h: libHD's C symbols
with its own scheduler thread, a script and a record of the calls, built with the C++
tests), for the tests that load it into the real servo through $HAPTICUT_OPENHAPTICS_LIB."""

from __future__ import annotations

from pathlib import Path

try:
    from standin_support import built_standin
except ImportError:  # Imported as tests.python.*, as the add-on's tests do.
    from tests.python.standin_support import built_standin

STANDIN_NAME = "libhapticut-hd-standin.so"


def standin_library() -> Path:
    return built_standin(STANDIN_NAME)
