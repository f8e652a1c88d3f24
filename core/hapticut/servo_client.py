"""A client for hapticut-servo's protocol (docs/protocol.md), standard library and numpy only.

    with ServoProcess(["scene.hapticut.msgpack", "--wait", "--device", "scalpel=sim"]) as servo:
        client = ServoClient(port=servo.port)
        client.hello()
        client.subscribe(rate_Hz=120)
        client.start()
        frame = client.poll()          # the newest frame, or None; never blocks
        frame.blades["scalpel"]["q"]   # (N, 3) proxies, mm
        client.stop()

The Blender add-on uses this same file from a timer on the main thread
(``poll`` drains the socket and keeps only the newest frame), so it must not
import the compiled ``hapticut._core``.
"""

from __future__ import annotations

import json
import os
import socket
import struct
import subprocess
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from hapticut import servo_layout as layout

PROTOCOL_VERSION = 3
MAX_MESSAGE_BYTES = 16 << 20


class ServoError(RuntimeError):
    """The servo answered with an error, or the connection failed; the message says which."""


@dataclass
class StreamFrame:
    header: np.void  # layout.FRAME_HEADER
    blades: dict[str, np.void]  # name -> layout.blade_dtype(points) ("block", "q", "p", "state")
    received_s: float  # time.monotonic() on arrival (the servo's clock: CLOCK_MONOTONIC)
    cuts: np.void | None = None  # layout.CUT_BLOCK: the cut tets it carries (CutSet.take)

    @property
    def sequence(self) -> int:
        """From 1 at every ``start``, shared by all subscribers: compare with ``order``."""
        return int(self.header["sequence"])

    @property
    def session(self) -> int:
        """The run the frame belongs to: increments with every ``start``."""
        return int(self.header["session"])

    @property
    def order(self) -> tuple[int, int]:
        """Newer frames are larger, across runs too (the sequence restarts at each start)."""
        return (self.session, self.sequence)

    def ideal_pose(self, blade: str) -> np.ndarray:
        """The blade's ideal tool pose (7,): x, y, z (mm), qw, qx, qy, qz
        (``servo_layout.ideal_pose``)."""
        return layout.ideal_pose(self.blades[blade])

    @property
    def age_s(self) -> float:
        """Arrival time minus the tick's time (both CLOCK_MONOTONIC, same machine)."""
        return self.received_s - float(self.header["servo_time_s"])


def parse_stream_frame(
    data: bytes, names: Sequence[str] | None = None, received_s: float = 0.0
) -> StreamFrame:
    """One datagram -> StreamFrame. ValueError naming what is wrong for anything else."""
    size = layout.FRAME_HEADER.itemsize
    if len(data) < size:
        raise ValueError(f"frame of {len(data)} bytes is shorter than its header ({size})")
    header = np.frombuffer(data, dtype=layout.FRAME_HEADER, count=1)[0]
    if bytes(header["magic"].tobytes()) != layout.FRAME_MAGIC:
        raise ValueError("not a hapticut frame (magic)")
    if int(header["version"]) != layout.FRAME_VERSION:
        raise ValueError(f"frame version {int(header['version'])}, expected {layout.FRAME_VERSION}")
    if int(header["frame_bytes"]) != len(data):
        raise ValueError(f"frame says {int(header['frame_bytes'])} bytes, got {len(data)}")
    blades: dict[str, np.void] = {}
    offset = size
    for i in range(int(header["blade_count"])):
        if offset + layout.BLADE_BLOCK.itemsize > len(data):
            raise ValueError(f"frame ends inside blade {i}")
        points = int(np.frombuffer(data, layout.BLADE_BLOCK, 1, offset)[0]["point_count"])
        dtype = layout.blade_dtype(points)
        if offset + dtype.itemsize > len(data):
            raise ValueError(f"frame ends inside blade {i}'s points")
        name = names[i] if names is not None and i < len(names) else f"blade{i}"
        blades[name] = np.frombuffer(data, dtype, 1, offset)[0]
        offset += dtype.itemsize
    if offset + layout.CUT_BLOCK.itemsize != len(data):
        raise ValueError(
            f"frame of {len(data)} bytes: its blades end at {offset}, and its cut block is "
            f"{layout.CUT_BLOCK.itemsize} bytes"
        )
    cuts = np.frombuffer(data, layout.CUT_BLOCK, 1, offset)[0]
    if int(cuts["carried"]) > layout.CUT_BLOCK_TETS:
        raise ValueError(f"cut block carries {int(cuts['carried'])} tets, over its room")
    return StreamFrame(header, blades, received_s, cuts)


class CutSet:
    """The scene's cut tets as a client keeps them from the stream: each frame carries the
    next entries of the servo's cut order (servo_layout.CUT_BLOCK); a frame that is not the
    next (a lost datagram, a slower subscription, a client that joined late) asks for the
    rest over the control channel (``ServoClient.cuts``). ``order`` is the servo's cut
    order, ``tets`` the same as a set."""

    def __init__(self) -> None:
        self.generation: int | None = None
        self.order: list[int] = []
        self.tets: set[int] = set()
        self.total = 0  # What the newest frame says the servo has cut.
        self.fills = 0  # Times a hole was filled over the control channel.

    def take(self, frame: StreamFrame, client: ServoClient | None = None) -> bool:
        """Adds what ``frame`` carries; True when the set is whole up to the frame's tick.
        A frame of another generation (the cuts were reset or loaded) starts the set again;
        one that leaves a hole is filled from ``client`` when given (else False)."""
        block = frame.cuts
        if block is None:
            return False
        generation, first = int(block["generation"]), int(block["first"])
        carried = int(block["carried"])
        self.total = int(block["total"])
        if generation != self.generation:
            self.generation, self.order, self.tets = generation, [], set()
        if first > len(self.order):
            if client is None:
                return False
            self._fill(client)
        else:
            self._append(block["tets"][:carried].tolist()[len(self.order) - first :])
        return len(self.order) >= self.total

    def wanted_from(self) -> int | None:
        """Where a ``cuts`` request should start for the set to be whole (None: it is): for a
        client that pipelines its requests (the add-on's timer) rather than waiting in
        ``take``; its reply goes to ``add_reply``."""
        return None if len(self.order) >= self.total else len(self.order)

    def add_reply(self, reply: dict) -> None:
        """A ``cuts`` reply: appended when it goes on from what the set holds; one of a new
        generation starting at the first entry starts the set again; any other is stale (the
        next frame asks again)."""
        generation, start = int(reply["generation"]), int(reply["from"])
        if generation != self.generation:
            if start != 0:
                return
            self.generation, self.order, self.tets = generation, [], set()
        if start == len(self.order):
            self.fills += 1
            self._append([int(t) for t in reply["tets"]])
        self.total = max(self.total, int(reply["total"]))

    def _fill(self, client: ServoClient) -> None:
        self.fills += 1
        generation, tets = client.cuts(len(self.order))
        if generation != self.generation:
            self.generation, self.order, self.tets = generation, [], set()
            generation, tets = client.cuts(0)
        self._append(tets.tolist())

    def _append(self, tets: list[int]) -> None:
        self.order += tets
        self.tets.update(tets)


_SESSION_OFFSET = layout.FRAME_HEADER.fields["session"][1]
_SEQUENCE_OFFSET = layout.FRAME_HEADER.fields["sequence"][1]


def _order_of(data: bytes) -> tuple[int, int] | None:
    """A datagram's (session, sequence) from its header alone (``StreamFrame.order``), or None
    when it is no frame."""
    if len(data) < layout.FRAME_HEADER.itemsize or data[:4] != layout.FRAME_MAGIC:
        return None
    (session,) = struct.unpack_from("<I", data, _SESSION_OFFSET)
    (sequence,) = struct.unpack_from("<Q", data, _SEQUENCE_OFFSET)
    return (int(session), int(sequence))


def _load_fields(path, scene, devices, rate_Hz, as_fast_as_possible) -> dict:
    fields: dict = {}
    if path is not None:
        fields["path"] = os.fspath(path)
    if scene is not None:
        fields["scene"] = scene
    if devices is not None:
        fields["devices"] = list(devices)
    if rate_Hz is not None:
        fields["rate_Hz"] = rate_Hz
    if as_fast_as_possible is not None:
        fields["as_fast_as_possible"] = as_fast_as_possible
    return fields


class ServoClient:
    """The control channel (TCP, length-prefixed JSON) and the stream (UDP)."""

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = 0,
        timeout_s: float = 10.0,
        token: str | None = None,
    ) -> None:
        self.host = host
        self.port = port
        self.timeout_s = timeout_s
        self.token = token
        self.blade_names: list[str] = []
        self.frames_received = 0
        self.bad_datagrams = 0
        self.datagrams_read = 0
        # Datagrams from any sender but the servo's stream socket, ignored: any local
        # process can send to the stream port.
        self.foreign_datagrams = 0
        self.stream_source: tuple[str, int] | None = None  # The servo's (address, port).
        self._sock: socket.socket | None = None
        self._stream: socket.socket | None = None
        self._next_id = 0
        self._inbox = b""  # Bytes of replies read ahead (send_request / replies).
        self._unanswered = 0  # Requests sent by send_request whose replies were not read.
        self._early: list[dict] = []  # Their replies, read while request() waited for its own.

    # Connection.
    def connect(self) -> ServoClient:
        if self._sock is None:
            self._sock = socket.create_connection((self.host, self.port), timeout=self.timeout_s)
            self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        return self

    def close(self) -> None:
        for s in (self._sock, self._stream):
            if s is not None:
                s.close()
        self._sock = self._stream = None

    def __enter__(self) -> ServoClient:
        return self.connect()

    def __exit__(self, *exc) -> None:
        self.close()

    # Messages.
    def send_raw(self, payload: bytes) -> None:
        """Bytes as they are (tests of malformed input)."""
        self.connect()
        assert self._sock is not None
        self._sock.sendall(payload)

    def send_message(self, message: dict) -> None:
        text = json.dumps(message).encode("utf-8")
        self.send_raw(struct.pack(">I", len(text)) + text)

    def receive_message(self) -> dict:
        header = self._receive_exactly(4)
        (length,) = struct.unpack(">I", header)
        if length > MAX_MESSAGE_BYTES:
            raise ServoError(f"reply of {length} bytes is over the limit")
        return json.loads(self._receive_exactly(length).decode("utf-8"))

    def _receive_exactly(self, n: int) -> bytes:
        assert self._sock is not None
        chunks = [self._inbox[:n]]
        self._inbox = self._inbox[n:]
        n -= len(chunks[0])
        while n:
            chunk = self._sock.recv(n)
            if not chunk:
                raise ServoError("the servo closed the connection")
            chunks.append(chunk)
            n -= len(chunk)
        return b"".join(chunks)

    def request(self, message_type: str, check: bool = True, **fields) -> dict:
        """Send one message and wait for its reply; ServoError when it is an error (if check)."""
        self._next_id += 1
        message = {"type": message_type, "id": self._next_id, **fields}
        self.send_message(message)
        while self._unanswered:  # Replies come in order: the earlier ones first.
            self._early.append(self.receive_message())
            self._unanswered -= 1
        reply = self.receive_message()
        return self.checked(message_type, reply) if check else reply

    @staticmethod
    def checked(message_type: str, reply: dict) -> dict:
        """The reply; ServoError naming the request when it is an error."""
        if not reply.get("ok"):
            raise ServoError(f"{message_type}: {reply.get('error', 'failed')}")
        return reply

    def send_request(self, message_type: str, **fields) -> int:
        """Send one message without waiting for its reply (``replies`` returns it); its id."""
        self._next_id += 1
        self.send_message({"type": message_type, "id": self._next_id, **fields})
        self._unanswered += 1
        return self._next_id

    @property
    def unanswered(self) -> int:
        """Requests sent by ``send_request`` whose replies ``replies`` has not returned yet."""
        return self._unanswered + len(self._early)

    def replies(self) -> list[dict]:
        """The replies to ``send_request`` that have arrived, in order; never blocks.
        ServoError when the servo closed the connection."""
        out, self._early = self._early, []
        if not self._unanswered:
            return out
        assert self._sock is not None
        self._sock.settimeout(0.0)  # A socket with a timeout would wait for data first.
        try:
            while True:
                try:
                    chunk = self._sock.recv(1 << 16)
                except (BlockingIOError, InterruptedError):
                    break
                if not chunk:
                    raise ServoError("the servo closed the connection")
                self._inbox += chunk
        finally:
            self._sock.settimeout(self.timeout_s)
        while self._unanswered and len(self._inbox) >= 4:
            (length,) = struct.unpack(">I", self._inbox[:4])
            if length > MAX_MESSAGE_BYTES:
                raise ServoError(f"reply of {length} bytes is over the limit")
            if len(self._inbox) < 4 + length:
                break
            text, self._inbox = self._inbox[4 : 4 + length], self._inbox[4 + length :]
            out.append(json.loads(text.decode("utf-8")))
            self._unanswered -= 1
        return out

    def hello(self) -> dict:
        fields = {"version": PROTOCOL_VERSION}
        if self.token is not None:
            fields["token"] = self.token
        reply = self.request("hello", **fields)
        # The same protocol with other layouts would be misread frame by frame: say so once.
        for name, mine in (("frame", layout.FRAME_VERSION), ("record", layout.RECORD_VERSION)):
            theirs = reply.get(f"{name}_version")
            if theirs != mine:
                raise ServoError(
                    f"the servo writes {name} version {theirs}, this client reads version "
                    f"{mine}: use the hapticut toolkit of the servo's release"
                )
        self._learn_stream_source(reply)
        return reply

    def _learn_stream_source(self, reply: dict) -> None:
        """The servo sends frames from ``stream_source_port`` on the address the control
        channel reached; frames from anywhere else are not its."""
        assert self._sock is not None
        self.stream_source = (self._sock.getpeername()[0], int(reply["stream_source_port"]))

    def load(
        self,
        path: str | os.PathLike | None = None,
        scene: dict | None = None,
        devices: Sequence[str] | None = None,
        rate_Hz: float | None = None,
        as_fast_as_possible: bool | None = None,
    ) -> dict:
        fields = _load_fields(path, scene, devices, rate_Hz, as_fast_as_possible)
        return self.loaded(self.request("load", check=False, **fields))

    def send_load(
        self,
        path: str | os.PathLike | None = None,
        scene: dict | None = None,
        devices: Sequence[str] | None = None,
        rate_Hz: float | None = None,
        as_fast_as_possible: bool | None = None,
    ) -> int:
        """``load`` without waiting for the servo to read the scene: ``replies`` returns the
        reply (give it to ``loaded``); the request's id."""
        fields = _load_fields(path, scene, devices, rate_Hz, as_fast_as_possible)
        return self.send_request("load", **fields)

    def loaded(self, reply: dict) -> dict:
        """A load's reply taken: ServoError when it is an error; else the frames' blades are
        the ones it names."""
        self.checked("load", reply)
        self.blade_names = [b["name"] for b in reply["blades"]]
        return reply

    def start(self) -> dict:
        return self.request("start")

    def stop(self) -> dict:
        return self.request("stop")

    def status(self) -> dict:
        return self.request("status")

    def engage(self, engaged: bool = True) -> dict:
        return self.request("engage", engaged=engaged)

    def set_parameters(self, **parameters) -> dict:
        return self.request("set", **parameters)

    def record(self, path: str | os.PathLike) -> dict:
        return self.request("record", action="start", path=os.fspath(path))

    def stop_recording(self) -> dict:
        return self.request("record", action="stop")

    def send_pose(self, blade: str, pose: Sequence[float], buttons: int = 0) -> dict:
        return self.request("pose", blade=blade, pose=[float(x) for x in pose], buttons=buttons)

    def cuts(self, from_index: int = 0) -> tuple[int, np.ndarray]:
        """The scene's cut tets in the order they were cut, from ``from_index`` on: (their
        generation, int32 array), asked a reply at a time (``cuts``, docs/protocol.md)."""
        tets: list[int] = []
        generation = None
        while True:
            reply = self.request("cuts", **{"from": from_index + len(tets)})
            if generation is not None and reply["generation"] != generation:
                tets, generation = [], None  # Reset between two replies: start again.
                continue
            generation = reply["generation"]
            tets += reply["tets"]
            if not reply["more"]:
                return int(generation), np.asarray(tets, np.int32)

    def reset_cuts(self) -> dict:
        return self.request("reset_cuts")

    def save_cuts(self, path: str | os.PathLike) -> dict:
        return self.request("save_cuts", path=os.fspath(path))

    def load_cuts(self, path: str | os.PathLike) -> dict:
        return self.request("load_cuts", path=os.fspath(path))

    def shutdown(self) -> dict:
        return self.request("shutdown")

    # Stream.
    def subscribe(self, rate_Hz: float = 120.0) -> dict:
        if self._stream is None:
            self._stream = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            self._stream.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
            self._stream.bind(("127.0.0.1", 0))
            self._stream.setblocking(False)
        reply = self.request("subscribe", port=self._stream.getsockname()[1], rate_Hz=rate_Hz)
        self._learn_stream_source(reply)
        return reply

    def _receive_datagram(self) -> tuple[bytes | None, float] | None:
        """The next datagram waiting and its arrival time; None when none waits. A datagram
        from another sender than the servo's stream socket comes back as None data, counted
        (``foreign_datagrams``): it is read, so it counts against a caller's bound."""
        assert self._stream is not None
        try:
            data, sender = self._stream.recvfrom(layout.MAX_FRAME_BYTES + 1)
        except (BlockingIOError, InterruptedError):
            return None
        now = time.monotonic()
        self.datagrams_read += 1
        if sender[:2] != self.stream_source:
            self.foreign_datagrams += 1
            return None, now
        return data, now

    def unsubscribe(self) -> dict:
        return self.request("unsubscribe")

    def poll(self) -> StreamFrame | None:
        """The newest complete frame waiting on the stream socket, or None. Never blocks."""
        frames = self.poll_all()
        return frames[-1] if frames else None

    def poll_newest(self, max_datagrams: int = 64, budget_s: float = 0.002) -> StreamFrame | None:
        """The newest frame among at most ``max_datagrams`` waiting datagrams, read for at most
        ``budget_s``; None when none came. Bounded by construction (a timer of the add-on
        calls it): only the newest datagram read is parsed whole; datagrams beyond the bound
        wait for the next call."""
        if self._stream is None:
            return None
        began = time.monotonic()
        newest_data, newest_order, newest_s = None, (-1, -1), 0.0
        for _ in range(max_datagrams):
            received = self._receive_datagram()
            if received is None:
                break
            data, now = received
            if data is not None:
                order = _order_of(data)
                if order is None:
                    self.bad_datagrams += 1
                elif order > newest_order:
                    newest_data, newest_order, newest_s = data, order, now
            if now - began >= budget_s:
                break
        if newest_data is None:
            return None
        try:
            frame = parse_stream_frame(newest_data, self.blade_names or None, newest_s)
        except ValueError:
            self.bad_datagrams += 1
            return None
        self.frames_received += 1
        return frame

    def poll_all(self) -> list[StreamFrame]:
        """Every frame waiting, oldest first (out-of-order ones dropped). Never blocks."""
        if self._stream is None:
            return []
        out: list[StreamFrame] = []
        newest = (-1, -1)
        while (received := self._receive_datagram()) is not None:
            data, now = received
            if data is None:
                continue
            try:
                frame = parse_stream_frame(data, self.blade_names or None, now)
            except ValueError:
                self.bad_datagrams += 1
                continue
            if frame.order <= newest:
                continue
            newest = frame.order
            self.frames_received += 1
            out.append(frame)
        return out


@dataclass
class ServoProcess:
    """hapticut-servo as a child process with a control channel on a free loopback port.

    ``args`` are the servo's own (scene, --device, ...); ``--control 0`` is
    added. Its stdout is collected on a thread (``lines``; the final
    ``stats`` line is ``stats()``).
    """

    args: Sequence[str]
    executable: str | None = None
    control: bool = True
    startup_timeout_s: float = 30.0
    process: subprocess.Popen | None = None
    port: int = 0
    lines: list[str] = field(default_factory=list)
    stderr_lines: list[str] = field(default_factory=list)
    _threads: list[threading.Thread] = field(default_factory=list)

    def start(self) -> ServoProcess:
        if self.executable is None:
            from hapticut import servo_path

            self.executable = servo_path()
        command = [self.executable, *self.args] + (["--control", "0"] if self.control else [])
        self.process = subprocess.Popen(
            command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, bufsize=1
        )
        port_ready = threading.Event()

        def read_stdout() -> None:
            assert self.process is not None and self.process.stdout is not None
            for line in self.process.stdout:
                self.lines.append(line.rstrip("\n"))
                if line.startswith("control: "):
                    self.port = int(line.rsplit(":", 1)[1])
                    port_ready.set()
            port_ready.set()

        def read_stderr() -> None:
            assert self.process is not None and self.process.stderr is not None
            for line in self.process.stderr:
                self.stderr_lines.append(line.rstrip("\n"))

        self._threads = [
            threading.Thread(target=read_stdout, daemon=True),
            threading.Thread(target=read_stderr, daemon=True),
        ]
        for t in self._threads:
            t.start()
        if self.control:
            port_ready.wait(self.startup_timeout_s)
            if not self.port:
                self.wait(5)
                raise ServoError(
                    f"hapticut-servo did not open its control port (exit {self.process.poll()}): "
                    + " | ".join(self.stderr_lines[-5:])
                )
        return self

    def wait(self, timeout_s: float | None = None) -> int:
        assert self.process is not None
        code = self.process.wait(timeout_s)
        for t in self._threads:
            t.join(5)
        return code

    def stats(self) -> dict | None:
        """The last ``stats`` line the servo printed (after a run ended), parsed."""
        for line in reversed(self.lines):
            if line.startswith("stats "):
                return json.loads(line[len("stats ") :])
        return None

    def stop(self, timeout_s: float = 10.0) -> int:
        """SIGTERM (the force ramps down, the recording closes), then wait."""
        assert self.process is not None
        if self.process.poll() is None:
            self.process.terminate()
        try:
            return self.wait(timeout_s)
        except subprocess.TimeoutExpired:
            self.process.kill()
            return self.wait(timeout_s)

    def __enter__(self) -> ServoProcess:
        return self.start()

    def __exit__(self, *exc) -> None:
        if self.process is not None:
            self.stop()
