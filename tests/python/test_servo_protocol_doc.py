"""docs/protocol.md against the real servo: every field of the `status` reply is named, and
the `"type": "error"` reply is what it says."""

from __future__ import annotations

import re
import struct
from pathlib import Path

import pytest
from servo_test_support import SPHERE, ServoProcess, connect

# Times a real servo's clock-paced threads: runs alone, never beside other tests
# (tests/run_all.sh runs the serial tests after the parallel ones).
pytestmark = pytest.mark.serial

PROTOCOL = Path(__file__).resolve().parents[2] / "docs" / "protocol.md"


def documented_status_names() -> set[str]:
    """The backquoted names in the protocol's `status` note."""
    text = PROTOCOL.read_text()
    start = text.index("- `status` returns")
    ends = (text.find("\n- ", start + 1), text.find("\n\n", start), len(text))
    end = min(i for i in ends if i != -1)
    return set(re.findall(r"`([A-Za-z_0-9]+)`", text[start:end]))


def field_names(value, prefix: str = "") -> set[str]:
    """Every key of a reply, nested ones as "parent.key" (lists: their first element's)."""
    if isinstance(value, list):
        return field_names(value[0], prefix) if value and isinstance(value[0], dict) else set()
    if not isinstance(value, dict):
        return set()
    names = set()
    for key, item in value.items():
        names.add(prefix + key)
        # device_counters and events are keyed by counter and flag names, not fields.
        if key not in ("device_counters", "events"):
            names |= field_names(item, f"{prefix}{key}.")
    return names


def test_every_status_field_is_documented():
    with ServoProcess([str(SPHERE), "--device", "scalpel=sim"]) as servo:
        client = connect(servo, ["scalpel"])
        status = client.status()
        client.close()
    assert status["state"] == "running" and status["blades"] and "settings" in status
    documented = documented_status_names()
    missing = sorted(
        name for name in field_names(status) if name.rsplit(".", 1)[-1] not in documented
    )
    assert not missing, f"status fields docs/protocol.md does not name: {missing}"


def test_a_message_without_a_request_type_gets_the_error_reply():
    with ServoProcess([str(SPHERE), "--device", "scalpel=sim"]) as servo:
        client = connect(servo, ["scalpel"])
        for payload, error in (
            (b'{"id": 7}', 'malformed message: expected an object with a string "type"'),
            (b'{"type": 7, "id": 7}', 'malformed message: expected an object with a string "type"'),
            (b"not json", "malformed JSON: "),
        ):
            client.send_raw(struct.pack(">I", len(payload)) + payload)
            reply = client.receive_message()
            assert set(reply) == {"type", "ok", "error"}, reply
            assert reply["type"] == "error" and reply["ok"] is False
            assert reply["error"].startswith(error)
        assert client.status()["state"] == "running"  # the connection goes on
        client.close()


def test_the_ranges_table_is_the_parameter_tables():
    """docs/protocol.md's "Ranges" table is what tools/protocol_ranges.py writes from the
    engine's parameter table (run it after changing parameter_range.h)."""
    import importlib.util

    from hapticut import _core

    tool = PROTOCOL.parents[1] / "tools" / "protocol_ranges.py"
    spec = importlib.util.spec_from_file_location("protocol_ranges", tool)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    written = module.current_section(PROTOCOL.read_text())
    assert written == module.generated_section(_core.setting_ranges()), (
        "docs/protocol.md's ranges table is stale: run python3 tools/protocol_ranges.py"
    )
