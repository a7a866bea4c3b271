"""`rotor-bridge emulate MODEL`: serve an emulated controller on a pty until told to stop.

What this is: the command-line face of the emulator registry, for the demo and for trying a
client by hand (`rotctl -m 401 -r "$(first line)" -s 4800 p`). bridge/cli.py wires it in as a
subcommand with add_arguments() and run(); `python -m bridge.emulators MODEL` runs it alone.

Rules:
1. stdout carries exactly the device path, then the link if one was asked for, one per line,
   flushed at once, so a script can read them; everything else goes to stderr.
2. SIGINT and SIGTERM end it cleanly (link removed, pty closed) with exit status 0, also when a
   second one comes while it ends.
"""

from __future__ import annotations

import argparse
import signal
import sys
from collections.abc import Sequence
from typing import Any

from bridge.emulators import EMULATORS, LoggedFrame, as_built, start


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", choices=sorted(EMULATORS), help="controller to emulate")
    parser.add_argument(
        "--link", metavar="PATH", help="also serve the device at PATH (a symlink, atomically set)"
    )
    parser.add_argument("--baud", type=int, help="line rate that paces replies (model default)")
    parser.add_argument(
        "--speed-deg-s", type=float, help="(azimuth) speed in deg/s (model default)"
    )
    parser.add_argument("--el-speed-deg-s", type=float, help="elevation speed (az/el models)")
    parser.add_argument("--start-az-deg", type=float, help="initial bearing (deg)")
    parser.add_argument("--start-el-deg", type=float, help="initial elevation (az/el models)")
    parser.add_argument(
        "--brake-delay-s",
        type=float,
        help="brake delay after motion (Rotor-EZ family; default 5 s Rotor-EZ/DCU-1, 0 RotorCard)",
    )
    parser.add_argument(
        "--jitter-deg", type=int, help="stationary reading noise (Rotor-EZ family; default 1)"
    )
    parser.add_argument("--firmware", help="controller version in its banner (Rotor-EZ family)")
    parser.add_argument(
        "--no-power-on-junk", action="store_true", help="no 0xE0 power-on byte (Rotor-EZ family)"
    )
    parser.add_argument(
        "--resolution", type=int, help="pulses per degree (SPID: 1, 2, 4; MD-01 also 10)"
    )
    parser.add_argument(
        "--coast-deg",
        type=float,
        help="how far a stopped rotor runs on, decelerating (SPID family; default 0: stops dead)",
    )
    parser.add_argument(
        "--blank-lines-after-w",
        type=int,
        help="blank lines after the answer to W, as K3NG's firmware sends (GS-232 family)",
    )
    parser.add_argument(
        "--decimals",
        type=int,
        help="decimals in a position answer, 1 or 0 for whole degrees (Easycomm family)",
    )
    parser.add_argument(
        "--firmware-version", help="the answer to VE, without the letters (Easycomm family)"
    )
    parser.add_argument(
        "--easycomm-firmware",
        choices=("generic", "satnogs", "k3ng"),
        help="whose reading of Easycomm the box has: SatNOGS's (a bare AZ turns to 0) or K3NG's "
        "(answers +123.4) (Easycomm family; default generic)",
    )
    parser.add_argument(
        "--reply-padding",
        choices=("none", "space", "zero"),
        help="the bearing's padding (RT-21): space ' 5.0;' (default), none '5.0;', zero '005.0;'",
    )
    parser.add_argument(
        "--echo", action="store_true", help="echo every command before answering (RC2800)"
    )
    parser.add_argument(
        "--stream-s",
        type=float,
        help="send the position unasked after this many quiet seconds (RC2800)",
    )
    parser.add_argument(
        "--streaming",
        action="store_true",
        help="send the position unasked until told STX u S CR, as some boxes do (Prosistel)",
    )
    parser.add_argument(
        "--soft-stop-s",
        type=float,
        help="how long the rotor runs on after a soft stop, its PWM ramp (Prosistel; default 0)",
    )
    parser.add_argument(
        "--log-frames", action="store_true", help="print every received frame on stderr"
    )


_ROTOREZ_FAMILY = {"rotorez", "rotorcard", "dcu1"}
_SPID_FAMILY = {"rot2prog", "rot1prog", "md01"}


def _controller_options(args: argparse.Namespace) -> dict[str, Any]:
    """The options this model's emulator takes, from the ones given (the rest stay default)."""
    opts: dict[str, Any] = {
        "baud": args.baud,
        "start_az_deg": args.start_az_deg,
        **as_built(args.model),  # (rule 3 of bridge/emulators: its rotor as built)
    }
    if args.model in _ROTOREZ_FAMILY:
        opts.update(
            speed_deg_s=args.speed_deg_s,
            brake_delay_s=args.brake_delay_s,
            jitter_deg=args.jitter_deg,
            version=args.firmware,
            power_on_junk=False if args.no_power_on_junk else None,
        )
    elif args.model in _SPID_FAMILY:
        opts.update(
            az_speed_deg_s=args.speed_deg_s,
            el_speed_deg_s=args.el_speed_deg_s,
            start_el_deg=args.start_el_deg,
            resolution_ppd=args.resolution,
            coast_deg=args.coast_deg,
        )
    elif args.model == "rt21":  # one box, one rotor: no elevation options
        opts.update(az_speed_deg_s=args.speed_deg_s, reply_padding=args.reply_padding)
    else:
        opts.update(
            az_speed_deg_s=args.speed_deg_s,
            el_speed_deg_s=args.el_speed_deg_s,
            start_el_deg=args.start_el_deg,
        )
        if args.model.startswith("gs232"):
            opts.update(blank_lines_after_w=args.blank_lines_after_w)
        if args.model.startswith("easycomm"):
            opts.update(
                decimals=args.decimals,
                version=args.firmware_version,
                firmware=args.easycomm_firmware,
            )
        if args.model.startswith("rc2800"):
            opts.update(echo=args.echo or None, stream_s=args.stream_s)
        if args.model.startswith("prosistel"):
            opts.update(streaming=args.streaming or None, soft_stop_s=args.soft_stop_s)
    return {k: v for k, v in opts.items() if v is not None}


def _print_frame(frame: LoggedFrame) -> None:
    print(f"{frame.time_s:.3f} {frame.data!r} -> {frame.outcome}", file=sys.stderr, flush=True)


def run(args: argparse.Namespace) -> int:
    # rule 2: no handler, the signals taken by sigwait (a handler that set an Event could land
    # inside that Event's wait on this thread, holding its lock, and wait on it for ever);
    # blocked before the emulator's thread starts, so that it blocks them too
    signals = {signal.SIGINT, signal.SIGTERM}
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, signals)
    try:
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
        try:
            print(port.path, flush=True)
            if port.link is not None:
                print(port.link, flush=True)
            signal.sigwait(signals)
        finally:
            port.close()
        for _ in signal.sigpending() & signals:  # a second one meanwhile ends nothing more
            signal.sigwait(signals)
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="rotor-bridge emulate", description="Serve an emulated rotator controller on a pty."
    )
    add_arguments(parser)
    return run(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
