"""Robot link: wire format, the resynchronising decoder, and the link over real (pseudo) serial ports.

No assertion on wall-clock time: waits poll for a condition with a generous deadline.
"""

from __future__ import annotations

import math
import os
import re
import struct
import threading
import time
import tty
from pathlib import Path

import numpy as np
import pytest

from badminton_gui.core.types import CameraResult, FlightInfo, LandingPrediction, TrackResult
from badminton_gui.io.robot_link import (
    FLAG_COURT_FRAME, FLAG_IN_FLIGHT, FLAG_POSITION, FLAG_PREDICTION, FLAG_VELOCITY, MSG_TRACK,
    HeartbeatMessage, RobotLink, StreamDecoder, TrackMessage, UnknownMessage, crc16_ccitt,
    encode_frame, encode_heartbeat, encode_track)

DOC = Path(__file__).resolve().parents[1] / "docs" / "robot-protocol.md"
EMPTY = CameraResult(detection=None)


def make_result(i: int = 1234, t: float = 12.5, with_prediction: bool = True) -> TrackResult:
    pred = LandingPrediction(0.5, 6.25, t + 1.25, 0.0625, "in", 4.75) if with_prediction else None
    return TrackResult(index=i, timestamp=t, left=EMPTY, right=EMPTY, point=(0.25, -3.5, 2.75),
                       in_court_frame=True,
                       flight=FlightInfo(shot_index=3, velocity=(1.5, 12.0, 4.0), prediction=pred,
                                         in_flight=True))


def wait_for(condition, timeout: float = 10.0, step: float = 0.01) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(step)
    return condition()


# ---- wire format ----------------------------------------------------------------------------------
def test_crc_check_value():
    assert crc16_ccitt(b"123456789") == 0x29B1


def test_documented_example_dumps_match_the_encoder():
    text = DOC.read_text(encoding="utf-8")
    dumps = [bytes.fromhex(" ".join(block.split()))
             for block in re.findall(r"```\n((?:[0-9a-f]{2}[ \n])+)```", text)]
    assert len(dumps) == 2
    assert dumps[0] == encode_track(make_result(), 42)
    assert dumps[1] == encode_heartbeat(43, 12.5, 40, 3, 0)


def test_track_round_trip():
    frame = encode_track(make_result(), 42)
    (msg,) = StreamDecoder().feed(frame)
    assert isinstance(msg, TrackMessage)
    assert (msg.version, msg.msg_type, msg.seq, msg.timestamp) == (1, MSG_TRACK, 42, 12.5)
    assert msg.frame_index == 1234 and msg.shot_index == 3
    assert msg.flags == FLAG_POSITION | FLAG_VELOCITY | FLAG_PREDICTION | FLAG_COURT_FRAME | FLAG_IN_FLIGHT
    assert msg.position == pytest.approx((0.25, -3.5, 2.75))
    assert msg.velocity == pytest.approx((1.5, 12.0, 4.0))
    assert msg.landing == pytest.approx((0.5, 6.25))
    assert msg.landing_in == pytest.approx(1.25)
    assert msg.landing_radius == pytest.approx(0.0625)
    assert msg.call == "in" and msg.aero_length == pytest.approx(4.75)
    assert "landing=(0.500,6.250)" in msg.describe()


def test_missing_values_are_nan_with_their_flags_clear():
    result = TrackResult(index=7, timestamp=1.0, left=EMPTY, right=EMPTY)
    (msg,) = StreamDecoder().feed(encode_track(result, 0))
    assert msg.flags == 0
    assert all(math.isnan(v) for v in (*msg.position, *msg.velocity, *msg.landing, msg.landing_in))
    assert msg.call == "" and msg.shot_index == -1


def test_heartbeat_round_trip():
    (msg,) = StreamDecoder().feed(encode_heartbeat(9, 3.25, 100, 7, 2))
    assert isinstance(msg, HeartbeatMessage)
    assert (msg.seq, msg.timestamp, msg.messages_sent, msg.messages_dropped, msg.errors) == (9, 3.25, 100, 7, 2)


def test_unknown_types_versions_and_longer_payloads():
    known = encode_track(make_result(), 1)
    payload = known[18:-2]
    longer = encode_frame(MSG_TRACK, 2, 1.0, payload + b"\x01\x02\x03")   # appended future fields
    other_type = encode_frame(0x7F, 3, 1.0, b"hello")
    other_version = encode_frame(MSG_TRACK, 4, 1.0, payload, version=2)
    msgs = StreamDecoder().feed(longer + other_type + other_version + known)
    assert [type(m) for m in msgs] == [TrackMessage, UnknownMessage, UnknownMessage, TrackMessage]
    assert msgs[0].position == pytest.approx((0.25, -3.5, 2.75))
    assert msgs[1].payload == b"hello" and msgs[2].version == 2


# ---- the decoder against bad input ------------------------------------------------------------------
def frames(n: int) -> list[bytes]:
    return [encode_track(make_result(i, i / 120.0), i) if i % 5 else encode_heartbeat(i, i / 120.0, i, 0, 0)
            for i in range(n)]


def test_byte_by_byte_feed():
    stream = b"".join(frames(20))
    dec = StreamDecoder()
    msgs = [m for b in stream for m in dec.feed(bytes([b]))]
    assert [m.seq for m in msgs] == list(range(20))


def test_garbage_truncated_and_corrupted_frames_are_skipped():
    good = frames(6)
    truncated = good[1][:30]
    corrupted = bytearray(good[2])
    corrupted[25] ^= 0x40
    fake_header = b"\xa5\x5a\x01\x01\xff\xff"              # length 65535: not a frame
    stream = (b"noise\xa5\x00\xa5" + good[0] + truncated + bytes(corrupted) + fake_header
              + good[3] + b"\xa5" + good[4] + b"\x5a\x5a" + good[5])
    dec = StreamDecoder()
    msgs = dec.feed(stream)
    assert [m.seq for m in msgs] == [0, 3, 4, 5]
    assert dec.crc_errors >= 1 and dec.bytes_skipped > 0


def test_random_fuzz_never_raises_and_recovers_every_intact_frame():
    rng = np.random.default_rng(1234)
    dec = StreamDecoder()
    sent, stream = [], bytearray()
    for i, frame in enumerate(frames(300)):
        junk = rng.integers(0, 256, rng.integers(0, 40), dtype=np.uint8).tobytes()
        if rng.uniform() < 0.3:
            junk += b"\xa5\x5a" + junk[:10]                     # false sync starts
        stream += junk
        if rng.uniform() < 0.1:
            cut = bytearray(frame[: rng.integers(1, len(frame))])   # truncated / damaged frame
            if cut and rng.uniform() < 0.5:
                cut[rng.integers(len(cut))] ^= 0xFF
            stream += cut
        else:
            stream += frame
            sent.append(i)
    stream += bytes(600)    # flush: lets a false header that claimed a long payload be rejected
    got = []
    pos = 0
    while pos < len(stream):
        n = int(rng.integers(1, 200))
        got += dec.feed(bytes(stream[pos:pos + n]))
        pos += n
    assert [m.seq for m in got if not isinstance(m, UnknownMessage)] == sent
    for _ in range(200):                                        # pure noise, any chunking
        dec.feed(rng.integers(0, 256, rng.integers(0, 300), dtype=np.uint8).tobytes())
    dec.feed(b"")


# ---- the link ------------------------------------------------------------------------------------------
class PtyReader:
    """Reads and decodes the master side of a pseudo-terminal in a thread (the robot's end)."""

    def __init__(self, master_fd: int) -> None:
        self.fd = master_fd
        self.decoder = StreamDecoder()
        self.messages: list = []
        self._stop = False
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        import select
        while not self._stop:
            ready, _, _ = select.select([self.fd], [], [], 0.05)
            if not ready:
                continue
            try:
                data = os.read(self.fd, 4096)
            except OSError:
                return
            self.messages += self.decoder.feed(data)

    def tracks(self) -> list[TrackMessage]:
        return [m for m in self.messages if isinstance(m, TrackMessage)]

    def stop(self) -> None:
        self._stop = True
        self.thread.join(2.0)


def open_pty() -> tuple[int, int, str]:
    """(master fd, slave fd, slave device name). The link opens the device by name, like a real
    port; the test keeps its own slave fd open meanwhile, because while no slave fd is open,
    reading the master fails with EIO."""
    master, slave = os.openpty()
    tty.setraw(master)
    tty.setraw(slave)
    return master, slave, os.ttyname(slave)


def test_pseudo_terminal_messages_arrive_intact():
    master, slave, name = open_pty()
    reader = PtyReader(master)
    link = RobotLink(name, 115200, max_rate_hz=1000.0, heartbeat_s=0.2)
    try:
        assert wait_for(lambda: link.status().connected)
        for i in range(40):
            link.send_result(make_result(i, i / 120.0))
            time.sleep(0.002)
        assert wait_for(lambda: link.status().messages_sent + link.status().messages_dropped >= 40)
        assert wait_for(lambda: len(reader.tracks()) >= link.status().messages_sent)
        assert wait_for(lambda: any(isinstance(m, HeartbeatMessage) for m in reader.messages))
        tracks = reader.tracks()
        assert len(tracks) == link.status().messages_sent >= 1
        assert all(m.position == pytest.approx((0.25, -3.5, 2.75)) for m in tracks)
        seqs = [m.seq for m in reader.messages]
        assert seqs == sorted(seqs) and len(set(seqs)) == len(seqs)   # in writing order, unique
        assert reader.decoder.crc_errors == 0
        status = link.status()
        assert status.port == name and status.baud == 115200 and status.errors == 0
    finally:
        link.close()
        reader.stop()
        os.close(master)
        os.close(slave)


def test_device_vanishing_and_coming_back_is_survived(tmp_path):
    """A symlink plays the stable device name (/dev/rfcomm0); the pty behind it is closed and a
    new one appears, as when a Bluetooth robot goes out of range and comes back."""
    master, slave, name = open_pty()
    port = tmp_path / "robot"
    port.symlink_to(name)
    reader = PtyReader(master)
    link = RobotLink(str(port), max_rate_hz=500.0, heartbeat_s=0.1)
    link.RETRY_MAX_S = 0.2
    i = 0

    def send_some(n=10):
        nonlocal i
        for _ in range(n):
            link.send_result(make_result(i, i / 120.0))
            i += 1
            time.sleep(0.003)

    try:
        assert wait_for(lambda: link.status().connected)
        send_some()
        assert wait_for(lambda: len(reader.tracks()) > 0)
        # The device vanishes.
        reader.stop()
        os.close(master)
        os.close(slave)
        deadline = time.monotonic() + 10
        while not link.status().errors and time.monotonic() < deadline:
            send_some(2)              # the caller never blocks, whatever the port does
        assert link.status().errors >= 1
        assert wait_for(lambda: not link.status().connected)
        assert link.status().last_error
        send_some(5)
        # It comes back under the same name.
        master, slave, name2 = open_pty()
        port.unlink()
        port.symlink_to(name2)
        reader = PtyReader(master)
        assert wait_for(lambda: link.status().connected)
        assert wait_for(lambda: (send_some(3), len(reader.tracks()) > 0)[1])
        assert link.status().reconnects >= 1
        assert reader.decoder.crc_errors == 0
    finally:
        link.close()
        reader.stop()
        os.close(master)
        os.close(slave)


def test_loop_url_and_newest_wins_rate_limit():
    link = RobotLink("loop://", max_rate_hz=20.0, heartbeat_s=10.0)
    try:
        assert wait_for(lambda: link.status().connected)
        for i in range(100):             # much faster than 20 Hz: most are replaced
            link.send_result(make_result(i, i / 120.0))
        assert wait_for(lambda: link.status().messages_sent >= 1 and link._pending is None)
        status = link.status()
        assert status.messages_sent + status.messages_dropped == 100
        assert status.messages_dropped > 50
        dec = StreamDecoder()
        msgs = dec.feed(link._serial.read(1 << 16))
        tracks = [m for m in msgs if isinstance(m, TrackMessage)]
        assert tracks and tracks[-1].frame_index == 99          # the newest one went out
        assert len(tracks) == status.messages_sent
        # Numbered when written: gaps in seq count exactly the dropped messages.
        seqs = [m.seq for m in msgs]
        assert seqs == sorted(seqs)
        assert seqs[-1] + 1 - len(seqs) == status.messages_dropped     # numbering starts at 0
    finally:
        link.close()


def test_robot_not_reading_drops_messages_without_killing_the_link():
    # loop:// holds 4 KB and raises queue.Full when nobody reads it: like a stalled Bluetooth link.
    link = RobotLink("loop://", max_rate_hz=1000.0, heartbeat_s=0.05, write_timeout_s=0.01)
    try:
        assert wait_for(lambda: link.status().connected)
        for i in range(400):
            link.send_result(make_result(i, i / 120.0))
            time.sleep(0.001)
        assert wait_for(lambda: link.status().errors >= 1)
        assert link._thread.is_alive()
        assert "timeout" in link.status().last_error
        sent_before = link.status().messages_sent
        link._serial.read(1 << 16)        # the robot reads again: sending resumes
        link.send_result(make_result(999, 9.0))
        assert wait_for(lambda: link.status().messages_sent > sent_before)
    finally:
        link.close()
    assert not link._thread.is_alive()


def test_missing_port_never_blocks_or_raises():
    link = RobotLink("/dev/this-port-does-not-exist", heartbeat_s=0.1)
    try:
        for i in range(500):
            link.send_result(make_result(i))
        assert wait_for(lambda: link.status().errors >= 1)
        status = link.status()
        assert not status.connected and status.messages_sent == 0
        assert "this-port-does-not-exist" in status.last_error
    finally:
        link.close()
    assert not link._thread.is_alive()


def test_a_malformed_result_is_counted_not_raised():
    link = RobotLink("loop://", heartbeat_s=10.0)
    try:
        bad = TrackResult(index=1, timestamp=0.0, left=EMPTY, right=EMPTY, point=(1.0, 2.0))
        link.send_result(bad)
        assert link.status().errors == 1 and "cannot encode" in link.status().last_error
    finally:
        link.close()


def test_bad_arguments():
    with pytest.raises(ValueError):
        RobotLink("", 115200)
    with pytest.raises(ValueError):
        RobotLink("loop://", max_rate_hz=0)


def loopback_server():
    """A listening TCP socket on 127.0.0.1 (any free port): the robot's end for socket:// tests."""
    import socket

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(1)
    host, port_no = server.getsockname()
    return server, host, port_no


def test_robot_listen_cli_decodes_a_socket_stream(capsys):
    from badminton_gui.cli import main

    server, host, port_no = loopback_server()

    def serve():
        # pyserial empties the input buffer right after connecting, so keep sending.
        conn, _ = server.accept()
        try:
            for _ in range(100):
                conn.sendall(b"junk" + encode_track(make_result(5, 0.5), 1)
                             + encode_heartbeat(2, 0.5, 1, 0, 0))
                time.sleep(0.05)
        except OSError:
            pass    # the listener has gone after --count messages
        finally:
            conn.close()

    threading.Thread(target=serve, daemon=True).start()
    code = main(["robot-listen", f"socket://{host}:{port_no}", "--count", "4", "--timeout", "20"])
    server.close()
    captured = capsys.readouterr()
    out = captured.out.splitlines()
    assert code == 0, captured.err
    assert len(out) == 4
    assert any(line.startswith("seq=1 t=0.5000 TRACK frame=5 shot=3") for line in out)
    assert any("HEARTBEAT sent=1" in line for line in out)


def test_robot_listen_cli_survives_the_port_going_away(capsys):
    """The robot's reader reopens a vanished port and goes on decoding (like the link itself)."""
    from badminton_gui.cli import main

    server, host, port_no = loopback_server()

    def serve():
        try:
            for frame_index in (5, 7):          # two connections: the first one is dropped
                conn, _ = server.accept()
                try:
                    for _ in range(8):
                        conn.sendall(encode_track(make_result(frame_index, 0.5), 1))
                        time.sleep(0.05)
                finally:
                    conn.close()
        except OSError:
            pass
        finally:
            server.close()

    threading.Thread(target=serve, daemon=True).start()
    code = main(["robot-listen", f"socket://{host}:{port_no}", "--timeout", "4"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert any("TRACK frame=5" in line for line in captured.out.splitlines())
    assert any("TRACK frame=7" in line for line in captured.out.splitlines())
    assert "reopening" in captured.err and "is back" in captured.err


def test_robot_listen_cli_user_error_on_missing_port(capsys):
    from badminton_gui.cli import main

    assert main(["robot-listen", "/dev/this-port-does-not-exist", "--timeout", "0.1"]) == 2
    assert "cannot open" in capsys.readouterr().err


# ---- a link that never takes the process down --------------------------------------------------
def _reference_crc(data: bytes, crc: int = 0xFFFF) -> int:
    """The bitwise loop of docs/robot-protocol.md, the reference the fast CRC must equal."""
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


def test_the_crc_equals_the_reference_loop_on_random_data():
    rng = np.random.default_rng(16)
    for n in list(range(0, 40)) + [int(k) for k in rng.integers(40, 600, 300)]:
        data = rng.integers(0, 256, n, dtype=np.uint8).tobytes()
        assert crc16_ccitt(data) == _reference_crc(data)
        start = int(rng.integers(0, 1 << 16))
        assert crc16_ccitt(data, start) == _reference_crc(data, start)


def test_a_damaged_length_holds_back_no_later_message():
    """A header whose length field says 512 (the most the protocol allows) used to make the
    decoder wait for 532 bytes: the next ~15 messages. A whole frame after it proves it false."""
    good = [encode_heartbeat(i, 1.0, i, 0, 0) for i in range(3)]
    damaged = bytearray(good[0])
    struct.pack_into("<H", damaged, 4, 512)
    dec = StreamDecoder()
    assert dec.feed(bytes(damaged)) == []                 # could still be a long frame
    got = dec.feed(good[1])
    assert [m.seq for m in got] == [1]                     # decoded as soon as it arrived
    assert [m.seq for m in dec.feed(good[2])] == [2]
    # Byte by byte the same: nothing waits for the damaged frame's 512 bytes.
    dec = StreamDecoder()
    seqs = []
    for byte in bytes(damaged) + b"".join(good[1:]):
        seqs += [m.seq for m in dec.feed(bytes([byte]))]
    assert seqs == [1, 2]


class FakePort:
    """A serial port for the link's tests: records writes; ``write_blocks`` holds a write until
    it is set; ``link_closed`` is set by the test once close() returned."""

    def __init__(self) -> None:
        self.writes: list[bytes] = []
        self.writes_after_close = 0
        self.link_closed = threading.Event()
        self.write_blocks: threading.Event | None = None
        self.writing = threading.Event()

    def write(self, data):
        if self.link_closed.is_set():
            self.writes_after_close += 1
        self.writing.set()
        if self.write_blocks is not None:
            self.write_blocks.wait(30)
        self.writes.append(bytes(data))
        return len(data)

    def close(self):
        pass


def test_the_back_off_holds_while_results_flow():
    """With the port gone, results arriving must not bring the next open attempt forward (it was
    tried again on every result: 300 attempts in 3 s)."""
    attempts = []

    def refuse(port, baud, write_timeout):
        attempts.append(port)
        raise OSError(2, "No such file or directory")

    link = RobotLink("/dev/robot", serial_factory=refuse)
    link.RETRY_MIN_S = link.RETRY_MAX_S = 600.0      # the next attempt is far away: only close() ends the wait
    try:
        assert not link.wait_first_attempt(10.0).connected
        for i in range(3000):
            link.send_result(make_result(i, i / 120.0))
        assert wait_for(lambda: link.status().messages_dropped >= 2999)
        assert link.open_attempts == 1 and len(attempts) == 1
    finally:
        link.close()
    assert wait_for(lambda: not link._thread.is_alive())


def test_close_stops_the_thread_and_nothing_is_written_after_it():
    """A port whose every write outlasts the heartbeat period kept the thread writing heartbeats
    after close() had given up on it."""
    port = FakePort()
    link = RobotLink("fake", heartbeat_s=0.01, max_rate_hz=1000.0,
                     serial_factory=lambda *a: port)
    port.write_blocks = threading.Event()
    assert link.wait_first_attempt(10.0).connected
    link.send_result(make_result(1))
    assert port.writing.wait(10)                          # a write is stuck in the "driver"
    closer = threading.Thread(target=link.close)
    closer.start()
    closer.join(30)
    assert not closer.is_alive()                          # close() returned with the write stuck
    port.link_closed.set()
    port.write_blocks.set()                               # the driver lets the write go
    assert wait_for(lambda: not link._thread.is_alive())
    time.sleep(0.1)
    assert port.writes_after_close == 0


def test_close_sends_what_is_pending_then_stops():
    port = FakePort()
    link = RobotLink("fake", heartbeat_s=10.0, serial_factory=lambda *a: port)
    assert link.wait_first_attempt(10.0).connected
    link.send_result(make_result(7))
    link.close()
    assert not link._thread.is_alive() or wait_for(lambda: not link._thread.is_alive())
    tracks = [m for m in StreamDecoder().feed(b"".join(port.writes)) if isinstance(m, TrackMessage)]
    assert [m.frame_index for m in tracks] == [7]


def test_send_result_of_anything_but_a_track_result_is_a_type_error():
    link = RobotLink("fake", heartbeat_s=10.0, serial_factory=lambda *a: FakePort())
    try:
        for wrong in (None, 3, "result"):
            with pytest.raises(TypeError, match="send_result takes a TrackResult"):
                link.send_result(wrong)
        assert link.status().errors == 0
    finally:
        link.close()


@pytest.mark.parametrize("baud", [0, -9600, 9600.5, True])
def test_invalid_baud_rates_are_refused(baud):
    with pytest.raises(ValueError, match="baud"):
        RobotLink("loop://", baud)


def test_track_says_at_once_that_the_robot_port_cannot_be_opened(tmp_path, capsys):
    from badminton_gui.cli import main
    from .test_safe_write import _pair
    _pair(tmp_path)
    args = ["track", "--left", str(tmp_path / "l.avi"), "--right", str(tmp_path / "r.avi"),
            "--calib", str(tmp_path / "rig.yaml"), "-o", str(tmp_path / "t.csv"), "--quiet",
            "--robot", str(tmp_path / "no-such-port")]
    assert main(args) == 0
    err = capsys.readouterr().err.splitlines()
    # Said even with --quiet: the robot was asked for and gets nothing.
    assert f"robot link: cannot open {tmp_path / 'no-such-port'}: " in err[0]
    assert "tracking anyway" in err[0]
    assert f"robot link: nothing was sent to {tmp_path / 'no-such-port'}" in err[-1]
    assert len((tmp_path / "t.csv").read_text().splitlines()) == 1 + 5
    assert main(args + ["--robot-required", "-o", str(tmp_path / "t2.csv")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cannot open" in err and "--robot-required" in err
    assert not (tmp_path / "t2.csv").exists()


@pytest.mark.parametrize("argv", [["robot-listen", "loop://", "--timeout", "nan"],
                                  ["robot-listen", "loop://", "--timeout", "inf"],
                                  ["robot-listen", "loop://", "--timeout", "-1"],
                                  ["robot-listen", "loop://", "--count", "-1"],
                                  ["robot-listen", "loop://", "--baud", "0"],
                                  ["track", "--left", "l", "--right", "r", "--calib", "c", "-o", "o",
                                   "--robot", "/dev/null", "--baud", "0"]])
def test_bad_robot_options_are_refused_when_parsed(argv, capsys):
    from badminton_gui.cli import main
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    assert "Traceback" not in capsys.readouterr().err


class VanishingPort(FakePort):
    """Writes ``good_writes`` frames, then fails as an unplugged adapter does."""

    def __init__(self, good_writes: int) -> None:
        super().__init__()
        self.good_writes = good_writes

    def write(self, data):
        if len(self.writes) >= self.good_writes:
            raise OSError(5, "Input/output error")
        return super().write(data)


def test_a_lost_link_is_counted_timed_and_logged_and_its_return_too(caplog):
    ports = [VanishingPort(good_writes=1), FakePort()]
    opened = threading.Event()

    def factory(port, baud, write_timeout):
        if len(ports) == 1:
            opened.wait(30)              # the device stays away until the test brings it back
        return ports.pop(0)

    caplog.set_level("WARNING", logger="badminton_gui.io.robot_link")
    link = RobotLink("/dev/robot", heartbeat_s=0.05, serial_factory=factory)
    link.RETRY_MIN_S = link.RETRY_MAX_S = 0.01
    try:
        assert wait_for(lambda: link.status().outages == 1)
        time.sleep(0.2)
        down = link.status()
        assert not down.connected and down.seconds_down >= 0.2     # an outage going on counts up
        opened.set()
        assert wait_for(lambda: link.status().connected)
        back = link.status()
        assert back.outages == 1 and back.reconnects == 1
        assert back.seconds_down >= down.seconds_down
        time.sleep(0.1)
        assert link.status().seconds_down == back.seconds_down     # finished: no longer counting
    finally:
        link.close()
    said = [r.getMessage() for r in caplog.records]
    assert any(m.startswith("robot link: lost (write to /dev/robot:") for m in said), said
    assert any("/dev/robot back after" in m for m in said), said


def test_closing_the_link_is_not_an_outage():
    link = RobotLink("fake", heartbeat_s=0.05, serial_factory=lambda *a: FakePort())
    try:
        assert wait_for(lambda: link.status().heartbeats_sent >= 2)
    finally:
        link.close()
    assert link.status().outages == 0 and link.status().seconds_down == 0.0


def test_track_with_the_robot_required_fails_when_the_link_was_lost_on_the_way(tmp_path, capsys,
                                                                                monkeypatch):
    """The output is still written in full; the exit status and one line say the robot went
    without results (without --robot-required: said, exit 0)."""
    import badminton_gui.io.robot_link as robot_link
    from badminton_gui.cli import main
    from .test_safe_write import _pair

    class LinkToAVanishingRobot(robot_link.RobotLink):
        def __init__(self, port, baud):
            ports = [VanishingPort(good_writes=1)]     # opens, one heartbeat, then writes fail
            super().__init__(port, baud, heartbeat_s=0.05,
                             serial_factory=lambda *a: ports.pop() if ports else _refuse())

    def _refuse():
        raise OSError(2, "No such file or directory")

    monkeypatch.setattr(robot_link, "RobotLink", LinkToAVanishingRobot)
    _pair(tmp_path)
    args = ["track", "--left", str(tmp_path / "l.avi"), "--right", str(tmp_path / "r.avi"),
            "--calib", str(tmp_path / "rig.yaml"), "--quiet", "--robot", "/dev/robot"]
    assert main(args + ["-o", str(tmp_path / "t.csv")]) == 0
    assert "robot link: lost once during the run" in capsys.readouterr().err
    assert main(args + ["-o", str(tmp_path / "t2.csv"), "--robot-required"]) == 2
    err = capsys.readouterr().err
    assert "robot link: lost once during the run" in err and "(--robot-required)" in err
    assert len((tmp_path / "t2.csv").read_text().splitlines()) == 1 + 5
