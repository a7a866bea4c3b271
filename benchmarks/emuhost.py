"""A helper process hosting many emulated controllers (each behind a paced line), so that a
process under test (the bridge, rotctld) shares no CPU time or memory accounting with them.

    python -m benchmarks.emuhost --model rotorez --count 32 --dir DIR

Links DIR/tty-0 .. DIR/tty-<count-1>. stdout: one line "ready" once every link exists, then one
line per command answered. stdin, one command per line:
    rotate AZ     every rotor turns towards AZ from its front panel (no serial command)
    state         a JSON list [[az_deg, is_moving], ...]
    quit          close everything and exit (so does end of input)
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from benchmarks.line import PacedRelay
from benchmarks.rig import baud_of
from bridge import emulators


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.emuhost")
    ap.add_argument("--model", required=True)
    ap.add_argument("--count", type=int, required=True)
    ap.add_argument("--dir", type=Path, required=True)
    ap.add_argument("--unpaced", action="store_true", help="no line pacing towards the controller")
    args = ap.parse_args(argv)
    args.dir.mkdir(parents=True, exist_ok=True)
    ports = []
    relays = []
    try:
        for i in range(args.count):
            emu_link = args.dir / f"emu-{i}"
            port = emulators.start(args.model, link=str(emu_link))
            ports.append(port)
            if args.unpaced:
                (args.dir / f"tty-{i}").symlink_to(port.path)
            else:
                relays.append(PacedRelay(port.path, args.dir / f"tty-{i}", baud_of(args.model)))
        print("ready", flush=True)
        for line in sys.stdin:
            words = line.split()
            if not words:
                continue
            if words[0] == "quit":
                break
            if words[0] == "rotate":
                az = float(words[1])
                for port in ports:
                    port.manual_rotate(az)
                print("ok", flush=True)
            elif words[0] == "state":
                states = [port.state() for port in ports]
                print(json.dumps([[s.az_deg, s.is_moving] for s in states]), flush=True)
            else:
                print(f"error unknown command {words[0]!r}", flush=True)
    finally:
        for relay in relays:
            relay.close()
        for port in ports:
            port.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
