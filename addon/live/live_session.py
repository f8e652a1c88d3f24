"""A live session: the servo as a child process, its control channel and its state stream.

No bpy and no thread: everything here is called from the main thread (operators and the live
timer). ``tick`` is the timer's work, bounded by construction and never waiting: at most
``MAX_DATAGRAMS`` datagrams and ``BUDGET_S`` of draining; the poses and a status request
every ``STATUS_INTERVAL_S`` are sent without waiting for their replies (read by the next
ticks; at most ``MAX_UNANSWERED`` outstanding). A servo that exits or stops answering turns
the session ``lost`` with the reason; nothing raises out of ``tick``.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import time
from dataclasses import dataclass, field

from ..background import steps
from ..toolkit.toolkit_link import ToolkitLink

MAX_DATAGRAMS = 64
BUDGET_S = 0.002
STATUS_INTERVAL_S = 0.25
STARTUP_TIMEOUT_S = 15.0
REPLY_TIMEOUT_S = 5.0
# A scene of millions of tets takes the servo seconds to read and check.
LOAD_TIMEOUT_S = 120.0
# The servo's stop ramp and its recording's end; then it is killed.
SHUTDOWN_WAIT_S = 5.0
MAX_UNANSWERED = 64
# Exit codes of hapticut-servo (docs/servo.md).
EXIT_NETWORK = 5
# FrameHeader.servo_flags: the run is as fast as possible, its servo_time_s virtual (the run's
# start plus one period a tick, docs/protocol.md "Clock"), so no age can be read from it.
SERVO_FLAG_AS_FAST_AS_POSSIBLE = 4


class LiveServoError(RuntimeError):
    """Starting or talking to the servo failed; the message is for the panel."""


@dataclass
class LiveServo:
    """The add-on's hold on one running servo: its child process, control channel and state
    stream (the servo's own ``Session``, server/session.h, is a scene it has loaded)."""

    link: ToolkitLink
    process: subprocess.Popen
    log_path: str
    client: object  # servo_client.ServoClient
    state: str = "connected"  # connected, loading, running, simulating, lost, stopped
    error: str = ""
    stream_frame: object = None  # The newest servo_client.StreamFrame.
    cut_set: object = None  # servo_client.CutSet: the scene's cut tets, from the stream.
    cuts_pending: bool = False  # A cuts request is unanswered.
    status: dict = field(default_factory=dict)
    blades: list = field(default_factory=list)  # load reply's blades
    scene_path: str = ""
    build_digest: str = ""  # The add-on's digest of the build loaded (recording_stamp).
    preview_path: str = ""
    recording_path: str = ""  # The recording being written (or last written).
    simulate: dict | None = None  # While a stroke simulates: what the bake needs.
    last_status_s: float = 0.0
    status_pending: bool = False
    stream_frames_drawn: int = 0
    tick_costs_s: list = field(default_factory=list)
    stream_frame_ages_s: list = field(default_factory=list)  # Servo time to the timer's take.
    drawn_ages_s: list = field(default_factory=list)  # Servo time to the first draw (GUI only).

    @property
    def alive(self) -> bool:
        return self.state not in ("lost", "stopped")

    @property
    def running(self) -> bool:
        return self.status.get("state") == "running"


def _last_line(path: str) -> str:
    try:
        with open(path, encoding="utf-8", errors="replace") as file:
            lines = [line.strip() for line in file.read()[-20000:].splitlines() if line.strip()]
    except OSError:
        return ""
    errors = [line for line in lines if line.startswith("hapticut-servo:")]
    return (errors or lines or [""])[-1]


def start_steps(
    link: ToolkitLink,
    log_path: str,
    port: int = 0,
    realtime: bool = True,
    extra: tuple[str, ...] = (),
) -> steps.Steps[LiveServo]:
    """Start hapticut-servo with a control channel (``port``; 0: any free one), its output in
    log_path; connect and say hello. LiveServoError naming the problem (port busy, no servo)."""
    os.makedirs(os.path.dirname(log_path) or ".", exist_ok=True)
    command = [
        link.servo,
        "--control",
        str(int(port)),
        "--exit-when-done",
        "--record-buffer-s",
        "30",
        *(() if realtime else ("--no-realtime",)),
        *extra,
    ]
    with open(log_path, "w", encoding="utf-8") as log:
        try:
            process = subprocess.Popen(
                command,
                stdout=log,
                stderr=subprocess.STDOUT,
                stdin=subprocess.DEVNULL,
                start_new_session=True,
            )
        except OSError as error:
            raise LiveServoError(f"cannot start {link.servo}: {error}") from None
    began = time.monotonic()
    found_port = 0
    while not found_port:
        with contextlib.suppress(OSError), open(log_path, encoding="utf-8") as file:
            for line in file:
                if line.startswith("control: "):
                    found_port = int(line.rsplit(":", 1)[1])
        if found_port:
            break
        code = process.poll()
        if code is not None:
            line = _last_line(log_path)
            if code == EXIT_NETWORK:
                raise LiveServoError(f"port {port} is busy or cannot be opened ({line})")
            raise LiveServoError(f"the servo exited with code {code}: {line}")
        if time.monotonic() - began > STARTUP_TIMEOUT_S:
            _kill(process)
            raise LiveServoError(
                f"the servo did not open its control port in {STARTUP_TIMEOUT_S} s"
            )
        yield "starting the servo"
    client = link.servo_client(found_port, REPLY_TIMEOUT_S)
    try:
        client.connect()
        client.hello()
    except (OSError, link.servo_error) as error:
        _kill(process)
        raise LiveServoError(f"the servo does not answer on port {found_port}: {error}") from None
    return LiveServo(link, process, log_path, client)


def _kill(process: subprocess.Popen, grace_s: float = 5.0) -> None:
    if process.poll() is None:
        steps.end_group(process, grace_s)


def request(session: LiveServo, name: str, *args, **kwargs):
    """One control request; on a lost connection the session turns lost (LiveServoError)."""
    if not session.alive:
        raise LiveServoError(session.error or "no servo")
    try:
        return getattr(session.client, name)(*args, **kwargs)
    except session.link.servo_error as error:
        if "closed the connection" in str(error):
            lose(session, str(error))
        raise LiveServoError(str(error)) from None
    except (OSError, ValueError) as error:
        lose(session, f"the servo stopped answering ({error})")
        raise LiveServoError(session.error) from None


def lose(session: LiveServo, why: str) -> None:
    """The servo is gone: say why (its exit code and last line), free the sockets."""
    code = session.process.poll()
    line = _last_line(session.log_path)
    text = why
    if code is not None:
        text = f"the servo exited (code {code})" + (f": {line}" if line else "")
    session.state, session.error = "lost", text
    session.stream_frame = None
    session.simulate = None
    session.client.close()


# Session states while a request's reply is awaited in steps: ``tick`` leaves the replies to
# the steps then.
AWAITING = ("loading", "stopping")


def _load_steps(session: LiveServo, **fields) -> steps.Steps[dict]:
    """The load request, its reply awaited in steps (the servo reads and checks the scene
    meanwhile); LiveServoError as ``request`` raises it."""
    return (
        yield from _reply_steps(
            session, lambda client: client.send_load(**fields), "loading", "loading the scene",
            session.client.loaded, LOAD_TIMEOUT_S,
        )
    )  # fmt: skip


def _stop_run_steps(session: LiveServo) -> steps.Steps[dict]:
    """The stop request (the servo ramps the force down before it answers), awaited in
    steps."""
    return (
        yield from _reply_steps(
            session, lambda client: client.send_request("stop"), "stopping",
            "stopping the run", lambda reply: session.client.checked("stop", reply),
            REPLY_TIMEOUT_S,
        )
    )  # fmt: skip


def _reply_steps(session: LiveServo, send, state_while: str, what: str, taken, timeout_s: float):
    """The request send(client) sends (its id), its reply awaited in steps yielding ``what``
    and given to taken(reply); the session is in state_while meanwhile. LiveServoError as
    ``request`` raises it."""
    if not session.alive:
        raise LiveServoError(session.error or "no servo")
    client = session.client
    state, session.state = session.state, state_while
    began = time.monotonic()
    try:
        wanted = send(client)
        while True:
            for reply in client.replies():
                if reply.get("id") != wanted:
                    if reply.get("type") == "status" and reply.get("ok"):
                        session.status, session.status_pending = reply, False
                    continue
                session.state = state
                try:
                    return taken(reply)
                except session.link.servo_error as error:
                    raise LiveServoError(str(error)) from None
            if session.process.poll() is not None:
                lose(session, "the servo exited")
                raise LiveServoError(session.error)
            if time.monotonic() - began > timeout_s:
                lose(session, f"the servo did not answer ({what}) in {timeout_s:g} s")
                raise LiveServoError(session.error)
            yield what
    except session.link.servo_error as error:
        lose(session, str(error))
        raise LiveServoError(str(error)) from None
    except OSError as error:
        lose(session, f"the servo stopped answering ({error})")
        raise LiveServoError(session.error) from None
    finally:
        if session.state == state_while:
            session.state = state


def run_steps(
    session: LiveServo,
    scene_path: str,
    devices: list[str],
    rate_Hz: float,
    as_fast_as_possible: bool = False,
    record_path: str = "",
    settings: dict | None = None,
    engage: bool = False,
) -> dict:
    """Load the scene with these device bindings, apply the settings, subscribe, start."""
    if session.running:
        yield from _stop_run_steps(session)
    reply = yield from _load_steps(
        session,
        path=scene_path,
        devices=devices,
        rate_Hz=rate_Hz,
        as_fast_as_possible=as_fast_as_possible,
    )
    session.blades = reply["blades"]
    session.scene_path = scene_path
    # The ages shown are this run's.
    session.stream_frame_ages_s.clear()
    session.drawn_ages_s.clear()
    if settings:
        request(session, "set_parameters", **settings)
    request(session, "engage", engage)
    request(session, "subscribe", rate_Hz=120.0)
    if record_path:
        os.makedirs(os.path.dirname(record_path) or ".", exist_ok=True)
        # The servo never overwrites a recording: the last stroke's goes first.
        with contextlib.suppress(FileNotFoundError):
            os.remove(record_path)
        request(session, "record", record_path)
        session.recording_path = record_path
    request(session, "start")
    session.state = "simulating" if as_fast_as_possible else "running"
    session.status = request(session, "status")
    session.last_status_s = time.monotonic()
    return reply


def run(session: LiveServo, *args, **kwargs) -> dict:
    """run_steps in one call."""
    return steps.run_to_end(run_steps(session, *args, **kwargs))


def tick(session: LiveServo, poses: dict[str, list[float]] | None = None) -> bool:
    """The timer's work: drain the stream (bounded), send the viewport poses, refresh the
    status now and then, notice a lost servo. True when a new frame arrived."""
    began = time.perf_counter()
    if not session.alive or session.state in AWAITING:
        return False
    if session.process.poll() is not None:
        lose(session, "the servo exited")
        return False
    new = False
    client = session.client
    try:
        for reply in client.replies():
            if reply.get("type") == "status" and reply.get("ok"):
                session.status, session.status_pending = reply, False
            elif reply.get("type") == "cuts" and reply.get("ok"):
                session.cuts_pending = False
                if session.cut_set is not None:
                    session.cut_set.add_reply(reply)
            elif not reply.get("ok"):
                session.status_pending = session.status_pending and reply.get("type") != "status"
                session.cuts_pending = session.cuts_pending and reply.get("type") != "cuts"
                session.error = f"{reply.get('type')}: {reply.get('error', 'failed')}"
        frame = client.poll_newest(MAX_DATAGRAMS, BUDGET_S)
        if frame is not None:
            session.stream_frame, new = frame, True
            follow_cuts(session, frame)
            age_s = stream_frame_age_s(frame, time.monotonic())
            if age_s is not None:
                session.stream_frame_ages_s.append(age_s)
        if client.unanswered < MAX_UNANSWERED:
            for blade, pose in (poses or {}).items():
                client.send_request("pose", blade=blade, pose=[float(x) for x in pose], buttons=0)
        now = time.monotonic()
        if not session.status_pending and now - session.last_status_s >= STATUS_INTERVAL_S:
            session.last_status_s = now
            session.status_pending = True
            client.send_request("status")
    except session.link.servo_error as error:
        if "closed the connection" in str(error):
            lose(session, str(error))
        else:
            session.error = str(error)
    except (OSError, ValueError) as error:
        lose(session, f"the servo stopped answering ({error})")
    session.tick_costs_s.append(time.perf_counter() - began)
    del session.tick_costs_s[:-4096], session.stream_frame_ages_s[:-4096]
    del session.drawn_ages_s[:-4096]
    return new


def follow_cuts(session: LiveServo, frame) -> None:
    """Adds the cut tets the frame carries to the session's set; the timer takes only the
    newest frame, so the set often has a hole: one ``cuts`` request at a time fills it."""
    if session.cut_set is None:
        session.cut_set = session.link.cut_set()
    session.cut_set.take(frame)
    start = session.cut_set.wanted_from()
    if start is not None and not session.cuts_pending:
        session.client.send_request("cuts", **{"from": start})
        session.cuts_pending = True


def stop_steps(session: LiveServo) -> steps.Steps[None]:
    """Shut the servo down (its force ramps to zero) and wait for it; kill it if it hangs."""
    if session.process.poll() is None and session.state != "lost":
        with contextlib.suppress(Exception):
            session.client.request("shutdown")
    began = time.monotonic()
    try:
        while session.process.poll() is None and time.monotonic() - began < SHUTDOWN_WAIT_S:
            yield "stopping the servo"
    finally:
        _kill(session.process)
        session.client.close()
        session.state = "stopped"


def stream_frame_age_s(frame, now_s: float) -> float | None:
    """A frame's age at now_s (time.monotonic(), the servo's CLOCK_MONOTONIC): None when it
    has none, in a run as fast as possible (virtual servo time, ahead of the clock) or when
    the servo time lies in the future (another machine's clock)."""
    if int(frame.header["servo_flags"]) & SERVO_FLAG_AS_FAST_AS_POSSIBLE:
        return None
    age_s = now_s - float(frame.header["servo_time_s"])
    return age_s if age_s >= 0.0 else None


def age_text(ages_s: list) -> str:
    """p50 / p99 of frame ages, in ms ("" without samples)."""
    if not ages_s:
        return ""
    ordered = sorted(ages_s)

    def at(fraction: float) -> float:
        return 1000.0 * ordered[min(len(ordered) - 1, int(fraction * len(ordered)))]

    return f"{at(0.5):.1f} / {at(0.99):.1f} ms"
