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
from dataclasses import dataclass, field

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
    # servo_layout.CUT_BLOCK per record (read from the file's bytes).
    cut_block_records: np.ndarray = field(default_factory=lambda: np.zeros(0, layout.CUT_BLOCK))

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

    def elapsed_s(self) -> np.ndarray:
        """(T,): each record's time from the first one (a stroke's time, 0 at its start)."""
        times = np.asarray(self.ticks["time_s"], np.float64)
        return times - times[0] if len(times) else times

    def placed_poses(self, name: str, ticks) -> np.ndarray:
        """(K, 7): where a bake places the blade at the ticks. A rigid blade's solved pose
        (the whole knife held out of rigid material); for independent points, which have no
        pose of their own, the one ``fitted_poses`` fits to them."""
        ticks = np.asarray(ticks, np.int64)
        if self.coupling(name) == "rigid":
            solved = np.array(self.ideal_pose(name)[ticks], np.float64)
            solved[:, 3:] = _normalized(solved[:, 3:])
            return solved
        blade = self.blade(name)
        return fitted_poses(blade["block"]["pose"][ticks], blade["p"][ticks], blade["q"][ticks])

    def coupling(self, name: str) -> str:
        """``"rigid"`` or ``"independent"``: what the blade's ideal pose is."""
        self.blade(name)  # KeyError naming the blades for an unknown one.
        return next(b["coupling"] for b in self.header["blades"] if b["name"] == name)

    @property
    def cut_blocks(self) -> np.ndarray:
        """(T,) servo_layout.CUT_BLOCK: each record's cut block."""
        return self.cut_block_records

    def cut_order(self, upto: int | None = None) -> np.ndarray:
        """(k,) int32: the tets the scene had cut at the end of record ``upto`` (default the
        last), in the order they were cut: the engine's own cut set (the servo records its
        cut order, docs/servo.md), since the last reset_cuts before that record. The records
        carry the order a block at a time, so entries of a record's tick may come in the
        next records: they are read from there. RecordingError when records were dropped
        and the order has a hole."""
        blocks = self.cut_blocks
        if not len(blocks):
            return np.zeros(0, np.int32)
        upto = len(blocks) - 1 if upto is None else int(upto)
        generation = int(blocks[upto]["generation"])
        wanted = int(blocks[upto]["total"])
        order: list[int] = []
        for i in range(len(blocks)):
            block = blocks[i]
            if int(block["generation"]) != generation:
                if i > upto:
                    break
                continue
            first, carried = int(block["first"]), int(block["carried"])
            if first > len(order):
                raise RecordingError(
                    f"recording {self.path!r}: record {i} carries cut tets from {first} on, "
                    f"and the records before it carry {len(order)} (records were dropped)"
                )
            order[first:] = block["tets"][:carried].tolist()
            if i >= upto and len(order) >= wanted:
                break
        if len(order) < wanted:
            raise RecordingError(
                f"recording {self.path!r}: {wanted} tets were cut by record {upto}, its "
                f"records carry {len(order)} (it ended before the rest were written)"
            )
        return np.asarray(order[:wanted], np.int32)

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
    cuts = layout.cut_blocks(body, count, dtype.itemsize)
    partial = 0 if complete else len(body) - count * dtype.itemsize
    return Recording(os.fspath(path), header, records, not complete, partial, dropped, cuts)


def fitted_poses(poses: np.ndarray, p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """(K, 7) poses for independent points (K, N, 3) ``q`` driven by device points ``p`` at
    device poses (K, 7): the device's rotation turned by the shortest arc that lays its edge
    (first to last point) along the proxies' edge, moved so the device points' centre lands
    on the proxies' centre."""
    poses, p, q = (np.asarray(a, np.float64) for a in (poses, p, q))
    rotation = _normalized(poses[:, 3:7])
    turn = _shortest_arc(p[:, -1] - p[:, 0], q[:, -1] - q[:, 0])
    turned = _product(turn, rotation)
    local_centre = _rotate(_conjugate(rotation), p.mean(axis=1) - poses[:, :3])
    location = q.mean(axis=1) - _rotate(turned, local_centre)
    return np.concatenate([location, turned], axis=1)


# Quaternions as (K, 4) w, x, y, z.
def _normalized(quaternions: np.ndarray) -> np.ndarray:
    return quaternions / np.linalg.norm(quaternions, axis=1, keepdims=True)


def _conjugate(quaternions: np.ndarray) -> np.ndarray:
    return quaternions * np.array([1.0, -1.0, -1.0, -1.0])


def _product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    w1, v1, w2, v2 = a[:, :1], a[:, 1:], b[:, :1], b[:, 1:]
    w = w1 * w2 - np.sum(v1 * v2, axis=1, keepdims=True)
    return np.concatenate([w, w1 * v2 + w2 * v1 + np.cross(v1, v2)], axis=1)


def _rotate(quaternions: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    w, v = quaternions[:, :1], quaternions[:, 1:]
    t = 2.0 * np.cross(v, vectors)
    return vectors + w * t + np.cross(v, t)


def _shortest_arc(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The rotations turning the directions a onto b (identity where either has no length;
    half a turn about an axis across a where they are opposite)."""
    length_a = np.linalg.norm(a, axis=1, keepdims=True)
    length_b = np.linalg.norm(b, axis=1, keepdims=True)
    usable = (length_a[:, 0] > 1e-9) & (length_b[:, 0] > 1e-9)
    a = a / np.where(length_a > 1e-9, length_a, 1.0)
    b = b / np.where(length_b > 1e-9, length_b, 1.0)
    arc = np.concatenate([1.0 + np.sum(a * b, axis=1, keepdims=True), np.cross(a, b)], axis=1)
    opposite = usable & (arc[:, 0] < 1e-9)
    if opposite.any():
        across = np.cross(a[opposite], np.array([1.0, 0.0, 0.0]))
        small = np.linalg.norm(across, axis=1) < 1e-6
        across[small] = np.cross(a[opposite][small], np.array([0.0, 1.0, 0.0]))
        arc[opposite] = np.concatenate([np.zeros((len(across), 1)), across], axis=1)
    arc[~usable] = (1.0, 0.0, 0.0, 0.0)
    return _normalized(arc)
