"""The robot link: tracking results as framed binary messages over a serial port (or Bluetooth SPP).

Why this file exists: the paper's last step sends the shuttle's coordinates to the robot over
Bluetooth. Here that is a documented, versioned, checksummed binary protocol
(``docs/robot-protocol.md``) that any serial-capable microcontroller can parse, sent so that
tracking can never be slowed down or crashed by the link:

* :meth:`RobotLink.send_result` only encodes the message and puts it in a one-slot mailbox
  (newest wins; a replaced message counts as dropped); it never touches the port.
* A background thread owns the port: it opens it (any pyserial port name or URL: ``COM5``,
  ``/dev/ttyUSB0``, ``/dev/rfcomm0``, ``loop://``, ``socket://host:port``), writes at most
  ``max_rate_hz`` messages a second, adds a heartbeat every ``heartbeat_s``, and when the device
  vanishes (write error, unplugged adapter, Bluetooth out of range) closes it and reopens it in
  the background, with a back-off, for as long as the link lives.
* :meth:`RobotLink.status` is a frozen snapshot (port, baud, connected, counters, last error,
  and how often and how long the link was lost while in use); a loss and a return are logged
  when they happen, so a run's log says when the robot went without results.

The robot side: :class:`StreamDecoder` turns any byte stream back into messages; it resynchronises
after garbage, lost bytes or corrupted frames (a damaged length field holds back no later message)
and never raises on bad input.
``badminton-track robot-listen PORT`` prints what it decodes (cli/robot_listen.py).
"""

from __future__ import annotations

import binascii
import logging
import math
import os
import queue
import struct
import threading
import time
from dataclasses import dataclass

from ..core.types import TrackResult

# ---- wire format (docs/robot-protocol.md) ----------------------------------------------------
SYNC = b"\xa5\x5a"
PROTOCOL_VERSION = 1
MSG_TRACK = 0x01
MSG_HEARTBEAT = 0x02
MAX_PAYLOAD = 512                      # a longer length field is garbage: resynchronise

# After the sync bytes: version u8, type u8, payload length u16, sequence u32, timestamp f64.
_HEADER = struct.Struct("<BBHId")
HEADER_SIZE = len(SYNC) + _HEADER.size   # 18
CRC_SIZE = 2
# TRACK payload, version 1 (54 bytes), see the byte table in docs/robot-protocol.md.
_TRACK = struct.Struct("<IHh3f3f2fffBBf")
# HEARTBEAT payload, version 1 (13 bytes).
_HEARTBEAT = struct.Struct("<IIIB")

# TRACK flags
FLAG_POSITION = 0x0001     # x, y, z valid
FLAG_VELOCITY = 0x0002     # vx, vy, vz valid
FLAG_PREDICTION = 0x0004   # landing fields valid
FLAG_COURT_FRAME = 0x0008  # coordinates are court coordinates (else left-camera frame)
FLAG_IN_FLIGHT = 0x0010    # a flight is being followed

_log = logging.getLogger(__name__)

CALL_UNKNOWN, CALL_IN, CALL_OUT = 0, 1, 2
_CALL_CODES = {"in": CALL_IN, "out": CALL_OUT}
_CALL_NAMES = {CALL_UNKNOWN: "", CALL_IN: "in", CALL_OUT: "out"}


def crc16_ccitt(data: bytes, crc: int = 0xFFFF) -> int:
    """CRC-16/CCITT-FALSE: polynomial 0x1021, initial 0xFFFF, no reflection, no final XOR.

    Check value: ``crc16_ccitt(b"123456789") == 0x29B1``. ``binascii.crc_hqx`` is this CRC
    (XMODEM's, which differs only by its initial value) computed in C; the bitwise loop of
    docs/robot-protocol.md is the reference it is tested against.
    """
    return binascii.crc_hqx(data, crc)


# ---- messages ----------------------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class Message:
    """Common header of every message."""

    version: int
    msg_type: int
    seq: int
    timestamp: float       # s, the tracker's clock


@dataclass(frozen=True, slots=True)
class TrackMessage(Message):
    """One frame's tracking state. Invalid values are NaN and their flag is clear."""

    frame_index: int = -1
    flags: int = 0
    shot_index: int = -1
    position: tuple[float, float, float] = (math.nan,) * 3        # m
    velocity: tuple[float, float, float] = (math.nan,) * 3        # m/s
    landing: tuple[float, float] = (math.nan, math.nan)           # m, court frame, on the floor
    landing_in: float = math.nan      # s from ``timestamp`` until landing
    landing_radius: float = math.nan  # m, uncertainty radius
    call: str = ""                    # "in" / "out" / ""
    aero_length: float = math.nan     # m, fitted L of the drag model

    @property
    def speed(self) -> float:
        return math.sqrt(sum(v * v for v in self.velocity))

    def describe(self) -> str:
        """One line for robot-listen."""
        parts = [f"seq={self.seq} t={self.timestamp:.4f} TRACK frame={self.frame_index} "
                 f"shot={self.shot_index}"]
        if self.flags & FLAG_POSITION:
            parts.append("pos=({:.3f},{:.3f},{:.3f})".format(*self.position))
        if self.flags & FLAG_VELOCITY:
            parts.append("vel=({:.2f},{:.2f},{:.2f}) speed={:.2f}".format(*self.velocity, self.speed))
        if self.flags & FLAG_PREDICTION:
            parts.append("landing=({:.3f},{:.3f}) in {:.3f}s ±{:.3f}m {} L={:.2f}".format(
                *self.landing, self.landing_in, self.landing_radius, self.call.upper() or "?",
                self.aero_length))
        parts.append("court" if self.flags & FLAG_COURT_FRAME else "camera")
        if self.flags & FLAG_IN_FLIGHT:
            parts.append("flying")
        return " ".join(parts)


@dataclass(frozen=True, slots=True)
class HeartbeatMessage(Message):
    """Sent every ``heartbeat_s``: the tracker is alive, with the link's counters."""

    messages_sent: int = 0
    messages_dropped: int = 0
    errors: int = 0
    connected_flags: int = 0

    def describe(self) -> str:
        return (f"seq={self.seq} t={self.timestamp:.4f} HEARTBEAT sent={self.messages_sent} "
                f"dropped={self.messages_dropped} errors={self.errors}")


@dataclass(frozen=True, slots=True)
class UnknownMessage(Message):
    """A well-formed frame (CRC good) of a type or version this decoder does not know."""

    payload: bytes = b""

    def describe(self) -> str:
        return (f"seq={self.seq} t={self.timestamp:.4f} UNKNOWN version={self.version} "
                f"type=0x{self.msg_type:02x} {len(self.payload)} bytes")


def encode_frame(msg_type: int, seq: int, timestamp: float, payload: bytes,
                 version: int = PROTOCOL_VERSION) -> bytes:
    """Sync + header + payload + CRC (CRC over everything after the sync bytes)."""
    body = _HEADER.pack(version, msg_type, len(payload), seq & 0xFFFFFFFF, timestamp) + payload
    return SYNC + body + struct.pack("<H", crc16_ccitt(body))


def _f(value) -> float:
    return math.nan if value is None else float(value)


def encode_track(result: TrackResult, seq: int) -> bytes:
    """The TRACK frame for one tracking result."""
    flags = 0
    pos = (math.nan,) * 3
    vel = (math.nan,) * 3
    if result.point is not None:
        flags |= FLAG_POSITION
        pos = tuple(float(c) for c in result.point)
    flight = result.flight
    if flight.velocity is not None:
        flags |= FLAG_VELOCITY
        vel = tuple(float(c) for c in flight.velocity)
    if result.in_court_frame:
        flags |= FLAG_COURT_FRAME
    if flight.in_flight:
        flags |= FLAG_IN_FLIGHT
    pred = flight.prediction
    landing = (math.nan, math.nan)
    landing_in = radius = aero = math.nan
    call = CALL_UNKNOWN
    if pred is not None:
        flags |= FLAG_PREDICTION
        landing = (float(pred.x), float(pred.y))
        landing_in = float(pred.t) - float(result.timestamp)
        radius = float(pred.radius)
        aero = _f(pred.aero_length)
        call = _CALL_CODES.get(pred.call, CALL_UNKNOWN)
    shot = max(-32768, min(32767, int(flight.shot_index)))
    payload = _TRACK.pack(int(result.index) & 0xFFFFFFFF, flags, shot, *pos, *vel, *landing,
                          landing_in, radius, call, 0, aero)
    return encode_frame(MSG_TRACK, seq, float(result.timestamp), payload)


def _renumber(frame: bytes, seq: int) -> bytes:
    """The same frame with another sequence number (and its CRC recomputed)."""
    buf = bytearray(frame)
    struct.pack_into("<I", buf, 6, seq & 0xFFFFFFFF)
    struct.pack_into("<H", buf, len(buf) - CRC_SIZE, crc16_ccitt(bytes(buf[len(SYNC):-CRC_SIZE])))
    return bytes(buf)


def encode_heartbeat(seq: int, timestamp: float, sent: int, dropped: int, errors: int) -> bytes:
    payload = _HEARTBEAT.pack(sent & 0xFFFFFFFF, dropped & 0xFFFFFFFF, errors & 0xFFFFFFFF, 1)
    return encode_frame(MSG_HEARTBEAT, seq, timestamp, payload)


def _decode_payload(version: int, msg_type: int, seq: int, timestamp: float,
                    payload: bytes) -> Message:
    # Version 1 rule: payloads may grow by appended fields; a decoder reads the fields it knows.
    if version == PROTOCOL_VERSION and msg_type == MSG_TRACK and len(payload) >= _TRACK.size:
        v = _TRACK.unpack_from(payload)
        return TrackMessage(version, msg_type, seq, timestamp, frame_index=v[0], flags=v[1],
                            shot_index=v[2], position=tuple(v[3:6]), velocity=tuple(v[6:9]),
                            landing=tuple(v[9:11]), landing_in=v[11], landing_radius=v[12],
                            call=_CALL_NAMES.get(v[13], ""), aero_length=v[15])
    if version == PROTOCOL_VERSION and msg_type == MSG_HEARTBEAT and len(payload) >= _HEARTBEAT.size:
        v = _HEARTBEAT.unpack_from(payload)
        return HeartbeatMessage(version, msg_type, seq, timestamp, messages_sent=v[0],
                                messages_dropped=v[1], errors=v[2], connected_flags=v[3])
    return UnknownMessage(version, msg_type, seq, timestamp, payload=bytes(payload))


class StreamDecoder:
    """Bytes in, messages out; resynchronises on garbage and never raises on bad input."""

    def __init__(self) -> None:
        self._buf = bytearray()
        self.frames_ok = 0
        self.crc_errors = 0
        self.bytes_skipped = 0

    def feed(self, data: bytes) -> list[Message]:
        out: list[Message] = []
        if data:
            self._buf += data
        buf = self._buf
        while True:
            start = buf.find(SYNC)
            if start < 0:
                # Keep a trailing first sync byte: its partner may be in the next chunk.
                keep = 1 if buf[-1:] == SYNC[:1] else 0
                self.bytes_skipped += len(buf) - keep
                del buf[:len(buf) - keep]
                break
            if start:
                self.bytes_skipped += start
                del buf[:start]
            if len(buf) < HEADER_SIZE:
                break
            version, msg_type, length, seq, timestamp = _HEADER.unpack_from(buf, len(SYNC))
            if length > MAX_PAYLOAD:
                self._skip_sync(buf)
                continue
            total = HEADER_SIZE + length + CRC_SIZE
            if len(buf) < total:
                # A damaged length field (up to MAX_PAYLOAD) would make this false start wait
                # for bytes that are the next messages; a complete frame with a good CRC
                # further on proves the start false, so the messages behind it are not held back.
                later = self._next_whole_frame(buf)
                if later < 0:
                    break
                self.bytes_skipped += later
                del buf[:later]
                continue
            body = bytes(buf[len(SYNC):HEADER_SIZE + length])
            (crc,) = struct.unpack_from("<H", buf, HEADER_SIZE + length)
            if crc != crc16_ccitt(body):
                self.crc_errors += 1
                self._skip_sync(buf)
                continue
            payload = body[_HEADER.size:]
            try:
                out.append(_decode_payload(version, msg_type, seq, timestamp, payload))
            except struct.error:   # cannot happen with the length checks above; never raise
                out.append(UnknownMessage(version, msg_type, seq, timestamp, payload=payload))
            self.frames_ok += 1
            del buf[:total]
        return out

    @staticmethod
    def _next_whole_frame(buf: bytearray) -> int:
        """Offset of the first complete, CRC-valid frame after the start of ``buf``, or -1."""
        at = buf.find(SYNC, 1)
        while at >= 0 and len(buf) - at >= HEADER_SIZE + CRC_SIZE:
            (length,) = struct.unpack_from("<H", buf, at + 4)
            end = at + HEADER_SIZE + length
            if length <= MAX_PAYLOAD and end + CRC_SIZE <= len(buf):
                (crc,) = struct.unpack_from("<H", buf, end)
                if crc == crc16_ccitt(bytes(buf[at + len(SYNC):end])):
                    return at
            at = buf.find(SYNC, at + 1)
        return -1

    def _skip_sync(self, buf: bytearray) -> None:
        """A false start: drop this sync's first byte and look for the next one."""
        self.bytes_skipped += 1
        del buf[:1]


# ---- the link ------------------------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class LinkStatus:
    """A snapshot of the link for the GUI / CLI."""

    port: str
    baud: int
    connected: bool
    messages_sent: int
    messages_dropped: int
    heartbeats_sent: int
    errors: int
    reconnects: int
    last_error: str
    # Times a link in use was lost (write error, device gone), and the seconds without a link
    # since the first connection (an outage still going on counts up to now).
    outages: int = 0
    seconds_down: float = 0.0


class RobotLink:
    """Sends tracking results to a robot over a serial port, never blocking the caller.

    ``serial_factory(port, baud, write_timeout_s)`` opens the port (default: pyserial's
    ``serial_for_url``); tests give a fake one.
    """

    RETRY_MIN_S = 0.2
    RETRY_MAX_S = 2.0

    def __init__(self, port: str, baud: int = 115200, max_rate_hz: float = 200.0,
                 heartbeat_s: float = 0.5, write_timeout_s: float = 0.5,
                 serial_factory=None) -> None:
        if not port:
            raise ValueError("robot link: empty port name")
        if isinstance(baud, bool) or int(baud) != baud or baud <= 0:
            raise ValueError(f"robot link: baud must be a positive whole number, not {baud!r}")
        if not all(math.isfinite(v) and v > 0 for v in (max_rate_hz, heartbeat_s, write_timeout_s)):
            raise ValueError("robot link: max_rate_hz, heartbeat_s and write_timeout_s must be "
                             "positive and finite")
        # A write that cannot finish in this time (robot not reading) drops the message.
        self.write_timeout_s = float(write_timeout_s)
        self.port = port
        self.baud = int(baud)
        self.min_interval = 1.0 / float(max_rate_hz)
        self.heartbeat_s = float(heartbeat_s)
        self._serial_factory = serial_factory or _open_serial
        self._cond = threading.Condition()
        self._pending: bytes | None = None     # one-slot mailbox, newest wins
        self._last_timestamp = 0.0             # heartbeats carry the tracker clock's latest time
        self._closing = False                  # close() asked: send what is pending, then stop
        # Set by close() once it gives up waiting: no write starts after it (checked under
        # ``_write_lock``, which a write holds).
        self._stopped = False
        self._write_lock = threading.Lock()
        self._first_attempt = threading.Event()   # the first open attempt is over
        self._seq = 0
        self._sent = 0
        self._dropped = 0
        self._heartbeats = 0
        self._errors = 0
        self._reconnects = 0
        self._open_attempts = 0
        self._connected = False
        self._last_error = ""
        self._outages = 0
        self._down_since: float | None = None   # monotonic time the link in use was lost
        self._seconds_down = 0.0                 # finished outages
        self._serial = None
        self._thread = threading.Thread(target=self._run, name=f"robot-link {port}", daemon=True)
        self._thread.start()

    # ---- caller side (tracking thread) ------------------------------------------------------
    def send_result(self, result: TrackResult) -> None:
        """Queue the newest result for sending; returns at once, whatever the port does.

        Anything but a ``TrackResult`` (None included) is a programming error: TypeError. A
        result whose values cannot be encoded is counted as an error and skipped."""
        if not isinstance(result, TrackResult):
            raise TypeError(f"send_result takes a TrackResult, not {type(result).__name__}")
        with self._cond:
            if self._closing:
                return
            try:
                frame = encode_track(result, 0)   # the I/O thread numbers it when writing
            except (struct.error, TypeError, ValueError, OverflowError) as exc:
                # A malformed result must not stop tracking: count it and carry on.
                self._errors += 1
                self._last_error = f"cannot encode frame {getattr(result, 'index', '?')}: {exc}"
                return
            self._last_timestamp = float(result.timestamp)
            if self._pending is not None:
                self._dropped += 1
                self._seq = (self._seq + 1) & 0xFFFFFFFF   # a gap in seq marks the dropped one
            self._pending = frame
            self._cond.notify_all()

    def status(self) -> LinkStatus:
        with self._cond:
            down = self._seconds_down
            if self._down_since is not None:
                down += time.monotonic() - self._down_since
            return LinkStatus(self.port, self.baud, self._connected, self._sent, self._dropped,
                              self._heartbeats, self._errors, self._reconnects, self._last_error,
                              self._outages, down)

    @property
    def open_attempts(self) -> int:
        """How many times the port was tried (the back-off's count)."""
        with self._cond:
            return self._open_attempts

    def wait_first_attempt(self, timeout: float = 2.0) -> LinkStatus:
        """Wait (at most ``timeout`` s) until the port has been tried once, then the status: a
        command can say at once that the port cannot be opened."""
        self._first_attempt.wait(timeout)
        return self.status()

    def close(self, timeout: float = 1.0) -> None:
        """Send what is pending if the port is up, then stop the thread and close the port.

        Returns within about ``timeout`` s whatever the port does; no write starts after it
        returns (a write already under way, bounded by ``write_timeout_s``, may finish)."""
        deadline = time.monotonic() + timeout
        with self._cond:
            self._closing = True
            self._cond.notify_all()
        self._thread.join(max(0.0, deadline - time.monotonic()))
        with self._cond:
            if self._down_since is not None:    # an outage ends with the link: its time is final
                self._seconds_down += time.monotonic() - self._down_since
                self._down_since = None
        if self._write_lock.acquire(timeout=max(0.0, deadline - time.monotonic())):
            self._stopped = True
            self._write_lock.release()
        else:
            self._stopped = True    # a write is stuck in the driver: the next one will not start

    def __enter__(self) -> "RobotLink":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # ---- I/O thread ---------------------------------------------------------------------------
    def _run(self) -> None:
        retry = self.RETRY_MIN_S
        last_send = -math.inf
        last_heartbeat = -math.inf
        try:
            while True:
                with self._cond:
                    if self._closing and (self._pending is None or not self._connected):
                        return
                if not self._connected:
                    opened = self._open()
                    self._first_attempt.set()
                    if opened:
                        retry = self.RETRY_MIN_S
                    else:
                        self._back_off(retry)
                        retry = min(retry * 2.0, self.RETRY_MAX_S)
                    continue
                if time.monotonic() - last_heartbeat >= self.heartbeat_s and not self._closing:
                    with self._cond:
                        frame = encode_heartbeat(self._seq, self._last_timestamp, self._sent,
                                                 self._dropped, self._errors)
                        self._seq = (self._seq + 1) & 0xFFFFFFFF
                    if self._write(frame):
                        with self._cond:
                            self._heartbeats += 1
                    # Counted from the end of the write: a port so slow that a write outlasts
                    # the heartbeat period still gets the results through between heartbeats.
                    last_heartbeat = time.monotonic()
                    continue
                # Wait for a result, or until the next heartbeat is due.
                with self._cond:
                    next_heartbeat = last_heartbeat + self.heartbeat_s
                    while self._pending is None and not self._closing:
                        remaining = next_heartbeat - time.monotonic()
                        if remaining <= 0.0:
                            break
                        self._cond.wait(remaining)
                    if self._pending is None:
                        continue
                # Rate limit: meanwhile newer results replace the pending one (newest wins).
                delay = last_send + self.min_interval - time.monotonic()
                if delay > 0.0:
                    with self._cond:
                        if not self._closing:
                            self._cond.wait(delay)
                with self._cond:
                    frame, self._pending = self._pending, None
                    if frame is not None:
                        frame = _renumber(frame, self._seq)
                        self._seq = (self._seq + 1) & 0xFFFFFFFF
                if frame is not None and self._write(frame):
                    last_send = time.monotonic()
                    with self._cond:
                        self._sent += 1
        finally:
            self._first_attempt.set()
            self._close_port()

    def _back_off(self, seconds: float) -> None:
        """Wait ``seconds`` before the next open attempt; only close() cuts it short (results
        arriving meanwhile wake the condition but do not bring the attempt forward)."""
        deadline = time.monotonic() + seconds
        with self._cond:
            while not self._closing:
                remaining = deadline - time.monotonic()
                if remaining <= 0.0:
                    return
                self._cond.wait(remaining)

    def _open(self) -> bool:
        with self._cond:
            self._open_attempts += 1
        try:
            ser = self._serial_factory(self.port, self.baud, self.write_timeout_s)
        except Exception as exc:  # noqa: BLE001 - a bad URL or handler must not kill the I/O thread
            # pyserial repeats the port name and errno in its text: the system's reason is enough.
            reason = os.strerror(exc.errno) if isinstance(exc, OSError) and exc.errno else str(exc)
            self._record_error(f"cannot open {self.port}: {reason or type(exc).__name__}")
            return False
        self._serial = ser
        with self._cond:
            if self._sent or self._heartbeats or self._errors:
                self._reconnects += 1
            self._connected = True
            outage = None
            if self._down_since is not None:
                outage = time.monotonic() - self._down_since
                self._seconds_down += outage
                self._down_since = None
        if outage is not None:
            _log.warning("robot link: %s back after %.1f s without a link", self.port, outage)
        return True

    def _write(self, frame: bytes) -> bool:
        import serial

        with self._write_lock:
            ser = self._serial
            if self._stopped or ser is None:
                return False
            try:
                written = ser.write(frame)
                if written is not None and written != len(frame):
                    raise serial.SerialTimeoutException(f"wrote {written} of {len(frame)} bytes")
                return True
            except (serial.SerialTimeoutException, queue.Full) as exc:
                # The device is there but not reading (full buffer, Bluetooth stall; loop://
                # raises queue.Full): drop the message.
                self._record_error(f"write timeout on {self.port}: {exc or type(exc).__name__}")
                return False
            except Exception as exc:  # noqa: BLE001 - any handler error must not kill the I/O thread
                # Gone (unplugged, out of range, pty closed) or a URL handler's own error: reopen
                # in the background.
                self._record_error(f"write to {self.port}: {exc or type(exc).__name__}")
        self._close_port(lost=True)
        return False

    def _record_error(self, text: str) -> None:
        with self._cond:
            self._errors += 1
            self._last_error = text

    def _close_port(self, lost: bool = False) -> None:
        """Close the port; ``lost``: the device failed while in use (an outage begins, said in
        the log once, with the reason)."""
        ser, self._serial = self._serial, None
        with self._cond:
            lost = lost and self._connected
            self._connected = False
            if lost:
                self._outages += 1
                self._down_since = time.monotonic()
                reason = self._last_error
        if lost:
            _log.warning("robot link: lost (%s); retrying in the background", reason)
        if ser is not None:
            try:
                ser.close()
            except Exception as exc:  # noqa: BLE001 - closing a vanished device may fail: ignore
                self._record_error(f"close {self.port}: {exc}")


def _open_serial(port: str, baud: int, write_timeout_s: float):
    import serial   # pyserial; imported here so decoding needs no serial package

    return serial.serial_for_url(port, baudrate=baud, timeout=0, write_timeout=write_timeout_s)
