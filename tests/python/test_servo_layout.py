"""The frame and record layouts: C++ (hapticut-servo --print-layout) and Python agree."""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import numpy as np
import pytest
from hapticut import servo_layout as layout
from hapticut import servo_path
from servo_test_support import run_servo


@pytest.fixture(scope="module")
def printed() -> dict:
    result = run_servo("--print-layout")
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


@pytest.mark.parametrize(
    ("key", "dtype"),
    [
        ("frame_header", layout.FRAME_HEADER),
        ("record_header", layout.RECORD_HEADER),
        ("blade_block", layout.BLADE_BLOCK),
        ("recording_trailer", layout.RECORDING_TRAILER),
        ("cut_block", layout.CUT_BLOCK),
    ],
)
def test_fixed_structs_agree(printed, key, dtype):
    assert printed[key]["size"] == dtype.itemsize
    assert printed[key]["fields"] == layout.describe(dtype)


def test_points_block_and_versions_agree(printed):
    arrays = [(a["name"], a["type"], a["per_point"]) for a in printed["points_block"]["arrays"]]
    assert arrays == [
        (n, np.dtype(c).kind + str(np.dtype(c).itemsize), k) for n, c, k in layout.POINT_ARRAYS
    ]
    assert printed["points_block"]["align"] == 8
    assert printed["frame_version"] == layout.FRAME_VERSION
    assert printed["record_version"] == layout.RECORD_VERSION
    assert printed["max_frame_bytes"] == layout.MAX_FRAME_BYTES
    for points in (1, 7, 50, 500):
        assert layout.blade_dtype(points).itemsize == layout.BLADE_BLOCK.itemsize + (
            layout.points_block_bytes(points)
        )
        assert layout.blade_dtype(points).itemsize % 8 == 0


DOCS = Path(__file__).resolve().parents[2] / "docs"
DOC_TYPES = {
    "char": "S1",
    "u8": "u1",
    "u16": "u2",
    "u32": "u4",
    "u64": "u8",
    "i32": "i4",
    "f64": "f8",
}


def documented_struct(doc: str, name: str) -> tuple[int, list[dict]]:
    """The size and the rows (as --print-layout's fields) of the table after **name** (N
    bytes) in docs/doc."""
    text = (DOCS / doc).read_text()
    match = re.search(rf"\*\*{name}\*\* \((\d+) bytes\)", text)
    assert match, f"docs/{doc} has no **{name}** (N bytes) table"
    rows = []
    for line in text[match.end() :].splitlines():
        if rows and not line.startswith("|"):
            break
        cells = [c.strip() for c in line.strip("|").split("|")]
        if not line.startswith("|") or not cells[0].isdigit():
            continue
        offset, kind, field = int(cells[0]), cells[1], cells[2]
        array = re.fullmatch(r"(\w+)\[(\d+)\]", kind)
        base, shape = (array[1], [int(array[2])]) if array else (kind, [])
        assert base in DOC_TYPES, f"docs/{doc}, {name}.{field}: type {kind!r}"
        rows.append({"name": field, "type": DOC_TYPES[base], "offset": offset, "shape": shape})
    return int(match[1]), rows


@pytest.mark.parametrize(
    ("doc", "name", "key"),
    [
        ("protocol.md", "FrameHeader", "frame_header"),
        ("protocol.md", "BladeBlock", "blade_block"),
        ("servo.md", "RecordHeader", "record_header"),
        ("servo.md", "RecordingTrailer", "recording_trailer"),
        ("protocol.md", "CutBlock", "cut_block"),
    ],
)
def test_the_docs_tables_are_the_printed_layout(printed, doc, name, key):
    size, rows = documented_struct(doc, name)
    assert size == printed[key]["size"]
    assert rows == printed[key]["fields"]


def test_servo_path_names_a_missing_override(monkeypatch, tmp_path):
    monkeypatch.setenv("HAPTICUT_SERVO", str(tmp_path / "nope"))
    with pytest.raises(FileNotFoundError, match="HAPTICUT_SERVO"):
        servo_path()
    monkeypatch.delenv("HAPTICUT_SERVO")
    assert os.access(servo_path(), os.X_OK)
