"""hapticut-servo's command line and ``hapticut serve``: options documented, exit codes."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys

import pytest
from servo_test_support import SPHERE, run_servo, stats_of

# Times a real servo's clock-paced threads: runs alone, never beside other tests
# (tests/run_all.sh runs the serial tests after the parallel ones).
pytestmark = pytest.mark.serial

SERVO_SOURCE_OPTIONS = SPHERE.parents[1] / "server" / "options.cpp"


def test_help_documents_every_option():
    result = run_servo("--help")
    assert result.returncode == 0
    parsed = set(re.findall(r'arg == "(--[a-z-]+)"', SERVO_SOURCE_OPTIONS.read_text()))
    assert len(parsed) > 20
    for option in parsed:
        assert option in result.stdout, option
    for kind in ("sim", "replay", "viewport"):
        assert f"  {kind}" in result.stdout
    assert "Exit codes" in result.stdout


def test_usage_errors_exit_2():
    for args, message in [
        (["--rate", "20000"], "--rate"),
        (["--frobnicate"], "unknown option --frobnicate"),
        (["--duration"], "needs a value"),
        ([], "nothing to do"),
    ]:
        result = run_servo(*args)
        assert result.returncode == 2, (args, result.stderr)
        assert message in result.stderr


def test_record_file_that_cannot_be_written_exits_6(tmp_path):
    result = run_servo(
        str(SPHERE), "--device", "sim", "--record", str(tmp_path / "no" / "such" / "dir.rec")
    )
    assert result.returncode == 6 and "dir.rec" in result.stderr


def test_hapticut_serve_runs_the_servo(tmp_path):
    record = tmp_path / "serve.rec"
    command = [sys.executable, "-m", "hapticut.cli", "serve", str(SPHERE), "--device", "sim:press"]
    command += ["--as-fast-as-possible", "--exit-when-done", "--record", str(record)]
    result = subprocess.run(command, capture_output=True, text=True, timeout=60, check=False)
    assert result.returncode == 0, result.stderr
    stats = stats_of(result.stdout)
    assert stats["ended_by_itself"] and stats["recording"]["written"] == stats["ticks"] > 100
    help_result = subprocess.run(
        [sys.executable, "-m", "hapticut.cli", "serve", "--help-servo"],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert help_result.returncode == 0 and "--device" in help_result.stdout


def test_cpu_pins_the_loop_and_refuses_what_is_not_a_cpu():
    cpu = max(os.sched_getaffinity(0))
    result = run_servo("--bare-loop", "--rate", "1000", "--duration", "0.2", "--cpu", str(cpu))
    assert result.returncode == 0, result.stderr
    assert f"loop pinned to CPU {cpu}" in json.loads(result.stdout)["realtime"]
    # A CPU the machine does not have: one clear line, and the loop runs unpinned.
    result = run_servo("--bare-loop", "--rate", "1000", "--duration", "0.2", "--cpu", "1000")
    assert result.returncode == 0, result.stderr
    out = json.loads(result.stdout)
    assert "loop not pinned to CPU 1000" in out["realtime"]
    assert out["ticks"] > 0
    for value in ("-1", "1.5", "1024", "two"):
        result = run_servo("--bare-loop", "--cpu", value)
        assert result.returncode == 2, (value, result.stderr)
        assert "--cpu" in result.stderr


def test_cpu_keeps_the_servos_other_threads_off_the_loops_cpu():
    cpus = sorted(os.sched_getaffinity(0))
    result = run_servo(str(SPHERE), "--device", "sim", "--duration", "0.2", "--cpu", str(cpus[-1]))
    assert result.returncode == 0, result.stderr
    assert f"loop pinned to CPU {cpus[-1]}" in result.stdout
    if len(cpus) > 1:
        assert f"other threads kept off CPU {cpus[-1]}" in result.stdout
    else:
        assert "is the only CPU allowed" in result.stdout
