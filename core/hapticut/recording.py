"""Reading a servo recording (``hapticut-servo --record FILE``) with numpy alone.

    rec = read_recording("stroke.rec")
    rec.header["rate_Hz"], rec.blade_names       # the JSON header
    rec.ticks["time_s"]                          # (T,) per-tick fields (RECORD_HEADER)
    rec.blade("scalpel")["q"]                    # (T, N, 3) proxies, mm
    rec.blade("scalpel")["block"]["force_N"]     # (T, 3) force written to the device
    rec.ideal_pose("scalpel")                    # (T, 7) the ideal tool pose: x, y, z, qw..qz
    rec.truncated, rec.problem                   # cut short (no trailer): why, in words

The file is a magic, a JSON header, fixed-size records and a trailer (docs/servo.md);
a file without the trailer was cut short (the servo killed, a full disk): it is read
with every whole record and ``truncated`` set.
the layout lives in ``hapticut.servo_layout``. No compiled module: the
Blender add-on bakes from it.
"""

from __future__ import annotations

import json
import os
import stat
import struct
from dataclasses import dataclass

import numpy as np

from hapticut import servo_layout as layout


class RecordingError(ValueError):
    """A file that is not a readable recording; the message says why."""


@dataclass
class Recording:
    path: str
    header: dict
    records: np.ndarray  # Structured: "header" and one field per blade name.
    truncated: bool  # No trailer: the run was cut short; ``records`` are its whole records.
    truncated_bytes: int  # A partial last record (or trailer) that was dropped.
    dropped_records: int  # From the trailer: records lost while recording (0 when truncated).

    @property
    def problem(self) -> str:
        """Why the recording is incomplete, naming the file; "" when it is complete."""
        if not self.truncated:
            return ""
        text = (
            f"recording {self.path!r} is truncated (no end trailer: the run was cut short): "
            f"{len(self.records)} whole records"
        )
        if self.truncated_bytes:
            text += f", a partial last record of {self.truncated_bytes} bytes dropped"
        return text

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

    def ideal_pose(self, name: str) -> np.ndarray:
        """(T, 7): the blade's ideal tool pose per tick, x, y, z (mm), qw, qx, qy, qz; a rigid
        blade's solved pose, independent points' the device's (``coupling``)."""
        return layout.ideal_pose(self.blade(name))

    def coupling(self, name: str) -> str:
        """``"rigid"`` or ``"independent"``: what the blade's ideal pose is."""
        self.blade(name)  # KeyError naming the blades for an unknown one.
        return next(b["coupling"] for b in self.header["blades"] if b["name"] == name)

    def __len__(self) -> int:
        return len(self.records)


def _read_regular_file(path: str | os.PathLike, where: str) -> bytes:
    """A regular file's bytes (OSError when it cannot be opened). A FIFO or a device would
    block or never end (/dev/zero): refused before a byte is read; O_NONBLOCK keeps the open
    of a FIFO from waiting for a writer."""
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    info = os.fstat(fd)
    if not stat.S_ISREG(info.st_mode):
        os.close(fd)
        raise RecordingError(f"{where}: not a regular file")
    with os.fdopen(fd, "rb") as file:
        return file.read(info.st_size)


def read_recording(path: str | os.PathLike) -> Recording:
    where = f"recording {os.fspath(path)!r}"
    data = _read_regular_file(path, where)
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
            f"{where}: record version {header.get('version')}, this reader reads version "
            f"{layout.RECORD_VERSION} only (record it again with this servo)"
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
    trailer_bytes = layout.RECORDING_TRAILER.itemsize
    # The trailer is shorter than a record: a complete body is whole records, then it.
    complete = (
        len(body) % dtype.itemsize == trailer_bytes
        and bytes(body[-len(layout.RECORDING_END_MARKER) :]) == layout.RECORDING_END_MARKER
    )
    dropped = 0
    if complete:
        trailer = np.frombuffer(body[-trailer_bytes:], dtype=layout.RECORDING_TRAILER)[0]
        if int(trailer["record_count"]) != count:
            raise RecordingError(
                f"{where}: damaged: its trailer counts {int(trailer['record_count'])} records, "
                f"the file holds {count}"
            )
        dropped = int(trailer["dropped_records"])
    records = np.frombuffer(body[: count * dtype.itemsize], dtype=dtype)
    partial = 0 if complete else len(body) - count * dtype.itemsize
    return Recording(os.fspath(path), header, records, not complete, partial, dropped)
