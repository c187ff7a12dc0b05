"""``badminton-track robot-listen PORT``: the robot's end of the link, for testing it.

Why this file exists: a robot team needs to see what the tracker sends before their own parser
works. This opens a serial port (or Bluetooth serial port, or a pyserial URL such as
``socket://host:port``), decodes the stream with the same :class:`StreamDecoder` the protocol
document describes, and prints one message per line. When the port goes away it waits for
it and reopens it (as the robot's own reader should), so a link test survives a Bluetooth drop.
"""

from __future__ import annotations

import sys
import time

from .common import UserError, baud_rate, count_or_zero, seconds_or_zero

RETRY_S = 0.5      # s between attempts to reopen a port that went away


def register(sub) -> None:
    p = sub.add_parser(
        "robot-listen",
        help="decode and print the robot-link messages arriving on a serial port",
        description="Open PORT (COM5, /dev/ttyUSB0, /dev/rfcomm0, socket://host:port, ...) and "
                    "print every decoded robot-link message, one per line. "
                    "The format is in docs/robot-protocol.md.")
    p.add_argument("port", metavar="PORT", help="serial port name or pyserial URL")
    p.add_argument("--baud", type=baud_rate, default=115200, help="baud rate (default 115200)")
    p.add_argument("--count", type=count_or_zero, default=0, metavar="N",
                   help="stop after N messages (default: no limit)")
    p.add_argument("--timeout", type=seconds_or_zero, default=0.0, metavar="S",
                   help="stop after S seconds (default: no limit); exit status 1 if nothing was decoded")
    p.add_argument("--no-heartbeat", action="store_true", help="do not print heartbeat messages")
    p.set_defaults(func=run)


def run(args) -> int:
    import serial

    from ..io.robot_link import HeartbeatMessage, StreamDecoder

    try:
        port = serial.serial_for_url(args.port, baudrate=args.baud, timeout=0.05)
    except (serial.SerialException, OSError, ValueError) as exc:
        raise UserError(f"cannot open {args.port}: {exc}") from None

    decoder = StreamDecoder()
    received = 0
    deadline = time.monotonic() + args.timeout if args.timeout > 0 else None
    try:
        while deadline is None or time.monotonic() < deadline:
            if port is None:
                # The device went away (Bluetooth out of range, adapter unplugged, the other end of
                # a pseudo-terminal closed): wait for it like the robot would, then carry on.
                time.sleep(RETRY_S)
                try:
                    port = serial.serial_for_url(args.port, baudrate=args.baud, timeout=0.05)
                    print(f"robot-listen: {args.port} is back", file=sys.stderr, flush=True)
                except (serial.SerialException, OSError, ValueError):
                    continue
            try:
                data = port.read(4096)
            except (serial.SerialException, OSError) as exc:
                print(f"robot-listen: reading {args.port}: {exc}; reopening", file=sys.stderr, flush=True)
                _close(port)
                port = None
                continue
            for message in decoder.feed(data):
                received += 1
                if not (args.no_heartbeat and isinstance(message, HeartbeatMessage)):
                    print(message.describe(), flush=True)
                if args.count and received >= args.count:
                    return 0
    finally:
        if port is not None:
            _close(port)
        print(f"robot-listen: {received} messages, {decoder.crc_errors} CRC errors, "
              f"{decoder.bytes_skipped} bytes skipped", file=sys.stderr)
    return 0 if received else 1


def _close(port) -> None:
    try:
        port.close()
    except Exception:  # noqa: BLE001 - closing a vanished device may fail; nothing to do about it
        pass
