"""Fuzz of the robot's stream decoder (io/robot_link.py ``StreamDecoder``), seeded so every run is
the same: thousands of streams of mutated, truncated and concatenated frames between random
garbage, fed in random chunks. The decoder must never raise, must decode every intact frame in
order whatever came before it, and must never hold more than one frame's worth of bytes (which
bounds the work a case can cost, without timing anything).
"""

from __future__ import annotations

import math
import struct

import numpy as np
import pytest

from badminton_gui.io.robot_link import (
    CRC_SIZE, HEADER_SIZE, MAX_PAYLOAD, MSG_HEARTBEAT, MSG_TRACK, SYNC, HeartbeatMessage,
    StreamDecoder, TrackMessage, UnknownMessage, encode_frame, encode_heartbeat)

LONGEST_FRAME = HEADER_SIZE + MAX_PAYLOAD + CRC_SIZE
STREAM_CASES = 3000
NOISE_CASES = 2000


def _random_frame(rng: np.random.Generator, seq: int) -> bytes:
    kind = rng.integers(0, 4)
    t = float(rng.uniform(-1e6, 1e6))
    if kind == 0:
        return encode_heartbeat(seq, t, *(int(v) for v in rng.integers(0, 1 << 32, 3)))
    if kind == 1:   # a TRACK payload of random bytes: any float, NaN and infinities included
        return encode_frame(MSG_TRACK, seq, t, rng.integers(0, 256, 54, dtype=np.uint8).tobytes())
    if kind == 2:   # an unknown type or version, of any allowed length
        payload = rng.integers(0, 256, int(rng.integers(0, MAX_PAYLOAD + 1)), dtype=np.uint8).tobytes()
        return encode_frame(int(rng.integers(3, 256)), seq, t, payload, version=int(rng.integers(1, 256)))
    # A longer version-1 payload (fields appended by a later tracker).
    return encode_frame(MSG_HEARTBEAT, seq, t, rng.integers(0, 256, int(rng.integers(13, 80)),
                                                            dtype=np.uint8).tobytes())


def _garbage(rng: np.random.Generator, seq: int) -> bytes:
    """Bytes that are not a frame: noise, noise full of sync bytes and plausible headers, a
    truncated frame, or a frame with bytes changed, inserted or deleted."""
    kind = rng.integers(0, 6)
    if kind == 0:
        return rng.integers(0, 256, int(rng.integers(0, 120)), dtype=np.uint8).tobytes()
    if kind == 1:      # headers claiming any length, the protocol's maximum and beyond included
        out = bytearray()
        for _ in range(int(rng.integers(1, 4))):
            length = int(rng.choice([rng.integers(0, 1 << 16), MAX_PAYLOAD, MAX_PAYLOAD + 1,
                                     rng.integers(0, 64)]))
            out += SYNC + struct.pack("<BBHId", 1, int(rng.integers(0, 4)), length, seq, 0.0)
            out += rng.integers(0, 256, int(rng.integers(0, 40)), dtype=np.uint8).tobytes()
        return bytes(out)
    frame = bytearray(_random_frame(rng, seq))
    if kind == 2:      # cut short (a lost tail)
        return bytes(frame[:int(rng.integers(1, len(frame)))])
    if kind == 3:      # bytes flipped (never into the same value)
        for at in rng.choice(len(frame), size=int(rng.integers(1, 4)), replace=False):
            frame[at] ^= int(rng.integers(1, 256))
        return bytes(frame)
    if kind == 4:      # a byte lost from the middle
        at = int(rng.integers(2, len(frame)))
        return bytes(frame[:at] + frame[at + 1:])
    at = int(rng.integers(2, len(frame)))      # a byte too many
    return bytes(frame[:at] + bytes([int(rng.integers(0, 256))]) + frame[at:])


def _feed_in_chunks(decoder: StreamDecoder, data: bytes, rng: np.random.Generator) -> list:
    out, at = [], 0
    while at < len(data):
        size = int(rng.choice([1, rng.integers(1, 16), rng.integers(1, 300)]))
        out += decoder.feed(data[at:at + size])
        at += size
        # One frame's worth at most: the work per byte fed is bounded.
        assert len(decoder._buf) < LONGEST_FRAME
    return out


def _same(message, frame: bytes) -> bool:
    """``message`` is what ``frame`` says (header and payload)."""
    version, msg_type, length, seq, t = struct.unpack_from("<BBHId", frame, len(SYNC))
    if (message.version, message.msg_type, message.seq) != (version, msg_type, seq):
        return False
    if not (message.timestamp == t or (math.isnan(message.timestamp) and math.isnan(t))):
        return False
    payload = frame[HEADER_SIZE:HEADER_SIZE + length]
    if isinstance(message, UnknownMessage):
        return message.payload == payload
    return isinstance(message, (TrackMessage, HeartbeatMessage))


def test_every_intact_frame_after_any_garbage_is_decoded_in_order():
    rng = np.random.default_rng(20261127)
    frames_checked = 0
    for case in range(STREAM_CASES):
        stream = bytearray()
        intact = []
        for i in range(int(rng.integers(1, 7))):
            if rng.random() < 0.7:
                stream += _garbage(rng, 10_000 + i)
            frame = _random_frame(rng, i)
            intact.append(frame)
            stream += frame
        decoded = _feed_in_chunks(StreamDecoder(), bytes(stream), rng)
        # Garbage may hold frames of its own only by CRC coincidence; the intact ones all come
        # out, in order, with nothing between them that is not garbage-born.
        ours = [m for m in decoded if m.seq < 10_000]
        assert len(ours) == len(intact), (case, len(ours), len(intact))
        assert all(_same(m, f) for m, f in zip(ours, intact)), case
        frames_checked += len(intact)
    assert frames_checked > 2 * STREAM_CASES


@pytest.mark.parametrize("sync_share", [0.0, 0.05, 0.3])
def test_noise_never_raises_and_never_piles_up(sync_share):
    """Random bytes, more or less full of sync bytes, in random chunks; then a frame still gets
    through."""
    rng = np.random.default_rng([7, int(sync_share * 100)])
    for case in range(NOISE_CASES // 3 + 1):
        n = int(rng.integers(0, 2000))
        noise = rng.integers(0, 256, n, dtype=np.uint8)
        syncs = np.flatnonzero(rng.random(n) < sync_share / 2)
        noise[syncs] = SYNC[0]
        noise[np.minimum(syncs + 1, max(n - 1, 0))] = SYNC[1]
        decoder = StreamDecoder()
        _feed_in_chunks(decoder, noise.tobytes(), rng)
        tail = encode_heartbeat(77, 1.5, 1, 2, 3)
        # A false start at the end of the noise may claim up to a full frame of what follows:
        # a whole frame after it (the next one, at the latest) comes out.
        out = _feed_in_chunks(decoder, tail + tail, rng)
        assert [m.seq for m in out if isinstance(m, HeartbeatMessage) and m.seq == 77], case
