"""A bridge for the servo's UDP bridge device that needs no hardware.

A scripted hand (a mass on a spring and a damper pulled along a path) stands
in for a force device: every tick it sends its pose to the servo and feels
the force the servo answers with, so the loop is closed as with a real arm.
A bridge for a real device replaces ``ScriptedHand`` with the vendor SDK's
calls (docs/devices.md, "Writing a bridge"). Standard library and numpy only.

    hapticut-servo scene.hapticut.json --device scalpel=bridge:port=47810 &
    python3 examples/bridge_example.py --servo 127.0.0.1:47810 --duration 5

Fault drills for the tests: ``--silent-after S`` stops sending (the servo
must call the device lost), ``--garbage-every N`` replaces every Nth datagram
with a malformed one (the servo must refuse and count it). ``--summary``
prints what happened as one JSON line at the end.
"""

from __future__ import annotations

import argparse
import json
import math
import socket
import struct
import sys
import time

import numpy as np

# The two datagrams of docs/devices.md ("The bridge format"), little-endian.
MAGIC = 0x50424348  # "HCBP"
VERSION = 1
POSE_KIND = 1
FORCE_KIND = 2
# magic, version, kind, sequence, time_s, position_mm[3], rotation wxyz[4],
# buttons, flags, sequence of the last force applied.
POSE = struct.Struct("<IHHQd3d4dIIQ")
# magic, version, kind, sequence, time_s, force_N[3], torque_N_mm[3],
# sequence of the pose used, flags, zero.
FORCE = struct.Struct("<IHHQd3d3dQII")
assert POSE.size == 96 and FORCE.size == 88

# The bridge's own safety: a force older than this is not rendered.
FORCE_TIMEOUT_S = 0.05


class ScriptedHand:
    """A point mass (kg) on a spring (N/mm) and a damper (N s/mm) towards a path (mm)."""

    def __init__(self, mass_kg=0.2, spring_N_per_mm=0.3, damping_N_s_per_mm=0.002):
        self.mass_kg = mass_kg
        self.spring = spring_N_per_mm
        self.damping = damping_N_s_per_mm
        self.position_mm = self.target(0.0)
        self.velocity_mm_per_s = np.zeros(3)

    @staticmethod
    def target(t_s: float) -> np.ndarray:
        """Down from 10 mm above the origin to 10 mm below it in 1 s, sweeping sideways."""
        return np.array([20.0 * math.sin(math.pi * t_s), 0.0, 10.0 - 20.0 * min(t_s, 1.0)])

    def step(self, t_s: float, force_N: np.ndarray, dt_s: float) -> None:
        pull = (self.target(t_s) - self.position_mm) * self.spring
        drag = self.velocity_mm_per_s * self.damping
        acceleration = (pull - drag + force_N) * (1000.0 / self.mass_kg)  # mm/s^2
        self.velocity_mm_per_s = self.velocity_mm_per_s + acceleration * dt_s
        self.position_mm = self.position_mm + self.velocity_mm_per_s * dt_s


def garbage(index: int, valid: bytes) -> bytes:
    """Malformed datagrams of every kind the servo refuses, in turn."""
    kinds = [
        lambda: valid[:50],  # truncated
        lambda: b"\x00" * 4 + valid[4:],  # bad magic
        lambda: valid[:4] + struct.pack("<H", 99) + valid[6:],  # bad version
        lambda: valid[:24] + struct.pack("<d", float("nan")) + valid[32:],  # NaN position
        lambda: bytes(np.random.default_rng(index).integers(0, 256, 96, dtype=np.uint8)),
        lambda: valid + b"\x00" * 100,  # oversized
    ]
    return kinds[index % len(kinds)]()


def parse_address(text: str) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    return (host or "127.0.0.1", int(port))


def run(args: argparse.Namespace) -> dict:
    servo = parse_address(args.servo)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    sock.setblocking(False)
    hand = ScriptedHand()
    dt_s = 1.0 / args.rate
    summary = {
        "poses_sent": 0,
        "garbage_sent": 0,
        "forces_received": 0,
        "forces_refused": 0,
        "max_force_N": 0.0,
        "last_force_sequence": 0,
        "min_z_mm": float(hand.position_mm[2]),
    }
    force_N = np.zeros(3)
    force_time = -1.0
    force_sequence = 0
    start = time.monotonic()
    next_tick = start
    tick = 0
    while True:
        now = time.monotonic()
        t_s = now - start
        if t_s >= args.duration:
            break
        # Drain the socket: the newest force wins.
        while True:
            try:
                data = sock.recv(2048)
            except BlockingIOError:
                break
            if len(data) != FORCE.size:
                summary["forces_refused"] += 1
                continue
            fields = FORCE.unpack(data)
            if fields[0] != MAGIC or fields[1] != VERSION or fields[2] != FORCE_KIND:
                summary["forces_refused"] += 1
                continue
            if fields[3] <= force_sequence:
                continue
            force_sequence = fields[3]
            force_N = np.array(fields[5:8])
            force_time = now
            summary["forces_received"] += 1
            summary["max_force_N"] = max(summary["max_force_N"], float(np.linalg.norm(force_N)))
        rendered = force_N if now - force_time <= FORCE_TIMEOUT_S else np.zeros(3)
        hand.step(t_s, rendered, dt_s)
        summary["min_z_mm"] = min(summary["min_z_mm"], float(hand.position_mm[2]))

        silent = args.silent_after is not None and t_s >= args.silent_after
        if not silent:
            tick += 1
            pose = POSE.pack(
                MAGIC, VERSION, POSE_KIND, tick, now, *hand.position_mm, 1.0, 0.0, 0.0, 0.0,
                0, 0, force_sequence,
            )  # fmt: skip
            if args.garbage_every and tick % args.garbage_every == 0:
                pose = garbage(tick // args.garbage_every, pose)
                summary["garbage_sent"] += 1
            else:
                summary["poses_sent"] += 1
            sock.sendto(pose, servo)
        next_tick += dt_s
        time.sleep(max(0.0, next_tick - time.monotonic()))
    summary["last_force_sequence"] = force_sequence
    sock.close()
    return summary


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--servo", default="127.0.0.1:47810", help="the bridge device's HOST:PORT")
    parser.add_argument("--rate", type=float, default=1000.0, help="poses per second")
    parser.add_argument("--duration", type=float, default=5.0, help="seconds to run")
    parser.add_argument("--silent-after", type=float, default=None, help="stop sending after S s")
    parser.add_argument("--garbage-every", type=int, default=0, help="every Nth datagram garbage")
    parser.add_argument("--summary", action="store_true", help="print a JSON summary at the end")
    args = parser.parse_args(argv)
    if not 10.0 <= args.rate <= 5000.0:
        parser.error("--rate must be between 10 and 5000")
    summary = run(args)
    if args.summary:
        print(json.dumps(summary), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
