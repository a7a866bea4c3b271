"""`rotor-bridge emulate MODEL`: serve an emulated controller on a pty until told to stop.

What this is: the command-line face of the emulator registry, for the demo and for trying a
client by hand (`rotctl -m 401 -r "$(first line)" -s 4800 p`). bridge/cli.py wires it in as a
subcommand with add_arguments() and run(); `python -m bridge.emulators MODEL` runs it alone.

Rules:
1. stdout carries exactly the device path, then the link if one was asked for, one per line,
   flushed at once, so a script can read them; everything else goes to stderr.
2. SIGINT and SIGTERM end it cleanly (link removed, pty closed) with exit status 0.
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading
from collections.abc import Sequence
from types import FrameType
from typing import Any

from bridge.emulators import EMULATORS, LoggedFrame, start


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", choices=sorted(EMULATORS), help="controller to emulate")
    parser.add_argument(
        "--link", metavar="PATH", help="also serve the device at PATH (a symlink, atomically set)"
    )
    parser.add_argument("--baud", type=int, default=4800, help="line rate that paces replies")
    parser.add_argument("--speed-deg-s", type=float, default=6.0, help="rotor speed (deg/s)")
    parser.add_argument("--start-az-deg", type=float, default=0.0, help="initial bearing (deg)")
    parser.add_argument(
        "--brake-delay-s",
        type=float,
        default=None,
        help="brake delay after motion (default: model's, 5 s Rotor-EZ/DCU-1, 0 RotorCard)",
    )
    parser.add_argument(
        "--jitter-deg", type=int, default=1, help="stationary reading noise (deg), 0 disables"
    )
    parser.add_argument("--firmware", default="1.4S", help="controller version in its banner")
    parser.add_argument(
        "--no-power-on-junk", action="store_true", help="do not emit the 0xE0 power-on byte"
    )
    parser.add_argument(
        "--log-frames", action="store_true", help="print every received frame on stderr"
    )


def _controller_options(args: argparse.Namespace) -> dict[str, Any]:
    return {
        "baud": args.baud,
        "speed_deg_s": args.speed_deg_s,
        "start_az_deg": args.start_az_deg,
        "brake_delay_s": args.brake_delay_s,
        "jitter_deg": args.jitter_deg,
        "version": args.firmware,
        "power_on_junk": not args.no_power_on_junk,
    }


def _print_frame(frame: LoggedFrame) -> None:
    print(f"{frame.time_s:.3f} {frame.data!r} -> {frame.outcome}", file=sys.stderr, flush=True)


def run(args: argparse.Namespace) -> int:
    stop = threading.Event()

    def on_signal(_signum: int, _frame: FrameType | None) -> None:
        stop.set()

    try:
        port = start(
            args.model,
            link=args.link,
            on_frame=_print_frame if args.log_frames else None,
            **_controller_options(args),
        )
    except (ValueError, OSError) as exc:
        print(f"emulate: {exc}", file=sys.stderr)
        return 2
    previous = {sig: signal.signal(sig, on_signal) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        print(port.path, flush=True)
        if port.link is not None:
            print(port.link, flush=True)
        while not stop.wait(3600.0):
            pass
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        port.close()
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="rotor-bridge emulate", description="Serve an emulated rotator controller on a pty."
    )
    add_arguments(parser)
    return run(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
