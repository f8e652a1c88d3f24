"""The vendor stand-in libraries (server/devices/tests/*_standin.h: a vendor library's C
symbols with a script and a record of the calls, built with the C++ tests), for the tests
that load one into the real servo through its environment variable: where each is, its
record of calls, and what the tests of the two arm kinds (test_servo_forcedimension.py,
test_servo_openhaptics.py) check alike of a session through one."""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]

DHD_STANDIN = "libhapticut-dhd-standin.so"  # Force Dimension's libdhd ($HAPTICUT_DHD_LIB)
# The same without dhdSetWatchdog and dhdGetWatchdog: a libdhd before SDK 3.3.2.
DHD_STANDIN_NO_WATCHDOG = "libhapticut-dhd-standin-no-watchdog.so"
HD_STANDIN = "libhapticut-hd-standin.so"  # OpenHaptics's libHD ($HAPTICUT_OPENHAPTICS_LIB)


def built_standin(file_name: str) -> Path:
    """The stand-in `file_name` beside the servo under test ($HAPTICUT_SERVO, a build
    tree's), else in build/main (tests/scripts/setup.sh's build, with the C++ tests)."""
    candidates = []
    servo = os.environ.get("HAPTICUT_SERVO")
    if servo:
        candidates.append(Path(servo).resolve().parent / "devices" / file_name)
    candidates.append(ROOT / "build" / "main" / "server" / "devices" / file_name)
    for candidate in candidates:
        if candidate.is_file():
            return candidate
    raise AssertionError(
        f"the stand-in {file_name} was not built (looked at "
        f"{', '.join(map(str, candidates))}); tests/scripts/setup.sh builds it with the C++ tests"
    )


@dataclass(frozen=True)
class Call:
    """One line of a stand-in's record: the call, its arguments (a force, a position, a
    parameter), its result and CLOCK_MONOTONIC at the call; OpenHaptics's also the
    scheduler's frame and whether the call was inside it."""

    name: str
    args: tuple[float, float, float]
    result: int
    time_s: float
    frame: int = 0
    in_frame: bool = False


def parse_call(line: str) -> Call:
    """A record line: "name a b c result time_s" (DHD) or "name a b c frame in_frame result
    time_s" (OpenHaptics)."""
    fields = line.split()
    name, args = fields[0], (float(fields[1]), float(fields[2]), float(fields[3]))
    if len(fields) == 6:
        return Call(name, args, int(fields[4]), float(fields[5]))
    frame, in_frame, result, time_s = fields[4:]
    return Call(name, args, int(result), float(time_s), int(frame), in_frame == "1")


@dataclass
class Standin:
    """A stand-in loaded into the servos a test starts: its script and its record."""

    log: Path
    library_variable: str
    script_variable: str
    monkeypatch: pytest.MonkeyPatch

    def script(self, text: str) -> None:
        self.monkeypatch.setenv(self.script_variable, text)

    def name_library(self, path: str) -> None:
        """The servo loads `path` in the stand-in's place."""
        self.monkeypatch.setenv(self.library_variable, path)

    def calls(self) -> list[Call]:
        """The record the stand-in wrote when the servo closed the device."""
        return [parse_call(line) for line in self.log.read_text().splitlines()]


def use_standin(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, file_name: str, library_variable: str, prefix
) -> Standin:
    """The stand-in `file_name` named to the servo by `library_variable`, scripted by
    $PREFIX (empty until `script`) and recording to $PREFIX_LOG."""
    log = tmp_path / f"{file_name}.calls.txt"
    monkeypatch.setenv(library_variable, str(built_standin(file_name)))
    monkeypatch.setenv(f"{prefix}_LOG", str(log))
    monkeypatch.delenv(prefix, raising=False)
    return Standin(log, library_variable, prefix, monkeypatch)


def index_of(calls: list[Call], name: str, start: int = 0, a: float | None = None) -> int:
    """The first call named `name` (with first argument `a`, when given) from `start`."""
    return next(
        i
        for i in range(start, len(calls))
        if calls[i].name == name and (a is None or calls[i].args[0] == a)
    )


def counters(status: dict) -> dict:
    return status["blades"][0]["device_counters"]


def run_session(scene: Path, record: Path, binding: str, until, timeout_s: float = 20.0) -> dict:
    """The servo with `binding` as the blade scalpel, engaged and recorded, until
    `until(status)` holds; its last status."""
    # Imported here: the add-on's tests, in Blender's Python, import this module for
    # built_standin alone, without the toolkit's compiled module servo_test_support needs.
    from servo_test_support import ServoProcess, connect

    args = [str(scene), "--device", f"scalpel={binding}"]
    args += ["--engage", "--ramp", "0.05", "--record", str(record)]
    with ServoProcess(args) as servo:
        client = connect(servo, ["scalpel"])
        deadline = time.monotonic() + timeout_s
        status = client.status()
        while not until(status) and time.monotonic() < deadline:
            time.sleep(0.05)
            status = client.status()
        client.close()
        assert servo.stop() == 0
    return status


def load_and_run(binding: str, before=None, samples: int = 100) -> dict:
    """A servo started on the sim device, then `load`ed by a client with `binding` (after
    `before(client)`, when given), run until the device gave `samples` samples; its last
    status."""
    from servo_test_support import SPHERE, ServoProcess, connect

    with ServoProcess(["--device", "sim"]) as servo:
        client = connect(servo)
        if before is not None:
            before(client)
        loaded = client.load(SPHERE, devices=[binding])
        assert loaded["blades"][0]["kind"] == binding.split(":")[0]
        client.start()
        deadline = time.monotonic() + 20.0
        while counters(client.status()).get("samples", 0) < samples and time.monotonic() < deadline:
            time.sleep(0.05)
        status = client.status()
        client.close()
        assert servo.stop() == 0
    return status


EXIT_DEVICE = 4  # docs/servo.md


def check_refused_at_start(
    standin: Standin, kind: str, script: str | None, library: str | None, message: str
) -> None:
    """The servo bound to `kind` with the stand-in scripted by `script` (or with `library`
    named in its place) ends at the start as a device error, naming the binding and saying
    `message`."""
    from servo_test_support import SPHERE, run_servo

    if script is not None:
        standin.script(script)
    if library is not None:
        standin.name_library(library)
    result = run_servo(str(SPHERE), "--device", f"scalpel={kind}", "--duration", "0.5")
    assert result.returncode == EXIT_DEVICE, result.stderr
    assert message in result.stderr
    assert "scalpel" in result.stderr  # The binding is named.


def listing(kind: str) -> dict:
    """`--list-devices --json` at 500 Hz: the object of `kind`."""
    from servo_test_support import run_servo

    result = run_servo("--list-devices", "--json", "--rate", "500")
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)[kind]


def check_listed_without_library(standin: Standin, kind: str, missing: str) -> None:
    """With `missing` named as the library, the listing says the library was not found and
    why (dlerror()'s words), and lists no devices."""
    standin.name_library(missing)
    found = listing(kind)
    assert found["library_found"] is False and found["devices"] == []
    assert "No such file" in found["error"]


def print_sample_to_force(kind: str, found: dict) -> None:
    """The latency the device measured, as its status counters give it (not asserted)."""
    print(
        f"\nsample to force through the {kind} stand-in at 1 kHz: "
        f"median {found['sample_to_force_ns_p50'] / 1e3:.1f} us, "
        f"p99 {found['sample_to_force_ns_p99'] / 1e3:.1f} us ({found['samples']} samples)"
    )


def check_session_recorded_and_replayed(
    scene: Path, record: Path, pushed: list[tuple[float, float, float]], max_force_N: float
) -> None:
    """Each force that reached the arm (`pushed`, in the scene's axes) is one the servo
    recorded; the descent drove the blade past the clamp; the recorded proxies equal an
    offline engine run of the recorded poses, and a replay of the recording gives them
    again bit for bit."""
    from hapticut.servo_layout import flag_bit
    from servo_test_support import REPLAYED_BLOCK_FIELDS, bake, offline_check, read_recording

    recording = read_recording(record)
    block = recording.blade("scalpel")["block"]
    recorded = {tuple(float(v) + 0.0 for v in f) for f in block["force_N"]}
    assert len(pushed) > 500
    assert all(f in recorded for f in pushed), "a force reached the arm that was not recorded"
    z = block["pose"][:, 2]
    # The descent, in mm: the device's own scheduler may run its first frames before the
    # servo's first recorded tick (a slow start under ThreadSanitizer), so its top may not be.
    assert z.min() < -9.0 and z.max() > z.min() + 5.0
    engine = np.linalg.norm(block["engine_force_N"], axis=1)
    assert engine.max() > max_force_N, "the engine never asked for more than the clamp"
    assert np.any(block["safety_flags"] & flag_bit("force_clamped"))
    assert offline_check(scene, recording, "scalpel") > 500

    # The session replayed without the arm: the same proxies and engine forces, bit for bit.
    replayed = record.with_name("replayed.rec")
    bake(scene, replayed, f"scalpel=replay:{record}")
    again = read_recording(replayed).blade("scalpel")
    n = len(recording)
    original = recording.blade("scalpel")
    for name in ("q", "p", "state"):
        assert np.array_equal(original[name], again[name][:n]), name
    for name in REPLAYED_BLOCK_FIELDS:
        assert np.array_equal(original["block"][name], again["block"][name][:n]), name


def check_lost_then_ramped_back(record: Path) -> None:
    """The recording of a session with one fault: pushing before it, zero in the tick that
    saw the device lost and every tick until it was back, then the force ramped back in."""
    from hapticut.servo_layout import flag_bit
    from servo_test_support import read_recording

    block = read_recording(record).blade("scalpel")["block"]
    force = np.linalg.norm(block["force_N"], axis=1)
    lost = np.nonzero(block["events"] & flag_bit("device_lost"))[0]
    assert len(lost) == 1
    k = int(lost[0])
    assert force[k - 1] > 0.05 and force[k] == 0.0
    back = k + int(np.argmax(block["device_status"][k:] != 2))
    assert back > k and np.all(force[k:back] == 0.0)
    assert block["ramp"][back] < 0.2
    assert force[back:].max() > 0.05
