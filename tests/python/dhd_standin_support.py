"""Where the DHD stand-in is (server/devices/tests/dhd_standin.h: libdhd's C symbols with a
script and a record of the calls, built with the C++ tests), for the tests that load it
into the real servo through $HAPTICUT_DHD_LIB."""

from __future__ import annotations

from pathlib import Path

try:
    from standin_support import built_standin
except ImportError:  # Imported as tests.python.*, as the add-on's tests do.
    from tests.python.standin_support import built_standin

STANDIN_NAME = "libhapticut-dhd-standin.so"


def standin_library() -> Path:
    return built_standin(STANDIN_NAME)
