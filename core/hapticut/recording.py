"""Reading a servo recording (``hapticut-servo --record FILE``) with numpy alone.

    rec = read_recording("stroke.rec")
    rec.header["rate_Hz"], rec.blade_names       # the JSON header
    rec.ticks["time_s"]                          # (T,) per-tick fields (RECORD_HEADER)
    rec.blade("scalpel")["q"]                    # (T, N, 3) proxies, mm
    rec.blade("scalpel")["block"]["force_N"]     # (T, 3) force written to the device

The file is a magic, a JSON header and fixed-size records (docs/servo.md);
the layout lives in ``hapticut.servo_layout``. No compiled module: the
Blender add-on bakes from it.
"""

from __future__ import annotations

import json
import os
import struct
from dataclasses import dataclass

import numpy as np

from hapticut import servo_layout as layout


class RecordingError(ValueError):
    """A file that is not a readable recording; the message says why."""


@dataclass
class Recording:
    header: dict
    records: np.ndarray  # Structured: "header" and one field per blade name.
    truncated_bytes: int  # A partial last record (a run cut short) that was dropped.

    @property
    def blade_names(self) -> list[str]:
        return [b["name"] for b in self.header["blades"]]

    @property
    def ticks(self) -> np.ndarray:
        return self.records["header"]

    def blade(self, name: str) -> np.ndarray:
        if name not in self.blade_names:
            raise KeyError(
                f"recording has no blade {name!r} (it has: {', '.join(self.blade_names)})"
            )
        return self.records[name]

    def __len__(self) -> int:
        return len(self.records)


def read_recording(path: str | os.PathLike) -> Recording:
    data = open(path, "rb").read()  # noqa: SIM115 - whole file, closed by refcount
    where = f"recording {os.fspath(path)!r}"
    if len(data) < 16 or data[:8] != layout.RECORDING_MAGIC:
        raise RecordingError(f"{where}: not a hapticut recording (no HCREC001 magic)")
    (length,) = struct.unpack_from("<Q", data, 8)
    if length > len(data) - 16:
        raise RecordingError(f"{where}: header of {length} bytes is longer than the file")
    try:
        header = json.loads(data[16 : 16 + length].decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise RecordingError(f"{where}: header is not JSON ({error})") from error
    if header.get("version") != layout.RECORD_VERSION:
        raise RecordingError(
            f"{where}: record version {header.get('version')}, this reader reads "
            f"{layout.RECORD_VERSION}"
        )
    names = [b["name"] for b in header["blades"]]
    points = [int(b["points"]) for b in header["blades"]]
    dtype = layout.record_dtype(points, names)
    if dtype.itemsize != header["record_bytes"]:
        raise RecordingError(
            f"{where}: records of {header['record_bytes']} bytes, this reader's layout makes "
            f"{dtype.itemsize}"
        )
    body = memoryview(data)[16 + length :]
    count = len(body) // dtype.itemsize
    records = np.frombuffer(body[: count * dtype.itemsize], dtype=dtype)
    return Recording(header, records, len(body) - count * dtype.itemsize)
