"""The servo's binary layouts on the Python side: stream frames and recording records.

The C++ side declares them once in ``server/layout.h``; this module declares
them once here, as numpy dtypes, and ``tests/python/test_servo_layout.py``
checks the two against ``hapticut-servo --print-layout``. Pure numpy: the
Blender add-on imports it without the compiled module.

A frame:  FRAME_HEADER, then per blade: BLADE_BLOCK, its points block; a CUT_BLOCK.
A record: RECORD_HEADER, then per blade: BLADE_BLOCK, its points block; a CUT_BLOCK.
A recording ends with RECORDING_TRAILER, written when it is closed cleanly.
Points block of N points: q (N, 3) f8, p (N, 3) f8, state (N,) u1, zero
padding to a multiple of 8 bytes.
"""

from __future__ import annotations

import numpy as np

FRAME_VERSION = 4
RECORD_VERSION = 5
FRAME_MAGIC = b"HCFR"
RECORDING_MAGIC = b"HCREC001"
RECORDING_END_MARKER = b"HCRECEND"
MAX_FRAME_BYTES = 65507

FRAME_HEADER = np.dtype(
    [
        ("magic", "S1", (4,)),
        ("version", "<u2"),
        ("blade_count", "<u2"),
        ("frame_bytes", "<u4"),
        ("session", "<u4"),
        ("sequence", "<u8"),
        ("tick", "<u8"),
        ("servo_time_s", "<f8"),
        ("dt_s", "<f8"),
        ("compute_p50_us", "<f8"),
        ("compute_p99_us", "<f8"),
        ("compute_max_us", "<f8"),
        ("wake_p50_us", "<f8"),
        ("wake_p99_us", "<f8"),
        ("wake_max_us", "<f8"),
        ("late_ticks", "<u8"),
        ("dropped_records", "<u8"),
        ("servo_flags", "<u4"),
        ("reserved", "<u4"),
    ]
)

RECORD_HEADER = np.dtype(
    [
        ("tick", "<u8"),
        ("time_s", "<f8"),
        ("dt_s", "<f8"),
        ("compute_us", "<f8"),
        ("wake_latency_us", "<f8"),
        ("late_ticks", "<u8"),
        ("dropped_records", "<u8"),
        ("servo_flags", "<u4"),
        ("blade_count", "<u4"),
    ]
)

BLADE_BLOCK = np.dtype(
    [
        ("pose", "<f8", (7,)),  # The device's: x, y, z (mm), qw, qx, qy, qz.
        ("ideal_pose", "<f8", (7,)),  # The engine's (Blade::ideal_pose), as pose.
        ("engine_force_N", "<f8", (3,)),
        ("engine_torque_N_mm", "<f8", (3,)),
        ("force_N", "<f8", (3,)),
        ("torque_N_mm", "<f8", (3,)),
        ("ramp", "<f8"),
        ("step_dt_s", "<f8"),
        ("point_count", "<u4"),
        ("buttons", "<u4"),
        ("safety_flags", "<u4"),
        ("events", "<u4"),
        ("state_counts", "<u2", (5,)),
        ("capped_points", "<u2"),
        ("device_status", "u1"),
        ("step_kind", "u1"),
        ("max_transitions", "<u2"),
        ("stiffness_N_per_mm", "<f8"),
        ("rejected_ticks", "<u8"),
        ("out_of_workspace_ticks", "<u8"),
        ("unfinished_ticks", "<u8"),
        ("transitions", "<u4"),
        ("deferred_points", "<u2"),
        ("engine_rejected", "u1"),
        ("force_shading", "u1"),
    ]
)

# The next entries of the scene's cut order (the cut tets, in the order they were cut) after
# those the last frame, or record, carried: a reader that gets every one rebuilds the set by
# appending (docs/protocol.md, "Cut tets"). Last in a frame and in a record.
CUT_BLOCK_TETS = 64
CUT_BLOCK = np.dtype(
    [
        ("generation", "<u4"),  # Changes with every reset_cuts or load_cuts.
        ("total", "<u4"),  # Tets cut after this tick: the order's length.
        ("before_tick", "<u4"),  # Tets cut when the tick began.
        ("first", "<u4"),  # The order's index of tets[0].
        ("carried", "<u2"),  # Entries of tets in use.
        ("capacity", "<u2"),
        ("reserved", "<u4"),
        ("tets", "<i4", (CUT_BLOCK_TETS,)),
    ]
)

# After the last record of a recording closed cleanly; shorter than any record. The
# marker is last: a complete file's final 8 bytes.
RECORDING_TRAILER = np.dtype(
    [
        ("record_count", "<u8"),
        ("dropped_records", "<u8"),  # Lost (ring full) while the file was open.
        ("end_marker", "S1", (8,)),
    ]
)

# Per point, in this order, each as one array over the blade's points.
POINT_ARRAYS = (("q", "<f8", 3), ("p", "<f8", 3), ("state", "u1", 1))

# BladeBlock.safety_flags / events bits, in bit order (server/safety.h).
SAFETY_FLAGS = (
    "engaged",
    "ramping",
    "force_clamped",
    "torque_clamped",
    "device_lost",
    "watchdog",
    "non_finite_pose",
    "outside_workspace",
    "non_finite_force",
    "passivity",
    "no_force_output",
    "stale",
    "waiting",
    "stopping",
    "engine_rejected",
    "late_tick",
)
FAULT_FLAGS = (
    "device_lost",
    "watchdog",
    "non_finite_pose",
    "outside_workspace",
    "non_finite_force",
    "engine_rejected",
    "late_tick",
)
DEVICE_STATUS = ("fresh", "stale", "lost")
STEP_KINDS = ("none", "step", "reset_and_step")


def flag_bit(name: str) -> int:
    """The bit of a safety flag by name (``flag_bit("device_lost") == 16``)."""
    return 1 << SAFETY_FLAGS.index(name)


FAULT_MASK = sum(flag_bit(name) for name in FAULT_FLAGS)


def ideal_pose(blade: np.void | np.ndarray) -> np.ndarray:
    """The blade's ideal tool pose, x, y, z (mm), qw, qx, qy, qz: (7,) from a frame's blade,
    (T, 7) from a recording's. A rigid blade's solved pose (its knife rests on the bone);
    for independent points, the device's pose (``"coupling"`` in the recording's header
    and the ``load`` reply says which)."""
    return np.asarray(blade["block"]["ideal_pose"])


def points_block_bytes(points: int) -> int:
    return (points * 6 * 8 + points + 7) // 8 * 8


def blade_dtype(points: int) -> np.dtype:
    """One blade's BladeBlock and points block as one structured dtype."""
    fields: list = [("block", BLADE_BLOCK)]
    for name, code, per_point in POINT_ARRAYS:
        fields.append((name, code, (points, per_point) if per_point > 1 else (points,)))
    pad = points_block_bytes(points) - points * 49
    if pad:
        fields.append(("padding", "u1", (pad,)))
    return np.dtype(fields)


def _with_blades(header: np.dtype, names: list[str], points: list[int]) -> np.dtype:
    """The header and the blades as fields; the CUT_BLOCK after them is in the itemsize, not a
    field (a blade may have any name): ``cut_blocks`` reads it."""
    fields: list = [("header", header)]
    fields += [(name, blade_dtype(n)) for name, n in zip(names, points, strict=True)]
    packed = np.dtype(fields)
    return np.dtype(
        {
            "names": list(packed.names),
            "formats": [packed.fields[name][0] for name in packed.names],
            "offsets": [packed.fields[name][1] for name in packed.names],
            "itemsize": packed.itemsize + CUT_BLOCK.itemsize,
        }
    )


def cut_blocks(buffer, count: int, record_bytes: int) -> np.ndarray:
    """(count,) CUT_BLOCK, a copy: the cut block of each of ``count`` records (or frames) of
    ``record_bytes`` each in ``buffer``, its last CUT_BLOCK.itemsize bytes. Read from the
    bytes, not from a structured array of the records: the block is no field of theirs, and
    numpy need not copy the bytes between fields."""
    if count == 0:
        return np.zeros(0, CUT_BLOCK)
    return np.ndarray(
        (count,),
        CUT_BLOCK,
        buffer=buffer,
        offset=record_bytes - CUT_BLOCK.itemsize,
        strides=(record_bytes,),
    ).copy()


def stream_frame_dtype(points: list[int], names: list[str] | None = None) -> np.dtype:
    """A whole frame for blades with these point counts (fields ``blade0``, ... by default)."""
    names = names or [f"blade{i}" for i in range(len(points))]
    return _with_blades(FRAME_HEADER, names, points)


def record_dtype(points: list[int], names: list[str]) -> np.dtype:
    """A whole record: ``header``, then one field per blade, named after the blade."""
    return _with_blades(RECORD_HEADER, names, points)


def describe(dtype: np.dtype) -> list[dict]:
    """Fields as ``--print-layout`` lists them: name, type code, offset, shape."""
    out = []
    for name in dtype.names:
        sub, offset = dtype.fields[name][:2]
        base = sub.base if sub.subdtype else sub
        code = "S1" if base.kind == "S" else base.kind + str(base.itemsize)
        out.append(
            {
                "name": name,
                "type": code,
                "offset": offset,
                "shape": list(sub.shape) if sub.shape else [],
            }
        )
    return out
